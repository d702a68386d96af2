#include "bench/diagnose/multipos_run.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "bench/diagnose/diagnose_run.hpp"
#include "bench/diagnose/diagnose_text.hpp"
#include "bench/diagnose/finding_text.hpp"
#include "bench/io/coefficients_json.hpp"
#include "bench/io/recording.hpp"
#include "common/input_error.hpp"
#include "common/units.hpp"

namespace calbench {

using namespace diagnose_out;

MultiposDiagRun run_multipos_diagnosis(const std::string& dir, const std::string& coeffs_file,
                                       const std::string& device_class) {
  MultiposDiagRun run;
  FitMultiposArgs fa;
  fa.dir = dir;
  fa.device_class = device_class;
  run.fitted = fit_multipos_set(fa);
  run.current = run.fitted.set;
  if (!coeffs_file.empty()) {
    run.current = read_coefficients(coeffs_file);
    check_same_unit(run.current.device, coeffs_file, dir);
    run.fitted_first = false;
  }
  DiagnoseOptions opt;
  opt.noise = run.fitted.rec.noise;
  try {
    run.result = diagnose_multipos(run.fitted.rec.input, run.fitted.fit, run.current.errors, opt);
  } catch (const std::runtime_error& e) {
    throw InputError(dir, 0, "", e.what());
  }
  run.improved = run.current;
  run.improved.errors = run.result.core.improved;
  improved_extra(run.improved.extra, run.result.core, multipos_diagnosis_json(run));
  return run;
}

namespace {
// The largest χ²/dof after, over the gyros and the gravity magnitude: far below 1 on every one, the
// class assumes much more noise than this unit shows and the residual test is blind below it.
constexpr double kLooseNoiseChi2 = 0.25;
double largest_chi2_after(const DiagnoseResult& r) {
  double m = 0;
  for (int a = 0; a < 4; ++a) {
    if (!std::isfinite(r.after[a].chi2_dof)) return std::numeric_limits<double>::quiet_NaN();  // no note
    m = std::max(m, r.after[a].chi2_dof);
  }
  return m;
}
}  // namespace

nlohmann::json multipos_diagnosis_json(const MultiposDiagRun& run) {
  const MultiposDiagnoseResult& R = run.result;
  const DiagnoseResult& r = R.core;
  nlohmann::json findings = nlohmann::json::array();
  for (const auto& f : r.findings) {
    nlohmann::json x = finding_head_json(f);
    x["evidence"] = finding_evidence_json(f);
    x["rms_before"] = f.rms_before;
    x["rms_after"] = f.rms_after;
    not_established(f, x);
    x["sentence"] = finding_sentence(f);
    findings.push_back(x);
  }
  nlohmann::json unexplained = nlohmann::json::array();
  for (const auto& u : r.unexplained)
    unexplained.push_back({{"sensor", kSensor[u.sensor]},
                           {"axis", u.axis >= 0 ? kAxis[u.axis] : "gravity magnitude"},
                           {"chi2_per_dof", u.chi2_dof},
                           {"ljung_box_p", u.ljung_box_p},
                           {"systematic_rms", u.systematic_rms}});
  auto st = [](const AxisStats& s) {
    return nlohmann::json{{"systematic_rms", s.systematic_rms}, {"chi2_per_dof", s.chi2_dof}, {"ljung_box_p", s.ljung_box_p}};
  };
  nlohmann::json axes = nlohmann::json::object();
  for (int a = 0; a < 3; ++a)
    axes[std::string("gyro_") + kAxis[a]] = {{"before", st(r.before[a])}, {"after", st(r.after[a])},
                                             {"rms_before", R.gyro_rms_before[a]}, {"rms_after", R.gyro_rms_after[a]}};
  axes["accel_gravity_magnitude"] = {{"before", st(r.before[3])}, {"after", st(r.after[3])},
                                     {"rms_before", R.g_rms_before}, {"rms_after", R.g_rms_after}};
  const double largest = largest_chi2_after(r);
  nlohmann::json poses = nlohmann::json::array();
  for (std::size_t k = 0; k < R.poses.size(); ++k)
    poses.push_back({{"pose", R.poses[k]},
                     {"t_s", R.pose_t[k]},
                     {"g_residual_before", r.residual[3].before[k]},
                     {"g_residual_after", r.residual[3].after[k]}});
  return {{"findings", findings},
          {"unexplained", unexplained},
          {"withdrawn", withdrawn_json(r.withdrawn)},
          {"axes", axes},
          {"coefficients_tested", run.fitted_first ? "fit multipos of this recording" : "given"},
          {"noise_check", {{"class", class_name(run.fitted.rec)},
                           {"largest_chi2_per_dof_after", largest},
                           {"far_above_the_residual", largest < kLooseNoiseChi2}}},
          {"multipos",
           {{"observations", "static poses: gravity magnitude (accelerometers), mean rate (gyros); rotations not used"},
            {"poses_used", R.poses.size()},
            {"earth_rate_vertical_removed", R.earth_vertical_removed},
            {"poses", poses}}},
          {"data", {{"parent_blocks", r.parents}, {"data_s", r.data_s}}}};
}

std::string multipos_diagnosis_text(const MultiposDiagRun& run) {
  const MultiposDiagnoseResult& R = run.result;
  const DiagnoseResult& r = R.core;
  std::ostringstream o;
  o << "coefficients tested: " << (run.fitted_first ? "fit multipos of this recording" : "given") << "; "
    << R.poses.size() << " static poses, " << fmt(r.data_s, 4)
    << " s still (observed: gravity magnitude and the gyros' mean rate per pose; the rotations are not used here)\n";
  if (r.findings.empty())
    o << (r.unexplained.empty() ? "no finding: the pose residuals are consistent with the model and the sensor's noise\n"
                                : "no catalogue finding, but the residual is NOT consistent: see unexplained below\n");
  if (const double m = largest_chi2_after(r); m < kLooseNoiseChi2)
    o << "! the residuals are far below the noise the class " << class_name(run.fitted.rec)
      << " assumes (χ²/dof at most " << fmt(m, 2) << " on every axis): this unit is quieter than its class, and an effect "
         "smaller than the class's noise is not tested here; a class file with this unit's noise (--device-class FILE) "
         "makes the test sharper\n";
  for (const auto& f : r.findings) o << "* " << finding_sentence(f) << " [" << f.status << "]\n";
  for (const auto& w : r.withdrawn) o << withdrawn_text(w) << "\n";
  for (const auto& u : r.unexplained)
    o << "? unexplained (no catalogue effect explains it): " << kSensor[u.sensor] << " "
      << (u.axis >= 0 ? kAxis[u.axis] : "gravity magnitude") << " residual χ²/dof " << fmt(u.chi2_dof) << ", Ljung–Box p "
      << fmt(u.ljung_box_p) << " (over the poses in time order)\n";
  o << "gravity-magnitude residual RMS " << fmt(R.g_rms_before / units::kMilliG) << " mg → "
    << fmt(R.g_rms_after / units::kMilliG) << " mg; χ²/dof " << fmt(r.before[3].chi2_dof) << " → "
    << fmt(r.after[3].chi2_dof) << "\n";
  for (int a = 0; a < 3; ++a)
    o << "gyro " << kAxis[a] << " static-rate residual RMS " << fmt(R.gyro_rms_before[a] / units::kDegPerHour) << " °/h → "
      << fmt(R.gyro_rms_after[a] / units::kDegPerHour) << " °/h; χ²/dof " << fmt(r.before[a].chi2_dof) << " → "
      << fmt(r.after[a].chi2_dof) << "\n";
  return o.str();
}

}  // namespace calbench
