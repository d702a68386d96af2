// coefficients.json files. The schema (read strictly, unknown keys kept in `extra`) is the one
// codec in common/coefficients_codec.hpp, which the store uses as well; this adds the file I/O.
#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>

#include "common/coefficients_codec.hpp"

namespace calbench {

CoefficientSet read_coefficients(const std::filesystem::path& file);
void write_coefficients(const std::filesystem::path& file, const CoefficientSet& c);  // atomic

}  // namespace calbench
