#include "bench/io/coefficients_json.hpp"

#include "bench/io/json_util.hpp"

namespace calbench {

CoefficientSet read_coefficients(const std::filesystem::path& file) {
  return coefficients_from_json(read_json_file(file), file.string());
}

void write_coefficients(const std::filesystem::path& file, const CoefficientSet& c) {
  write_text_atomic(file, coefficients_to_json(c).dump(2) + "\n");
}

}  // namespace calbench
