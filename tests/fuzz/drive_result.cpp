// Harness: the one RESULT.json codec (common/drive_result.cpp), which `fit drive --coeffs`,
// `qc --coeffs`, `diagnose --coeffs`, `db import-inmotion` and the device report read through.
// Input: the file's text. A result the codec reads is written back and read again: the writer's
// output (of a result with its recording's URI and digest) must be accepted by its own reader and read to the same typed parts (a finding otherwise).
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <string>

#include "common/drive_result.hpp"
#include "common/input_error.hpp"
#include "common/json_parse.hpp"
#include "tests/fuzz/fuzz_util.hpp"

using namespace calbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)fuzz::scratch();  // silences the parsers' warnings
  const std::string text(reinterpret_cast<const char*>(data), size);
  DriveResult r;
  try {
    r = drive_result_from_json(parse_json_text(text, "RESULT.json"), "RESULT.json");
  } catch (const InputError&) {
    return 0;
  }
  // An older result without its recording's URI and digest reads, but is never written (the writer
  // requires them): nothing to write back.
  if (!r.recording.uri || !r.recording.digest) return 0;
  const nlohmann::json out = drive_result_to_json(r);
  DriveResult again;
  try {
    again = drive_result_from_json(parse_json_text(out.dump(2), "written.json"), "written.json");
  } catch (const InputError& e) {
    std::fprintf(stderr, "the codec refused what it wrote: %s\n", e.what());
    std::abort();
  }
  if (drive_result_to_json(again) != out) {
    std::fprintf(stderr, "a second read/write changed the result\n");
    std::abort();
  }
  return 0;
}
