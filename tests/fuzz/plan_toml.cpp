// Harness: bench plan files (bench/io/plan_toml.*, with the text check of bench/io/toml_text.*
// before toml++ sees the text). Input: the file.
#include <cstdint>

#include "common/input_error.hpp"
#include "bench/io/plan_toml.hpp"
#include "tests/fuzz/fuzz_util.hpp"

using namespace calbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fuzz::FdCheck fds;
  const auto file = fuzz::scratch() / "plan.toml";
  fuzz::write_file(file, std::string_view(reinterpret_cast<const char*>(data), size));
  try {
    load_plan(file);
  } catch (const InputError&) {
  }
  fds.verify();
  return 0;
}
