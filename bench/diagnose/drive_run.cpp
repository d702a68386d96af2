#include "bench/diagnose/drive_run.hpp"

#include <ctime>

#include "bench/diagnose/diagnose_run.hpp"
#include "bench/diagnose/diagnose_text.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "bench/drive/fit_drive.hpp"
#include "bench/io/json_util.hpp"
#include "calibration/ins/strapdown.hpp"
#include "common/units.hpp"

// `calbench diagnose` on a drive recording: the diagnosis, IMPROVED.json with the mounting, and
// the in-motion filter's innovations before and after. Loading: diagnose_load.cpp; output:
// diagnose_json.cpp, diagnose_text.cpp, diagnose_html.cpp.

namespace calbench {

InnovationSample innovation_sample(const inmotion::InnovationRecord& r) {
  return {r.t, r.nu, r.S, r.nis, static_cast<int>(r.status), r.speed, r.turn_rate, r.accel};
}

DriveInnovations drive_innovations(const DriveDiagInput& in, const DriveDiagRun& run) {
  DriveInnovations out;
  const std::clock_t c0 = std::clock();
  auto filter_run = [&](const CoefficientSet& set, InnovationStats (&stats)[3], std::vector<std::string>& applied) {
    std::vector<InnovationSample> x[3];
    FitDriveArgs a;
    a.dir = in.dir.string();
    a.coeffs_set = set;
    a.device_class = in.device_class;
    a.qc = false;
    a.write_out = false;
    a.on_innovation = [&](int type, const inmotion::InnovationRecord& r) {
      x[type].push_back(innovation_sample(r));
    };
    const DriveResult r = fit_drive(a);
    if (r.effects) applied.insert(applied.end(), r.effects->applied.begin(), r.effects->applied.end());  // the terms applied
    for (int k = 0; k < 3; ++k) stats[k] = innovation_stats(x[k], &in.data);
  };
  // "before": the improved b and M with only the terms that were tested (those the given
  // coefficients carried); "after": IMPROVED.json. The difference is the new terms alone.
  CoefficientSet before = run.improved;
  before.extra = run.current.extra;
  filter_run(before, out.before, out.applied_before);
  out.compared = !run.result.core.findings.empty();
  if (out.compared) filter_run(run.improved, out.after, out.applied_after);
  else {
    for (int k = 0; k < 3; ++k) out.after[k] = out.before[k];
    out.applied_after = out.applied_before;
  }
  out.cpu_s = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  return out;
}

DriveDiagRun run_drive_diagnosis(const DriveDiagInput& in, const DriveCoeffs* coeffs, bool innovations) {
  DriveDiagRun run;
  DriveDiagnoseOptions opt;
  run.noise_class = diagnosis_noise_class(in.device_class, in.meta.device.model, in.dir / "meta.json", opt.noise);
  EffectTerms carried;
  if (coeffs) {
    run.current = coeffs->set;
    carried = coeffs->carried;
    run.coeffs_given = true;
    opt.fixed_scale = true;
  } else {
    run.current.device = in.meta.device;
  }
  run.result = diagnose_drive(in.data, run.current.errors, carried, opt);
  const DiagnoseResult& r = run.result.core;
  run.improved = run.current;
  run.improved.device = run.current.device.serial.empty() ? in.meta.device : run.current.device;
  run.improved.errors = r.improved;
  nlohmann::json added = nlohmann::json::array();
  for (const auto& f : r.findings) added.push_back(f.term.label());
  nlohmann::json dj = {{"effects_added", added}, {"recording_kind", "drive"},
                       {"note", "b (and M without --coeffs) re-estimated on this drive; the bias of a drive is its "
                                "turn-on and in-run value"}};
  if (run.coeffs_given) {
    const Mat3 C = ins::dcm_from_rpy(in.mounting_rpy_deg * units::kDeg) *
                   ins::quat_from_rotvec(run.result.mounting_delta).toRotationMatrix();
    dj["mounting_rpy_deg"] = {{"value", to_json(Vec3(ins::rpy_from_dcm(C) / units::kDeg))},
                              {"sigma", to_json(Vec3(run.result.mounting_sigma / units::kDeg))},
                              {"tested", to_json(in.mounting_rpy_deg)}};
  }
  diagnose_out::improved_extra(run.improved.extra, r, dj);
  if (in.dir.empty()) return run;
  if (!innovations) run.innovations_skipped = "skipped (--no-innovations)";
  else {
    // The diagnosis stands without them: a filter run that fails is reported, not fatal.
    try {
      run.innovations = drive_innovations(in, run);
    } catch (const std::exception& e) {
      run.innovations_skipped = std::string("not run: the in-motion filter failed: ") + e.what();
    }
  }
  return run;
}

}  // namespace calbench
