// Harness: device-class files (bench/io/imu_class_toml.*: `fit drive --device-class`, `simulate
// drive --device-class`, bench/imu_classes/*.toml). Input: the file.
#include <cstdint>

#include "bench/io/imu_class_toml.hpp"
#include "common/input_error.hpp"
#include "tests/fuzz/fuzz_util.hpp"

using namespace calbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::FdCheck fds;
  const auto file = fuzz::scratch() / "class.toml";
  fuzz::write_file(file, std::string_view(reinterpret_cast<const char*>(data), size));
  try {
    load_imu_class(file);
  } catch (const InputError&) {
  }
  fds.verify();
  return 0;
}
