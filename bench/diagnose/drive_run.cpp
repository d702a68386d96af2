#include "bench/diagnose/drive_run.hpp"

#include <cmath>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "bench/diagnose/finding_text.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "bench/drive/fit_drive.hpp"
#include "bench/drive/qc_drive.hpp"
#include "bench/drive/route_toml.hpp"
#include "common/input_error.hpp"
#include "bench/io/plan_toml.hpp"
#include "bench/io/json_util.hpp"
#include "bench/report/gnuplot.hpp"
#include "calibration/bench_blocks.hpp"
#include "calibration/bench_fit.hpp"
#include "calibration/bench_sim.hpp"
#include "calibration/imu_error_sim.hpp"
#include "calibration/ins/strapdown.hpp"
#include "calibration/units.hpp"

namespace calbench {

namespace {
const char* kSensor[] = {"gyro", "accel", "reference"};
const char* kAxis[] = {"x", "y", "z"};
const char* kAxisName[] = {"gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"};

// Display units: gyro °/h, accel mg.
double disp(double v, int sensor) { return sensor == 0 ? v / units::kDegPerHour : v / units::kMilliG; }
const char* disp_unit(int sensor) { return sensor == 0 ? "°/h" : "mg"; }

std::string value_text(const DiagFinding& f) {
  const Term& t = f.term;
  const EffectSpec& x = effect_spec(t.effect);
  const int k = t.sensor == 1 ? 1 : 0;
  std::string v = f.value.size() == 1 ? fmt(x.drive_display.value(f.value[0], k)) : "(";
  for (std::size_t i = 0; f.value.size() != 1 && i < f.value.size(); ++i)
    v += (i ? ", " : "") + fmt(x.drive_display.value(f.value[i], k));
  v += std::string(f.value.size() == 1 ? " " : ") ") + x.drive_display.unit[k];
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

void feed_imu(DriveDiagBuilder& b, ins::RateIntegrator& integ, bool rates, double t, double dt, const Vec3& g,
              const Vec3& a, double temp) {
  DriveImuSample s;
  s.t = t;
  s.dt = dt;
  s.temp_c = temp;
  if (rates) {
    integ(g, a, dt, s.dtheta, s.dv);
    s.has_rates = true;
    s.w_raw = g;
    s.f_raw = a;
  } else {
    s.dtheta = g;
    s.dv = a;
  }
  b.imu(s);
}

DriveRefEpoch to_epoch(const DriveRefRow& r) {
  DriveRefEpoch e;
  e.t = r.t;
  e.lat = r.lat_deg * units::kDeg;
  e.lon = r.lon_deg * units::kDeg;
  e.h = r.h_m;
  e.v_ned = r.v_ned;
  e.rpy = r.rpy_deg * units::kDeg;
  return e;
}
}  // namespace

DriveCoeffs read_drive_coeffs(const std::string& file) {
  DriveCoeffs c;
  c.file = file;
  const QcSet q = load_qc_set(file);
  c.mounting_rpy_deg = q.mounting_rpy_deg;
  const nlohmann::json j = read_json_file(file);
  const nlohmann::json& cj = (j.is_object() && j.contains("coefficients")) ? j["coefficients"] : j;
  c.set = coefficients_from_json(cj, file);
  c.carried = effects_from_json(cj, file);
  return c;
}

DriveDiagInput load_drive_diag_input(const std::filesystem::path& dir, const std::optional<Vec3>& rpy_deg) {
  DriveDiagInput in;
  in.dir = dir;
  in.meta = read_meta(dir);
  const std::string mf = (dir / "meta.json").string();
  if (in.meta.kind != RecordingKind::drive) throw InputError(mf, 0, "kind", "expected a drive recording");
  if (!in.meta.mounting) throw InputError(mf, 0, "mounting", "a drive recording needs a mounting");
  if (!(in.meta.imu_rate_hz > 0)) throw InputError(mf, 0, "imu_rate_hz", "must be > 0");
  in.mounting_rpy_deg = rpy_deg ? *rpy_deg : in.meta.mounting->rpy_deg;
  in.mounting_source = rpy_deg ? "coefficients file" : "meta.json (nominal)";
  DriveDiagBuilder b(ins::dcm_from_rpy(in.mounting_rpy_deg * units::kDeg), in.meta.mounting->lever_arm_m);
  ImuReader imu(dir / "imu.csv", in.meta.imu_rate_hz);
  DriveRefReader ref(dir / "reference.csv");
  DriveRefRow rr;
  bool have_ref = ref.next(rr);
  if (!have_ref) throw InputError((dir / "reference.csv").string(), 0, "", "no data rows");
  ++in.ref_rows;
  ins::RateIntegrator integ;
  ImuRecord r;
  while (imu.next(r)) {
    ++in.imu_rows;
    feed_imu(b, integ, imu.form() == ImuForm::rates, r.t, r.dt, r.gyro, r.accel, r.temp_c);
    while (have_ref && rr.t <= r.t + 1e-9) {
      b.reference(to_epoch(rr));
      have_ref = ref.next(rr);
      if (have_ref) ++in.ref_rows;
    }
  }
  in.data = b.finish();
  if (in.data.parents.size() < 20)
    throw InputError(dir.string(), 0, "", "too little overlapping IMU and reference data for a diagnosis (< 20 s)");
  return in;
}

DriveCoeffs simulate_factory_coeffs(const std::string& plan_file, std::uint64_t seed, const EffectTerms& effects,
                                    std::uint64_t bench_seed) {
  const BenchPlan plan = load_plan(plan_file);
  BenchSimOptions so;
  so.seed = bench_seed;
  so.effects = effects;
  so.effects.time_offset_s = 0;
  so.effects.lever_arm_m.setZero();
  // An injected scale_factor is a shift since the calibration: the factory saw the unit without it.
  so.effects.gyro.scale.setZero();
  so.effects.accel.scale.setZero();
  BenchBlockBuilder bb(1.0);
  const double dt = 1.0 / so.noise.output_rate_hz;
  simulate_bench(plan, plan.site, draw_random_unit(seed), so, [&](const BenchSample& x) {
    bb.add(x.t, dt, x.gyro, x.accel, x.w_ref, x.f_ref, x.step, x.temp_c, x.saturated);
  });
  BenchFitOptions o;
  o.table = plan.table;
  DriveCoeffs c;
  c.set.errors = fit_bench(bb.finish(), o).estimate;
  c.file = plan_file + " (simulated, fitted)";
  return c;
}

DriveDiagInput simulate_drive_diag_input(const std::string& route_file, std::uint64_t seed, const EffectTerms& effects,
                                         double until_s) {
  const RouteFile rf = load_route(route_file);
  drivesim::DriveSimConfig cfg;
  cfg.route = rf.route;
  cfg.mems = draw_random_unit(seed);
  const Vec3 rpy = draw_true_mounting_rpy_deg(rf, seed);
  cfg.imu_rate_hz = rf.imu_rate_hz;
  cfg.mounting_rpy = rpy * units::kDeg;
  cfg.lever_arm = rf.lever_arm_m;
  cfg.reference = rf.reference;
  cfg.gnss = rf.gnss;
  cfg.gnss.rate_hz = 0;
  cfg.seed = seed;
  cfg.effects = effects;
  DriveDiagInput in;
  in.meta.kind = RecordingKind::drive;
  in.meta.imu_rate_hz = rf.imu_rate_hz;
  in.meta.mounting = Mounting{rf.mounting_rpy_deg, rf.lever_arm_m};
  in.meta.device.serial = "SIM-" + std::to_string(seed);
  in.mounting_rpy_deg = rf.mounting_rpy_deg;
  in.mounting_source = "route file (nominal)";
  DriveDiagBuilder b(ins::dcm_from_rpy(rf.mounting_rpy_deg * units::kDeg), rf.lever_arm_m);
  ins::RateIntegrator integ;
  const double dt = 1.0 / rf.imu_rate_hz;
  drivesim::DriveSinks sinks;
  sinks.imu = [&](const drivesim::SimImu& m) {
    ++in.imu_rows;
    feed_imu(b, integ, true, m.t, dt, m.gyro, m.accel, std::numeric_limits<double>::quiet_NaN());
  };
  sinks.reference = [&](const drivesim::SimRef& s) {
    ++in.ref_rows;
    DriveRefEpoch e;
    e.t = s.t;
    e.lat = s.lat;
    e.lon = s.lon;
    e.h = s.h;
    e.v_ned = s.v_ned;
    e.rpy = s.rpy;
    b.reference(e);
  };
  drivesim::simulate_drive(cfg, sinks, until_s);
  in.data = b.finish();
  return in;
}

DriveInnovations drive_innovations(const DriveDiagInput& in, const DriveDiagRun& run) {
  DriveInnovations out;
  const std::clock_t c0 = std::clock();
  auto filter_run = [&](const CoefficientSet& set, InnovationStats (&stats)[3], std::vector<std::string>& applied) {
    std::vector<InnovationSample> x[3];
    FitDriveArgs a;
    a.dir = in.dir.string();
    a.coeffs_set = set;
    a.qc = false;
    a.write_out = false;
    a.on_innovation = [&](int type, const inmotion::InnovationRecord& r) {
      x[type].push_back({r.t, r.nu, r.S, r.nis, static_cast<int>(r.status)});
    };
    const nlohmann::json j = fit_drive(a);
    if (j.contains("effects"))
      for (const auto& k : j["effects"]["applied"]) applied.push_back(k.get<std::string>());
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
  for (const auto& k : effect_json_keys()) run.improved.extra.erase(k);
  run.improved.extra.erase("diagnosis");
  effects_to_json(r.improved_terms, r.terms_sigma, run.improved.extra);
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
  run.improved.extra["diagnosis"] = dj;
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

namespace {
const char* kObsName[] = {"position", "velocity", "attitude"};

nlohmann::json innovation_stats_json(const InnovationStats& s) {
  nlohmann::json w = nlohmann::json::array(), c = nlohmann::json::array();
  for (const auto& x : s.worst_windows)
    w.push_back({{"t0_s", x.t0}, {"t1_s", x.t1}, {"nis_per_dof", x.nis_per_dof}, {"epochs", x.epochs}});
  for (std::size_t k = 0; k < s.correlations.size() && k < 5; ++k)
    c.push_back({{"condition", s.correlations[k].condition}, {"r", s.correlations[k].r}});
  return {{"epochs", s.epochs},
          {"used", s.used},
          {"rejected", s.rejected},
          {"forced", s.forced},
          {"nis_per_dof", s.nis_per_dof},
          {"median_nis_per_dof", s.median_nis_per_dof},
          {"fraction_within_95pct", s.fraction_within_95},
          {"ljung_box_p", {s.ljung_box_p[0], s.ljung_box_p[1], s.ljung_box_p[2]}},
          {"ljung_box_p_min", s.ljung_box_p_min},
          {"lag1_autocorr", {s.lag1_autocorr[0], s.lag1_autocorr[1], s.lag1_autocorr[2]}},
          {"worst_windows_s", w},
          {"correlations", c},
          {"correlation_blocks", s.correlation_blocks}};
}

// One sentence per observation type: NIS/dof, gating, whiteness, worst window, strongest condition.
std::string innovation_sentence(int type, const DriveInnovations& v) {
  const InnovationStats& b = v.before[type];
  const InnovationStats& a = v.after[type];
  auto arrow = [&](double x, double y, int prec = 3) { return v.compared ? fmt(x, prec) + " → " + fmt(y, prec) : fmt(x, prec); };
  std::ostringstream o;
  o << kObsName[type] << " innovations: NIS/dof " << arrow(b.nis_per_dof, a.nis_per_dof) << " (1 if consistent), gated "
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
}  // namespace

nlohmann::json drive_innovations_json(const DriveDiagRun& run) {
  if (!run.innovations) return {{"skipped", run.innovations_skipped}};
  const DriveInnovations& v = *run.innovations;
  nlohmann::json j;
  j["method"] = "in-motion filter as `fit drive --coeffs` runs it (obs pos,vel,att); normalised innovation "
                "ν_i/√S_ii per component (position, velocity: N, E, D; attitude: small-rotation axes)";
  j["before"] = {{"coefficients", "the improved b and M with only the tested catalogue terms"},
                 {"effects_applied", v.applied_before}};
  j["after"] = {{"coefficients", v.compared ? "IMPROVED.json (the new terms too)" : "same as before (no new term)"},
                {"effects_applied", v.applied_after}};
  j["compared"] = v.compared;
  j["cpu_s"] = v.cpu_s;
  for (int k = 0; k < 3; ++k)
    j[kObsName[k]] = {{"before", innovation_stats_json(v.before[k])}, {"after", innovation_stats_json(v.after[k])},
                      {"sentence", innovation_sentence(k, v)}};
  return j;
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

std::string drive_finding_sentence(const DiagFinding& f, int shown_sensor) {
  const Term& t = f.term;
  const int s = f.report_sensor < 2 ? f.report_sensor : 0;
  std::string who = std::string(kSensor[t.sensor < 2 ? t.sensor : s]);
  if (t.sensor < 2 && f.report_axis >= 0) who += std::string(" ") + kAxis[f.report_axis];
  const EffectSpec& x = effect_spec(t.effect);
  const std::string what = x.drive_what ? x.drive_what : x.key;
  const std::string head = x.drive_head ? fill_sentence(x.drive_head, who, "")
                                        : who + " error grows with " + condition_text(f.condition);
  const int rs = shown_sensor >= 0 ? shown_sensor : (f.report_sensor < 2 ? f.report_sensor : 0);
  return head + ": " + what + ", " + value_text(f) + "; systematic residual " + fmt(disp(f.rms_before, rs)) + " " +
         disp_unit(rs) + " → " + fmt(disp(f.rms_after, rs)) + " " + disp_unit(rs) + alternatives_text(f);
}

nlohmann::json drive_diagnosis_json(const DriveDiagInput& in, const DriveDiagRun& run) {
  const DriveDiagnoseResult& R = run.result;
  const DiagnoseResult& r = R.core;
  nlohmann::json j;
  j["kind"] = "drive";
  nlohmann::json fs = nlohmann::json::array();
  for (std::size_t fi = 0; fi < r.findings.size(); ++fi) {
    const DiagFinding& f = r.findings[fi];
    nlohmann::json x;
    x["effect"] = effect_name(f.term.effect);
    x["sensor"] = kSensor[f.term.sensor];
    x["axis"] = f.report_axis >= 0 ? kAxis[f.report_axis] : "all";
    if (f.value.size() == 1) {
      x["value"] = f.value[0];
      x["sigma"] = std::isfinite(f.sigma[0]) ? nlohmann::json(f.sigma[0]) : nlohmann::json(nullptr);
    } else {
      x["value"] = f.value;
      x["sigma"] = f.sigma;
    }
    x["unit"] = f.unit;
    nlohmann::json ev = {{"delta_chi2", f.delta_chi2}, {"delta_bic", f.delta_bic},
                         {"heldout_delta_chi2", f.heldout_delta_chi2}, {"revealing_condition", f.condition},
                         {"correlation_before", f.condition_r}};
    if (effect_spec(f.term.effect).shape == EffectShape::noise) add_drift_tau_evidence(f, ev);
    ev["indistinguishable_from"] = alternatives_json(f);
    if (fi < R.rms_floor.size()) ev["rms_noise_floor"] = R.rms_floor[fi];
    if (fi < R.shown_on.size() && effect_spec(f.term.effect).shape != EffectShape::noise) ev["rms_axis"] = kAxisName[R.shown_on[fi]];
    if (fi < R.rms_lowpass.size() && effect_spec(f.term.effect).shape != EffectShape::noise)
      ev["rms_of"] = R.rms_lowpass[fi] ? "three-block means" : "blocks";
    if (f.report_sensor < 2 && f.report_axis >= 0) {
      const int a = f.report_sensor * 3 + f.report_axis;
      ev["ljung_box_p_before"] = r.before[a].ljung_box_p;
      ev["ljung_box_p_after"] = r.after[a].ljung_box_p;
    }
    x["evidence"] = ev;
    x["rms_before"] = f.rms_before;
    x["rms_after"] = f.rms_after;
    x["sentence"] = drive_finding_sentence(f, fi < R.shown_on.size() ? R.shown_on[fi] / 3 : -1);
    fs.push_back(x);
  }
  j["findings"] = fs;
  nlohmann::json us = nlohmann::json::array();
  for (const auto& u : r.unexplained) {
    nlohmann::json c = nlohmann::json::array();
    for (const auto& cc : u.correlations) c.push_back({{"condition", cc.condition}, {"r", cc.r}});
    nlohmann::json w = nlohmann::json::array();
    for (int s : u.worst_steps) w.push_back({20.0 * s, 20.0 * (s + 1)});
    us.push_back({{"sensor", kSensor[u.sensor]}, {"axis", kAxis[u.axis]}, {"chi2_per_dof", u.chi2_dof},
                  {"ljung_box_p", u.ljung_box_p}, {"systematic_rms", u.systematic_rms}, {"worst_windows_s", w},
                  {"correlations", c}});
  }
  j["unexplained"] = us;
  j["withdrawn"] = withdrawn_json(r.withdrawn);
  nlohmann::json axes;
  for (int a = 0; a < 6; ++a) {
    auto st = [](const AxisStats& s) {
      return nlohmann::json{{"systematic_rms", s.systematic_rms}, {"chi2_per_dof", s.chi2_dof},
                            {"ljung_box_p", s.ljung_box_p}};
    };
    nlohmann::json cb = nlohmann::json::array(), ca = nlohmann::json::array();
    for (std::size_t k = 0; k < r.correlations_before[a].size() && k < 5; ++k)
      cb.push_back({{"condition", r.correlations_before[a][k].condition}, {"r", r.correlations_before[a][k].r}});
    for (std::size_t k = 0; k < R.correlations_after[a].size() && k < 5; ++k)
      ca.push_back({{"condition", R.correlations_after[a][k].condition}, {"r", R.correlations_after[a][k].r}});
    axes[kAxisName[a]] = {{"before", st(r.before[a])}, {"after", st(r.after[a])},
                          {"white_sigma_per_sample", r.white_sigma[a]}, {"white_scale", R.white_scale[a]},
                          {"block_noise_sigma", R.block_noise_sigma[a]},
                          {"correlations_before", cb}, {"correlations_after", ca}};
  }
  j["axes"] = axes;
  nlohmann::json segs = nlohmann::json::array();
  for (const auto& s : R.segments) {
    nlohmann::json m;
    for (int a = 0; a < 6; ++a)
      m[kAxisName[a]] = {{"mean_before", s.mean_before[a]}, {"mean_after", s.mean_after[a]},
                         {"z_before", s.z_before[a]}, {"z_after", s.z_after[a]}};
    segs.push_back({{"motion", s.motion}, {"blocks", s.blocks}, {"seconds", s.seconds}, {"axes", m}});
  }
  j["segments"] = segs;
  j["coefficients_tested"] = run.coeffs_given ? "given (M fixed; bias and mounting re-estimated)"
                                              : "none given: bias and M fitted on this drive";
  nlohmann::json mount = {{"tested_rpy_deg", to_json(in.mounting_rpy_deg)}, {"source", in.mounting_source},
                          {"lever_arm_m", to_json(in.meta.mounting ? in.meta.mounting->lever_arm_m : Vec3::Zero())}};
  if (run.coeffs_given) {
    mount["correction_rad"] = to_json(R.mounting_delta);
    mount["correction_sigma_rad"] = to_json(R.mounting_sigma);
  }
  j["mounting"] = mount;
  j["noise_model"] = {{"gyro_drift_sigma_rad_s", r.drift_sigma[0]}, {"gyro_drift_tau_s", r.drift_tau[0]},
                      {"accel_drift_sigma_m_s2", r.drift_sigma[1]}, {"accel_drift_tau_s", r.drift_tau[1]}};
  j["data"] = {{"blocks", r.parents}, {"intervals", r.subs}, {"seconds", r.data_s},
               {"imu_rate_hz", in.data.imu_rate_hz}, {"skipped_intervals", in.data.skipped_intervals}};
  if (run.innovations || !run.innovations_skipped.empty()) j["innovations"] = drive_innovations_json(run);
  return j;
}

std::string drive_diagnosis_text(const DriveDiagInput& in, const DriveDiagRun& run) {
  const DriveDiagnoseResult& R = run.result;
  const DiagnoseResult& r = R.core;
  std::ostringstream o;
  o << "drive: " << r.parents << " blocks, " << fmt(r.data_s, 4) << " s; reference intervals " << r.subs
    << "; coefficients tested: "
    << (run.coeffs_given ? "given (M fixed; bias and mounting re-estimated)" : "none (bias and M fitted on this drive)")
    << "\n";
  if (run.coeffs_given)
    o << "mounting correction (MEMS axes): " << fmt(R.mounting_delta(0) / units::kDeg) << ", "
      << fmt(R.mounting_delta(1) / units::kDeg) << ", " << fmt(R.mounting_delta(2) / units::kDeg) << " ° (σ "
      << fmt(R.mounting_sigma.maxCoeff() / units::kDeg) << " °) relative to " << in.mounting_source << "\n";
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
    for (const auto& c : u.correlations) o << " " << c.condition << " (r " << fmt(c.r, 2) << ")";
    o << "\n";
  }
  o << "per axis (systematic RMS, χ²/dof, Ljung–Box p) before → after:\n";
  for (int a = 0; a < 6; ++a) {
    const int s = a / 3;
    o << "  " << kSensor[s] << " " << kAxis[a % 3] << ": " << fmt(disp(r.before[a].systematic_rms, s)) << " "
      << disp_unit(s) << " → " << fmt(disp(r.after[a].systematic_rms, s)) << " " << disp_unit(s) << ";  "
      << fmt(r.before[a].chi2_dof) << " → " << fmt(r.after[a].chi2_dof) << ";  " << fmt(r.before[a].ljung_box_p, 2)
      << " → " << fmt(r.after[a].ljung_box_p, 2) << "\n";
  }
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

void write_drive_diagnosis_report(const std::filesystem::path& html, const DriveDiagInput& in, const DriveDiagRun& run,
                                  const std::string& title) {
  const DiagnoseResult& r = run.result.core;
  std::ostringstream h;
  h << "<!doctype html><html><head><meta charset=\"utf-8\"><title>calbench diagnose (drive) "
    << report::html_escape(title)
    << "</title><style>body{font-family:sans-serif;max-width:1000px;margin:auto;padding:0 1em}"
       "pre{white-space:pre-wrap;overflow-wrap:anywhere}img{max-width:100%;height:auto}</style></head><body>"
       "<h1>Drive diagnosis: " << report::html_escape(title)
    << "</h1><pre>" << report::html_escape(drive_diagnosis_text(in, run)) << "</pre>";
  std::vector<std::pair<int, std::string>> plots;  // axis, condition
  for (const auto& f : r.findings) {
    if (effect_spec(f.term.effect).shape == EffectShape::noise) {
      plots.push_back({f.term.sensor * 3, "time"});
      continue;
    }
    int a = f.report_sensor * 3 + std::max(0, f.report_axis);
    if (effect_spec(f.term.effect).dominant_component || f.term.sensor == 2) {
      double worst = -1;
      for (int b = 0; b < 6; ++b)
        if ((f.term.sensor == 2 || b >= 3) && r.before[b].systematic_rms > worst) {
          worst = r.before[b].systematic_rms;
          a = b;
        }
    }
    plots.push_back({a, f.condition.empty() ? "time" : f.condition});
  }
  if (plots.empty())
    for (int a = 0; a < 6; ++a) plots.push_back({a, "time"});
  for (const auto& [a, cond] : plots) {
    std::ostringstream data;
    const int s = a / 3;
    for (int k = 0; k < r.parents; ++k)
      data << drive_condition_value(in.data, k, cond) << " " << disp(r.residual[a].before[k], s) << " "
           << disp(r.residual[a].after[k], s) << "\n";
    // "before" as open circles under the smaller, half-transparent "after" dots: both stay visible.
    const std::string script = "set terminal pngcairo size 800,420\nset output 'plot.png'\nset xlabel '" +
                               condition_axis_label(cond) + "'\nset ylabel '" + kAxisName[a] + " residual (" +
                               disp_unit(s) + ")'\nset key outside\nset grid\n"
                               "plot 'd.txt' u 1:2 w p pt 6 ps 0.8 lc rgb '#d62728' t 'before', "
                               "'' u 1:3 w p pt 7 ps 0.45 lc rgb '#601f77b4' t 'after'\n";
    h << "<h2>" << kAxisName[a] << " vs " << report::html_escape(cond) << "</h2>";
    try {
      h << "<img src=\"" << report::png_data_uri(report::run_gnuplot(script, {{"d.txt", data.str()}})) << "\">";
    } catch (const std::exception& e) {
      h << "<p><i>(plot unavailable: " << report::html_escape(e.what()) << ")</i></p>";
    }
  }
  h << "</body></html>\n";
  write_text_atomic(html, h.str());
}

}  // namespace calbench
