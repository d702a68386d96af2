// What the harnesses of the multipos importers (imutk, csvimport) check around one import: besides
// crashes and exceptions other than InputError, two findings (abort): a refused import that leaves
// anything in the output folder's place, and an import that succeeds but writes a recording
// calbench's own reader refuses. What is imported is also fitted (`fit_multipos`; its refusal is fine).
#pragma once
#include <string>

#include "bench/io/recording.hpp"
#include "bench/multipos/fit_multipos_run.hpp"
#include "common/input_error.hpp"
#include "tests/fuzz/fuzz_util.hpp"

namespace calbench::fuzz {

// import() writes the recording dir/out (or throws InputError).
template <class Import>
void check_multipos_import(const char* harness, const fs::path& dir, Import import) {
  try {
    import();
  } catch (const InputError& e) {
    check_refused_import_left_nothing(dir, "out", harness, e.what());
    return;
  }
  try {  // what the import wrote, read back and fitted (a refusal is an InputError too)
    const MultiposRecording rec = read_multipos_recording(dir / "out", "");
    try {
      multipos::fit_multipos(rec.input, multipos::MultiposOptions{});
    } catch (const multipos::MultiposRefusal&) {
    }
  } catch (const InputError& e) {
    finding(harness, "the imported recording is refused by calbench's reader", e.what());
  }
}

}  // namespace calbench::fuzz
