// Harness: the JSON inputs of the coefficient store (db/): a coefficients.json for
// `db store-bench` (db/coefficients_payload.cpp), an in-motion RESULT.json for
// `db import-inmotion` (db/inmotion_import.cpp, with its "determined_by"), and the approval
// thresholds of `report --thresholds` (db/approval.cpp). Input: the file's text, given to each.
#include <cstdint>
#include <string>

#include "common/input_error.hpp"
#include "db/approval.hpp"
#include "db/inmotion_import.hpp"
#include "db/store.hpp"
#include "tests/fuzz/fuzz_util.hpp"

using namespace calbench;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)fuzz::scratch();  // silences the parsers' warnings
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    db::parse_coefficients(text, "coeffs.json", "");
  } catch (const InputError&) {
  }
  try {
    db::parse_inmotion_result(text, "RESULT.json");
  } catch (const InputError&) {
  }
  try {
    db::parse_determined_by(text, "RESULT.json");
  } catch (const InputError&) {
  }
  try {
    db::parse_thresholds(text, "thresholds.json");
  } catch (const InputError&) {
  }
  return 0;
}
