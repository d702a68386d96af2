#include <cmath>
#include <sstream>

#include "calibration/inmotion/obs_names.hpp"
#include "bench/diagnose/diagnose_run.hpp"
#include "bench/diagnose/diagnose_text.hpp"
#include "bench/diagnose/drive_run.hpp"
#include "bench/diagnose/finding_text.hpp"
#include "bench/diagnose/gnss_run.hpp"
#include "common/units.hpp"

// The text of `calbench diagnose`: the sentences of the findings and the summaries, bench and drive.

namespace calbench {

namespace diagnose_out {

const char* const kSensor[3] = {"gyro", "accel", "reference"};
const char* const kAxis[3] = {"x", "y", "z"};
const char* const kAxisName[6] = {"gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"};

double disp(double v, int sensor) { return sensor == 0 ? v / units::kDegPerHour : v / units::kMilliG; }
const char* disp_unit(int sensor) { return sensor == 0 ? "°/h" : "mg"; }

BiasChange bias_change(const DiagnoseResult& r) {
  BiasChange c;
  for (int a = 0; a < 6; ++a) {
    const TriadErrors& now = a < 3 ? r.improved.gyro : r.improved.accel;
    const TriadErrors& given = a < 3 ? r.base_before.gyro : r.base_before.accel;
    c.change[a] = now.bias(a % 3) - given.bias(a % 3);
    // The drive's σ and the given coefficients' own (their bench fit's): a change beyond 3σ of both
    // is a change of the unit, not of the estimates.
    c.sigma[a] = std::hypot(now.sigma_bias(a % 3), given.sigma_bias(a % 3));
    if (c.sigma[a] > 0 && std::abs(c.change[a]) > 3 * c.sigma[a]) c.beyond_3sigma.push_back(a);
  }
  return c;
}

std::string bias_change_text(const DiagnoseResult& r) {
  const BiasChange c = bias_change(r);
  std::string s = "bias since the given coefficients (re-estimated on every drive: a turn-on bias shift is the null "
                  "alternative of any term nearly constant here):";
  for (int sensor = 0; sensor < 2; ++sensor) {
    s += std::string(sensor ? ";" : "") + " " + kSensor[sensor];
    for (int i = 0; i < 3; ++i) {
      const int a = 3 * sensor + i;
      s += std::string(i ? ", " : " ") + fmt(disp(c.change[a], sensor), 3) + " ± " + fmt(disp(c.sigma[a], sensor), 2);
    }
    s += std::string(" ") + disp_unit(sensor);
  }
  s += "; beyond 3σ:";
  if (c.beyond_3sigma.empty()) s += " none";
  for (std::size_t k = 0; k < c.beyond_3sigma.size(); ++k)
    s += std::string(k ? "," : "") + " " + kSensor[c.beyond_3sigma[k] / 3] + " " + kAxis[c.beyond_3sigma[k] % 3];
  return s + "\n";
}

std::string correlations_text(const std::vector<ConditionCorrelation>& c) {
  std::string s;
  for (const auto& x : c) s += " " + x.condition + " (r " + fmt(x.r, 2) + ")";
  return s;
}

std::string axis_table_text(const DiagnoseResult& r, const std::function<std::string(int, double)>& rms) {
  std::ostringstream o;
  o << "per axis (systematic RMS, χ²/dof, Ljung–Box p) before → after:\n";
  for (int a = 0; a < 6; ++a) {
    const int s = a / 3;
    o << "  " << kSensor[s] << " " << kAxis[a % 3] << ": " << rms(s, r.before[a].systematic_rms) << " → "
      << rms(s, r.after[a].systematic_rms) << ";  " << fmt(r.before[a].chi2_dof) << " → " << fmt(r.after[a].chi2_dof)
      << ";  " << fmt(r.before[a].ljung_box_p, 2) << " → " << fmt(r.after[a].ljung_box_p, 2) << "\n";
  }
  return o.str();
}

// Value in the units people use, for sentences.
std::string human_value(const DiagFinding& f, double v) {
  const DisplayUnit& u = effect_spec(f.term.effect).bench_display;
  const int k = f.term.sensor == 1 ? 1 : 0;
  return fmt(u.value(v, k)) + " " + u.unit[k];
}

std::string human_rms(int sensor, double v) {
  using namespace units;
  return sensor == 0 ? fmt(v / kDegPerHour) + " °/h" : fmt(v / kMilliG, 3) + " mg";
}

int finding_axis_index(const DiagFinding& f, const DiagnoseResult& r) {
  if (f.term.sensor < 2 && f.report_axis >= 0) return f.term.sensor * 3 + f.report_axis;
  const EffectSpec& x = effect_spec(f.term.effect);
  if (x.dominant_component && f.report_axis >= 0) return x.sensor * 3 + f.report_axis;
  int best = 0;
  for (int a = 1; a < 6; ++a)
    if (r.before[a].systematic_rms > r.before[best].systematic_rms) best = a;
  if (x.shows_on == 1) {
    best = 3;
    for (int a = 4; a < 6; ++a)
      if (r.before[a].systematic_rms > r.before[best].systematic_rms) best = a;
  }
  return best;
}

const char* condition_phrase(const std::string& c) {
  if (c == "temperature") return "temperature";
  if (c == "rate") return "rotation rate";
  if (c == "angle") return "table angle";
  if (c == "time") return "time";
  if (c == "f_x") return "specific force along x";
  if (c == "f_y") return "specific force along y";
  if (c == "f_z") return "specific force along z";
  if (c == "f") return "orientation (specific force)";
  return c.c_str();
}

// One sentence per observation type: NIS/dof, gating, whiteness, worst window, strongest condition.
std::string innovation_sentence(int type, const DriveInnovations& v) {
  const InnovationStats& b = v.before[type];
  const InnovationStats& a = v.after[type];
  auto arrow = [&](double x, double y, int prec = 3) { return v.compared ? fmt(x, prec) + " → " + fmt(y, prec) : fmt(x, prec); };
  std::ostringstream o;
  o << inmotion::obs_type_name(type) << " innovations: NIS/dof " << arrow(b.nis_per_dof, a.nis_per_dof) << " (1 if consistent), gated "
    << (v.compared ? std::to_string(b.rejected) + " → " + std::to_string(a.rejected) : std::to_string(b.rejected)) << " of "
    << b.epochs << "; whiteness (Ljung–Box p, worst component) " << arrow(b.ljung_box_p_min, a.ljung_box_p_min, 2)
    << (a.ljung_box_p_min < 0.05 ? " (not white at the 5 % level)" : " (white at the 5 % level)");
  // Far from 1 either way is not "consistent": below, the assumed noise is too large (a smaller
  // NIS after a correction is then no improvement); above, too small or a model error remains.
  if (a.nis_per_dof < 0.5) o << "; NIS/dof " << fmt(a.nis_per_dof, 3) << " is far below 1: the assumed noise is too large";
  else if (a.nis_per_dof > 2) o << "; NIS/dof " << fmt(a.nis_per_dof, 3) << " is far above 1: noise too small or a model error left";
  if (!a.worst_windows.empty()) {
    const auto& w = a.worst_windows[0];
    o << "; worst 20 s window " << fmt(w.t0, 4) << "–" << fmt(w.t1, 4) << " s (NIS/dof " << fmt(w.nis_per_dof) << ")";
  }
  if (!a.correlations.empty()) {
    const auto& c = a.correlations[0];
    double rb = 0;
    for (const auto& x : b.correlations)
      if (x.condition == c.condition) rb = x.r;
    o << "; normalised magnitude follows " << c.condition << " most (r "
      << (v.compared ? fmt(rb, 2) + " → " + fmt(c.r, 2) : fmt(c.r, 2)) << ", " << a.correlation_blocks << " blocks)";
  }
  return o.str();
}

}  // namespace diagnose_out

using namespace diagnose_out;

namespace {

// What the residual does and the effect's name, for the sentence of a bench finding.
void sentence_head(std::ostringstream& o, const DiagFinding& f, const std::string& who) {
  o << fill_sentence(effect_spec(f.term.effect).bench_sentence, who, condition_phrase(f.condition));
}

std::string value_text(const DiagFinding& f) {
  const Term& t = f.term;
  const EffectSpec& x = effect_spec(t.effect);
  const int k = t.sensor == 1 ? 1 : 0;
  std::string v = f.value.size() == 1 ? fmt(x.drive_display.value(f.value[0], k)) : "(";
  for (std::size_t i = 0; f.value.size() != 1 && i < f.value.size(); ++i)
    v += (i ? ", " : "") + fmt(x.drive_display.value(f.value[i], k));
  // One value told apart: its σ beside it (a value not told apart has none, as in the JSON).
  if (f.value.size() == 1 && f.sigma.size() == 1 && f.told_apart() && std::isfinite(f.sigma[0]) && f.sigma[0] > 0 &&
      x.shape != EffectShape::noise)
    v += " ± " + fmt(x.drive_display.value(f.sigma[0], k), 2);
  v += std::string(f.value.size() == 1 ? " " : ") ") + x.drive_display.unit[k];
  // τ < 0: the IMU is early, which "late by τ" leaves the reader to work out.
  if (t.effect == EffectId::time_offset && f.value.size() == 1 && f.value[0] < 0)
    v += " (the IMU early by " + fmt(x.drive_display.value(-f.value[0], k)) + " " + x.drive_display.unit[k] + ")";
  return x.shape == EffectShape::noise ? v + ", τ " + drift_tau_text(f) : v;
}

std::string condition_text(const std::string& c) {
  if (c.size() == 3 && c[1] == '_' && (c[0] == 'w' || c[0] == 'f'))
    return std::string(c[0] == 'w' ? "angular rate about " : "specific force along ") + c[2];
  if (c == "ang_accel") return "angular acceleration";
  if (c == "turn_rate") return "turn rate";
  if (c == "along_accel") return "longitudinal acceleration";
  if (c == "|w|") return "rotation rate magnitude";
  if (c == "|f|") return "specific force magnitude";
  return c;
}

// The effect's name as a drive finding's sentence gives it.
std::string drive_effect_what(const Term& t) {
  const EffectSpec& x = effect_spec(t.effect);
  return x.drive_what ? x.drive_what : x.key;
}

}  // namespace

std::string finding_sentence(const DiagFinding& f) {
  std::ostringstream o;
  const std::string who = f.term.sensor == 2 ? std::string("the bench reference")
                                             : std::string(kSensor[f.report_sensor]) +
                                                   (f.report_axis >= 0 ? std::string(" ") + kAxis[f.report_axis] : "");
  const EffectSpec& x = effect_spec(f.term.effect);
  const int rs = x.shows_on >= 0 ? x.shows_on : f.report_sensor;
  sentence_head(o, f, who);
  if (f.value.size() == 1) {
    o << human_value(f, f.value[0]);
    // A finding not told apart from an alternative is not established: no σ as if it were.
    if (std::isfinite(f.sigma[0]) && f.told_apart()) o << " ± " << human_value(f, f.sigma[0]);
  } else if (x.shape == EffectShape::axis_rows && f.report_axis >= 0 && f.sigma.size() == f.value.size()) {
    // A row of named components (g² products, the other axes): "y 0.37 ± 0.04, z 0.01 ± 0.05 unit".
    const int u = f.term.sensor == 1 ? 1 : 0;
    o << "(";
    for (std::size_t k = 0; k < f.value.size(); ++k) {
      o << (k ? ", " : "") << effect_component_name(x, f.report_axis, static_cast<int>(k)) << " "
        << fmt(x.bench_display.value(f.value[k], u));
      if (std::isfinite(f.sigma[k]) && f.told_apart()) o << " ± " << fmt(x.bench_display.value(f.sigma[k], u));
    }
    o << " " << x.bench_display.unit[u] << ")";
  } else if (f.sigma.size() == f.value.size() && f.told_apart()) {
    // Components told apart: each with its σ, the unit once ("(0.0903 ± 5.3e-05, …) °/s/g").
    const DisplayUnit& u = x.bench_display;
    const int k = f.term.sensor == 1 ? 1 : 0;
    o << "(";
    for (std::size_t i = 0; i < f.value.size(); ++i) {
      o << (i ? ", " : "") << fmt(u.value(f.value[i], k));
      if (std::isfinite(f.sigma[i])) o << " ± " << fmt(u.value(f.sigma[i], k), 2);
    }
    o << ") " << u.unit[k];
  } else {
    o << "(";
    for (std::size_t k = 0; k < f.value.size(); ++k) o << (k ? ", " : "") << human_value(f, f.value[k]);
    o << ")";
  }
  if (x.shape == EffectShape::noise) o << ", τ ≈ " << drift_tau_text(f);
  o << "; systematic residual " << human_rms(rs, f.rms_before) << " → " << human_rms(rs, f.rms_after);
  o << alternatives_text(f);
  if (std::string(f.status) == "partial")
    o << "; partial, not established: the model cuts this axis's systematic residual by "
      << fmt(100 * f.explained_fraction) << " %"
      << (f.remainder_is_noise ? "" : " and the axis's remainder is unexplained (see Unexplained)");
  if (f.versus_drift.tested) {
    const DisplayUnit& du = noise_effect_spec().bench_display;
    const int k = f.term.sensor == 1 ? 1 : 0;
    o << "; against a drift of the triad in its place (σ " << fmt(du.value(f.versus_drift.drift_sigma, k)) << " " << du.unit[k]
      << ", τ " << fmt(f.versus_drift.drift_tau_s) << " s): −2 ln L " << fmt(f.versus_drift.delta_score)
      << " in favour of the temperature term (" << f.versus_drift.verdict << ")";
  }
  return o.str();
}

// "not excited by this recording (not candidates): g2_sensitivity gyro x, y, z — needs …", one
// line per effect and sensor.
std::string not_excited_text(const std::vector<NotExcited>& v) {
  std::ostringstream o;
  for (std::size_t i = 0; i < v.size();) {
    const Term& t = v[i].term;
    std::string axes;
    std::size_t j = i;
    for (; j < v.size() && v[j].term.effect == t.effect && v[j].term.sensor == t.sensor; ++j)
      if (v[j].term.axis >= 0) axes += std::string(axes.empty() ? " " : ", ") + "xyz"[v[j].term.axis];
    const EffectSpec& x = effect_spec(t.effect);
    o << "- not excited by this recording (not a candidate): " << x.key << (t.sensor == 0 ? " gyro" : t.sensor == 1 ? " accel" : "")
      << axes << "; needs " << effect_excited_by(x) << "\n";
    i = j;
  }
  return o.str();
}

std::string diagnosis_text(const DiagRun& run) {
  const DiagnoseResult& r = run.result;
  std::ostringstream o;
  o << "coefficients tested: " << (run.fitted_first ? "bench fit of this recording" : "given") << "; " << r.parents
    << " blocks, " << fmt(r.data_s, 4) << " s of plan steps\nnoise model (drift prior) of " << run.noise_class << "\n";
  for (const auto& x : r.saturation) o << "! " << saturation_sentence(x) << "\n";
  if (r.low_input.stated()) o << "! " << low_input_sentence(r.low_input) << "\n";
  if (r.findings.empty())
    o << (!r.drift_excess.empty() ? std::string("no established finding: see the drift beyond the class's stability below\n") :
          r.unexplained.empty() ? std::string("no finding") + (r.saturation.empty() ? "" : " in the rest of the recording") +
                                      ": the residual is consistent with the model and the sensor's noise\n"
                                : "no catalogue finding, but the residual is NOT consistent: see unexplained below\n");
  for (const auto& f : r.findings) o << "* " << finding_sentence(f) << "\n";
  for (const auto& x : r.drift_excess) o << "~ " << drift_excess_sentence(x) << "\n";
  if (!r.drift_noted.empty())
    o << "notes (not findings): a bias change beyond 2× the class's stability in the tail of its own drift\n";
  for (const auto& x : r.drift_noted) o << "~ " << drift_note_sentence(x) << "\n";
  for (const auto& w : r.withdrawn) o << withdrawn_text(w) << "\n";
  for (const auto& u : r.unexplained) {
    o << "? unexplained (no catalogue effect explains it): " << kSensor[u.sensor] << " " << kAxis[u.axis] << " residual χ²/dof " << fmt(u.chi2_dof)
      << " (within steps " << fmt(u.high_chi2_dof) << "), Ljung–Box p " << fmt(u.ljung_box_p)
      << ", step-offset test (" << (std::string(u.step_family) == "all" ? "all steps" : std::string(u.step_family) + " steps")
      << ") p " << fmt(u.step_p, 2) << "; worst steps";
    for (int s : u.worst_steps) o << " " << s;
    o << "; correlates with";
    o << correlations_text(u.correlations);
    if (u.angle_harmonic > 0) o << "; angle harmonic " << u.angle_harmonic << " amplitude " << fmt(u.angle_harmonic_amp);
    const char* unit = u.sensor == 0 ? " rad/s" : " m/s²";
    if (std::isfinite(u.angle_bin_deg[0]))
      o << "; concentrated at table angle " << fmt(u.angle_bin_deg[0]) << "–" << fmt(u.angle_bin_deg[1]) << "° (mean "
        << fmt(u.angle_bin_mean) << unit << ", z " << fmt(u.angle_bin_z, 2) << ")";
    if (u.period_hz > 0) o << "; strongest periodic component " << fmt(u.period_hz, 3) << " Hz, amplitude " << fmt(u.period_amp) << unit;
    o << "\n";
  }
  o << not_excited_text(r.not_excited);
  o << axis_table_text(r, human_rms);
  return o.str();
}

std::string drive_finding_sentence(const DiagFinding& f, int shown_sensor) {
  const Term& t = f.term;
  const int s = f.report_sensor < 2 ? f.report_sensor : 0;
  std::string who = std::string(kSensor[t.sensor < 2 ? t.sensor : s]);
  if (t.sensor < 2 && f.report_axis >= 0) who += std::string(" ") + kAxis[f.report_axis];
  const std::string what = drive_effect_what(t);
  const EffectSpec& x = effect_spec(t.effect);
  const std::string head = x.drive_head ? fill_sentence(x.drive_head, who, "")
                                        : who + " error grows with " + condition_text(f.condition);
  const int rs = shown_sensor >= 0 ? shown_sensor : (f.report_sensor < 2 ? f.report_sensor : 0);
  return head + ": " + what + ", " + value_text(f) + "; systematic residual " + fmt(disp(f.rms_before, rs)) + " " +
         disp_unit(rs) + " → " + fmt(disp(f.rms_after, rs)) + " " + disp_unit(rs) + alternatives_text(f);
}

std::string gnss_finding_sentence(const DiagFinding& f, double phi) {
  const Term& t = f.term;
  std::string who = t.sensor < 2 ? std::string(kSensor[t.sensor]) : "the IMU";
  if (t.sensor < 2 && f.report_axis >= 0) who += std::string(" ") + kAxis[f.report_axis];
  const EffectSpec& x = effect_spec(t.effect);
  const int k = t.sensor == 1 ? 1 : 0;
  std::string sg;
  for (std::size_t i = 0; i < f.sigma.size(); ++i) sg += (i ? ", " : "") + fmt(x.drive_display.value(f.sigma[i], k), 2);
  if (f.sigma.size() > 1) sg = "(" + sg + ")";
  // value_text gives a single value's σ itself.
  std::string s = who + ": " + drive_effect_what(t) + ", " + value_text(f) + (f.value.size() == 1 ? "" : ", σ " + sg) +
                  " (innovations against the GNSS fixes: Δχ² " + fmt(f.delta_chi2) + ", ΔBIC " + fmt(f.delta_bic);
  if (phi > 1)
    s += ", in the final model Δχ² " + fmt(f.delta_chi2_final) + ", /φ " + fmt(f.delta_chi2_final / phi) + " against the threshold " +
         fmt(DriveDiagnoseOptions{}.min_delta_chi2);
  s += ")";
  if (std::string(f.status) != "established")
    s += "; " + std::string(f.status) + ": the innovations stay overdispersed (φ " + fmt(phi) +
         "), a model error no candidate covers: worth a look, not a correction to apply blindly";
  return s;
}

std::string drive_diagnosis_text(const DriveDiagInput& in, const DriveDiagRun& run) {
  const DriveDiagnoseResult& R = run.result;
  const DiagnoseResult& r = R.core;
  std::ostringstream o;
  o << "drive: " << r.parents << " blocks, " << fmt(r.data_s, 4) << " s; reference intervals " << r.subs
    << "; coefficients tested: "
    << (run.coeffs_given ? "given (M fixed; bias and mounting re-estimated)" : "none (bias and M fitted on this drive)")
    << "\nnoise model (drift prior) of " << run.noise_class << "\n";
  if (run.coeffs_given)
    o << "mounting correction (MEMS axes): " << fmt(R.mounting_delta(0) / units::kDeg) << ", "
      << fmt(R.mounting_delta(1) / units::kDeg) << ", " << fmt(R.mounting_delta(2) / units::kDeg) << " ° (σ "
      << fmt(R.mounting_sigma.maxCoeff() / units::kDeg) << " °) relative to " << in.mounting_source << "\n";
  if (run.coeffs_given) o << bias_change_text(r);
  int flagged = 0;  // motion classes whose mean residual is beyond 3σ after the fit
  for (const auto& sg : R.segments)
    for (int a = 0; a < 6; ++a) flagged += std::abs(sg.z_after[a]) > 3;
  if (r.findings.empty()) {
    if (r.unexplained.empty() && flagged == 0)
      o << "no finding: the residual is consistent with the model and the noise (no axis unexplained, no motion class beyond 3σ)\n";
    else
      o << "no catalogue finding, but the residual is NOT consistent: " << r.unexplained.size() << " axis(es) unexplained, "
        << flagged << " motion-class mean(s) beyond 3σ (marked ! below)\n";
  }
  for (std::size_t fi = 0; fi < r.findings.size(); ++fi)
    o << "* " << drive_finding_sentence(r.findings[fi], fi < R.shown_on.size() ? R.shown_on[fi] / 3 : -1) << "\n";
  for (const auto& w : r.withdrawn) o << withdrawn_text(w) << "\n";
  for (const auto& u : r.unexplained) {
    o << "! unexplained: " << kSensor[u.sensor] << " " << kAxis[u.axis] << " χ²/dof " << fmt(u.chi2_dof)
      << ", Ljung–Box p " << fmt(u.ljung_box_p, 2) << "; strongest correlations:";
    o << correlations_text(u.correlations);
    if (!u.condition_test.empty())
      o << "; the bias the noise model's drift absorbed follows " << u.condition_test << " (GLS test Δχ² " << fmt(u.condition_dchi2)
        << ", r " << fmt(u.condition_r, 2) << "): an effect outside the catalogue, not a drift";
    if (u.period_hz > 0)
      o << "; strongest periodic component " << fmt(u.period_hz, 3) << " Hz, amplitude " << fmt(disp(u.period_amp, u.sensor))
        << " " << disp_unit(u.sensor);
    o << "\n";
  }
  o << axis_table_text(r, [](int s, double v) { return fmt(disp(v, s)) + " " + disp_unit(s); });
  // The closest an axis came to the remainder's condition test without reaching it (how far the
  // recording was from calling an axis unexplained).
  int near = -1;
  for (int a = 0; a < 6; ++a)
    if (R.condition_test[a].tested && R.condition_test[a].dchi2 < DriveDiagnoseResult::kConditionTestLevel &&
        (near < 0 || R.condition_test[a].dchi2 > R.condition_test[near].dchi2))
      near = a;
  if (near >= 0)
    o << "remainder against the motion conditions (GLS, unexplained at Δχ² ≥ " << fmt(DriveDiagnoseResult::kConditionTestLevel, 3)
      << ", false alarm 10⁻³ per recording): largest below it " << kSensor[near / 3] << " " << kAxis[near % 3] << " "
      << R.condition_test[near].condition << " Δχ² " << fmt(R.condition_test[near].dchi2, 3) << "\n";
  o << "per motion class (mean residual z-score before → after, |z| > 3 marked):\n";
  for (const auto& sg : R.segments) {
    o << "  " << sg.motion << " (" << fmt(sg.seconds, 4) << " s):";
    for (int a = 0; a < 6; ++a) {
      o << " " << kAxisName[a] << " " << fmt(sg.z_before[a], 2) << "→" << fmt(sg.z_after[a], 2);
      if (std::abs(sg.z_after[a]) > 3) o << "!";
    }
    o << "\n";
  }
  o << drive_innovations_text(run);
  return o.str();
}

std::string drive_innovations_text(const DriveDiagRun& run) {
  if (!run.innovations) return run.innovations_skipped.empty() ? "" : "in-motion filter innovations: " + run.innovations_skipped + "\n";
  const DriveInnovations& v = *run.innovations;
  std::ostringstream o;
  o << "in-motion filter innovations (fit drive over the whole drive; " << (v.compared ? "without → with the new terms" : "no new term")
    << ", " << fmt(v.cpu_s, 2) << " s CPU):\n";
  for (int k = 0; k < 3; ++k) o << "  " << innovation_sentence(k, v) << "\n";
  return o.str();
}

}  // namespace calbench
