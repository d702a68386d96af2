// Harness: drive route files (bench/drive/route_toml.*, with the text check of
// bench/io/toml_text.*). Input: the file. A route that is read also draws its random mounting.
#include <cstdint>

#include "bench/drive/route_toml.hpp"
#include "common/input_error.hpp"
#include "tests/fuzz/fuzz_util.hpp"

using namespace calbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::FdCheck fds;
  const auto file = fuzz::scratch() / "route.toml";
  fuzz::write_file(file, std::string_view(reinterpret_cast<const char*>(data), size));
  try {
    const RouteFile rf = load_route(file);
    draw_true_mounting_rpy_deg(rf, 1);
  } catch (const InputError&) {
  }
  fds.verify();
  return 0;
}
