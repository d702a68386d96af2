// Recording-level driver of `calbench diagnose` on a multipos recording (issue 37 item 4,
// docs/diagnosis.md "Multi-position recordings"): the recording read and fitted as `fit multipos`
// does (one function, fit_multipos_set), the coefficients tested (that fit, or --coeffs), the static
// poses' residuals through the catalogue search (calibration/diagnosis/multipos_diagnose.hpp), and
// the result as JSON (the bench side's schema plus "multipos"), text and IMPROVED.json.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "bench/multipos/fit_multipos_run.hpp"
#include "calibration/diagnosis/multipos_diagnose.hpp"

namespace calbench {

struct MultiposDiagRun {
  MultiposSetResult fitted;     // the recording and its fit multipos (statics, noise levels)
  CoefficientSet current;       // what was tested ("before")
  bool fitted_first = true;     // false: --coeffs
  MultiposDiagnoseResult result;
  CoefficientSet improved;      // IMPROVED.json
};

// coeffs_file empty: the fit multipos of this recording is tested. InputError when the recording
// cannot be fitted (which poses to add) or the set is for another unit.
MultiposDiagRun run_multipos_diagnosis(const std::string& dir, const std::string& coeffs_file,
                                       const std::string& device_class);
nlohmann::json multipos_diagnosis_json(const MultiposDiagRun& run);
std::string multipos_diagnosis_text(const MultiposDiagRun& run);

}  // namespace calbench
