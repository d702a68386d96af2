// Harness: multi-unit fixture files (bench/station/fixture.*: slots, IMU URIs, poses). Input: the file.
#include <cstdint>

#include "bench/station/fixture.hpp"
#include "common/input_error.hpp"
#include "tests/fuzz/fuzz_util.hpp"

using namespace calbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::FdCheck fds;
  const auto file = fuzz::scratch() / "fixture.toml";
  fuzz::write_file(file, std::string_view(reinterpret_cast<const char*>(data), size));
  try {
    station::load_fixture(file);
  } catch (const InputError&) {
  }
  fds.verify();
  return 0;
}
