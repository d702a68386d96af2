#include "bench/diagnose/diagnose_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <unistd.h>

#include "bench/bench_recording.hpp"
#include "bench/diagnose/finding_text.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "calibration/bench_fit_effects.hpp"
#include "calibration/units.hpp"

namespace calbench {

namespace {
const char* kSensor[] = {"gyro", "accel", "reference"};
const char* kAxis[] = {"x", "y", "z"};

// Parent blocks kept by the diagnosis (dense covariance per axis): longer parents beyond this.
constexpr int kMaxParents = 1000;

void feed(DiagDataBuilder& db, BenchBlockBuilder& bb, const DiagSample& s) {
  db.add(s);
  bb.add(s.t, s.dt, s.gyro, s.accel, s.w, s.f, s.step, s.temp_c);
}
}  // namespace

DiagInput load_diag_input(const std::filesystem::path& dir, double parent_s) {
  DiagInput in;
  in.meta = read_meta(dir);
  if (in.meta.kind != RecordingKind::bench)
    throw InputError((dir / "meta.json").string(), 0, "kind",
                     "this is a drive recording; this command needs kind \"bench\"");
  ImuReader imu(dir / "imu.csv", in.meta.imu_rate_hz);
  BenchRefReader ref(dir / "reference.csv");
  DiagDataBuilder db(std::min(0.05, parent_s), parent_s, kMaxParents);
  BenchBlockBuilder bb(parent_s);
  BenchRefRow r0, r1;
  if (!ref.next(r0)) throw InputError((dir / "reference.csv").string(), 0, "", "no data rows");
  bool have_r1 = ref.next(r1);
  in.ref_rows = have_r1 ? 2 : 1;
  ImuRecord s;
  while (imu.next(s)) {
    ++in.imu_rows;
    const bool inc = imu.form() == ImuForm::increments;
    DiagSample x;
    x.t = inc ? s.t - 0.5 * s.dt : s.t;
    x.dt = s.dt;
    x.gyro = inc ? Vec3(s.gyro / s.dt) : s.gyro;
    x.accel = inc ? Vec3(s.accel / s.dt) : s.accel;
    x.temp_c = s.temp_c;
    while (have_r1 && r1.t < x.t) {
      r0 = r1;
      have_r1 = ref.next(r1);
      if (have_r1) ++in.ref_rows;
    }
    if (x.t == r0.t) {
      x.w = r0.w;
      x.f = r0.f;
      x.step = r0.step;
      x.angle_deg = r0.angle_deg;
    } else if (have_r1 && x.t > r0.t && x.t <= r1.t) {
      const double u = (x.t - r0.t) / (r1.t - r0.t);
      x.w = r0.w + u * (r1.w - r0.w);
      x.f = r0.f + u * (r1.f - r0.f);
      x.step = (r0.step == r1.step) ? r0.step : (x.t == r1.t ? r1.step : -1);
      if (std::isfinite(r0.angle_deg) && std::isfinite(r1.angle_deg))
        x.angle_deg = r0.angle_deg + u * std::remainder(r1.angle_deg - r0.angle_deg, 360.0);
    } else {
      continue;
    }
    if (x.step >= 0) ++in.used_rows;
    feed(db, bb, x);
  }
  while (have_r1 && ref.next(r1)) ++in.ref_rows;
  in.data = db.finish();
  in.blocks = bb.finish();
  if (in.data.parents.empty())
    throw InputError((dir / "reference.csv").string(), 0, "step", "no IMU sample falls inside a plan step (all steps are −1?)");
  return in;
}

DiagInput simulate_diag_input(const BenchPlan& plan, const SensorErrors& truth, const BenchSimOptions& opt) {
  DiagInput in;
  in.meta.kind = RecordingKind::bench;
  in.meta.site = plan.site;
  in.meta.imu_rate_hz = opt.noise.output_rate_hz;
  in.meta.extra["bench"] = {{"plan", plan.name}, {"table", table_spec_json(plan.table)}};
  DiagDataBuilder db(0.05, 1.0, kMaxParents);
  BenchBlockBuilder bb(1.0);
  const double dt = 1.0 / opt.noise.output_rate_hz;
  simulate_bench(plan, plan.site, truth, opt, [&](const BenchSample& s) {
    DiagSample x;
    x.t = s.t;
    x.dt = dt;
    x.gyro = s.gyro;
    x.accel = s.accel;
    x.w = s.w_ref;
    x.f = s.f_ref;
    x.step = s.step;
    x.temp_c = s.temp_c;
    x.angle_deg = s.angle_deg;
    feed(db, bb, x);
    ++in.imu_rows;
    ++in.ref_rows;
    if (x.step >= 0) ++in.used_rows;
  });
  in.data = db.finish();
  in.blocks = bb.finish();
  return in;
}

DiagRun run_diagnosis(const DiagInput& in, const CoefficientSet* coeffs, const TableSpec& table) {
  DiagRun run;
  EffectTerms carried;
  if (coeffs) {
    run.current = *coeffs;
    carried = effects_from_json(coeffs->extra, "coefficients");
  } else {
    BenchFitOptions fo;
    fo.table = table;
    // Long runs (a thermal plan: thousands of 1 s blocks) are fitted on the diagnosis's parent blocks.
    const BenchFitResult r = in.blocks.size() > 2000 ? fit_bench(blocks_without_effects(in.data, EffectTerms{}), fo)
                                                     : fit_bench(in.blocks, fo);
    run.current = bench_result_to_coefficients(r, fo, in.meta, "");
    run.fitted_first = true;
  }
  // Unknown coefficients (σ = ∞) are tested at 0, as the spec says they are applied.
  SensorErrors cur = run.current.errors;
  DiagnoseOptions opt;
  opt.table = table;
  run.result = diagnose_bench(in.data, cur, carried, opt);

  using namespace units;
  CoefficientSet& c = run.improved;
  c.device = in.meta.device.serial.empty() ? run.current.device : in.meta.device;
  c.errors = run.result.improved;
  auto limit = [](TriadErrors& t, double lb, double lm) {
    for (int i = 0; i < 3; ++i) {
      if (!(t.sigma_bias(i) < lb)) {
        t.bias(i) = 0;
        t.sigma_bias(i) = kUnknownSigma;
      }
      for (int j = 0; j < 3; ++j)
        if (!(t.sigma_M(i, j) < lm)) {
          t.M(i, j) = 0;
          t.sigma_M(i, j) = kUnknownSigma;
        }
    }
  };
  limit(c.errors.gyro, 0.05 * kDeg, 1e-3);
  limit(c.errors.accel, 5 * kMilliG, 2e-3);
  c.extra = run.current.extra.is_object() ? run.current.extra : nlohmann::json::object();
  for (const auto& k : effect_json_keys()) c.extra.erase(k);
  effects_to_json(run.result.improved_terms, run.result.terms_sigma, c.extra);
  nlohmann::json eff = nlohmann::json::array();
  for (const auto& f : run.result.findings) eff.push_back(effect_name(f.term.effect));
  c.extra["diagnosis"] = {{"source", "calbench diagnose"},
                          {"effects_added", eff},
                          {"note", "b and M refitted together with the extra terms; keys documented in docs/diagnosis.md"}};
  return run;
}

namespace {

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

}  // namespace

std::string finding_sentence(const DiagFinding& f) {
  std::ostringstream o;
  const std::string who = f.term.sensor == 2 ? std::string("the bench reference")
                                             : std::string(kSensor[f.report_sensor]) +
                                                   (f.report_axis >= 0 ? std::string(" ") + kAxis[f.report_axis] : "");
  const EffectSpec& x = effect_spec(f.term.effect);
  const int rs = x.shows_on >= 0 ? x.shows_on : f.report_sensor;
  o << fill_sentence(x.bench_sentence, who, condition_phrase(f.condition));
  if (f.value.size() == 1) {
    o << human_value(f, f.value[0]);
    if (std::isfinite(f.sigma[0])) o << " ± " << human_value(f, f.sigma[0]);
  } else {
    o << "(";
    for (std::size_t k = 0; k < f.value.size(); ++k) o << (k ? ", " : "") << human_value(f, f.value[k]);
    o << ")";
  }
  if (x.shape == EffectShape::noise) o << ", τ ≈ " << drift_tau_text(f);
  o << "; systematic residual " << human_rms(rs, f.rms_before) << " → " << human_rms(rs, f.rms_after);
  o << alternatives_text(f);
  return o.str();
}

nlohmann::json diagnosis_json(const DiagRun& run) {
  const DiagnoseResult& r = run.result;
  nlohmann::json findings = nlohmann::json::array();
  for (const auto& f : r.findings) {
    nlohmann::json v, s;
    if (f.value.size() == 1) {
      v = f.value[0];
      s = std::isfinite(f.sigma[0]) ? nlohmann::json(f.sigma[0]) : nlohmann::json(nullptr);
    } else {
      v = f.value;
      s = f.sigma;
    }
    const int ai = finding_axis_index(f, r);
    nlohmann::json ev = {{"delta_chi2", f.delta_chi2},
                         {"delta_bic", f.delta_bic},
                         {"heldout_delta_chi2", f.heldout_delta_chi2},
                         {"revealing_condition", f.condition},
                         {"correlation_before", f.condition_r},
                         {"ljung_box_p_before", r.before[ai].ljung_box_p},
                         {"ljung_box_p_after", r.after[ai].ljung_box_p}};
    if (effect_spec(f.term.effect).shape == EffectShape::noise) add_drift_tau_evidence(f, ev);
    ev["indistinguishable_from"] = alternatives_json(f);
    findings.push_back({{"effect", effect_name(f.term.effect)},
                        {"sensor", kSensor[f.report_sensor]},
                        {"axis", f.report_axis >= 0 ? kAxis[f.report_axis] : "all"},
                        {"value", v},
                        {"unit", f.unit},
                        {"sigma", s},
                        {"evidence", ev},
                        {"rms_before", f.rms_before},
                        {"rms_after", f.rms_after},
                        {"sentence", finding_sentence(f)}});
  }
  nlohmann::json unexplained = nlohmann::json::array();
  for (const auto& u : r.unexplained) {
    nlohmann::json corr = nlohmann::json::array();
    for (const auto& c : u.correlations) corr.push_back({{"condition", c.condition}, {"r", c.r}});
    unexplained.push_back({{"sensor", kSensor[u.sensor]},
                           {"axis", kAxis[u.axis]},
                           {"chi2_per_dof", u.chi2_dof},
                           {"within_step_chi2_per_dof", u.high_chi2_dof},
                           {"ljung_box_p", u.ljung_box_p},
                           {"systematic_rms", u.systematic_rms},
                           {"worst_steps", u.worst_steps},
                           {"correlations", corr},
                           {"angle_harmonic", u.angle_harmonic},
                           {"angle_harmonic_amplitude", u.angle_harmonic_amp}});
  }
  nlohmann::json axes = nlohmann::json::object();
  for (int a = 0; a < 6; ++a) {
    auto st = [](const AxisStats& s) {
      return nlohmann::json{{"systematic_rms", s.systematic_rms}, {"step_rms", s.step_rms}, {"within_step_rms", s.within_rms},
                            {"chi2_per_dof", s.chi2_dof},        {"within_step_chi2_per_dof", s.high_chi2_dof},
                            {"ljung_box_q", s.ljung_box_q},      {"ljung_box_p", s.ljung_box_p},
                            {"criterion", s.bic}};
    };
    nlohmann::json corr = nlohmann::json::array();
    for (std::size_t k = 0; k < r.correlations_before[a].size() && k < 4; ++k)
      corr.push_back({{"condition", r.correlations_before[a][k].condition}, {"r", r.correlations_before[a][k].r}});
    axes[std::string(kSensor[a / 3]) + "_" + kAxis[a % 3]] = {
        {"before", st(r.before[a])}, {"after", st(r.after[a])}, {"white_sigma_per_sample", r.white_sigma[a]},
        {"correlations_before", corr}};
  }
  return {{"findings", findings},
          {"unexplained", unexplained},
          {"withdrawn", withdrawn_json(r.withdrawn)},
          {"axes", axes},
          {"coefficients_tested", run.fitted_first ? "bench fit of this recording" : "given"},
          {"data", {{"parent_blocks", r.parents}, {"sub_blocks", r.subs}, {"data_s", r.data_s}}}};
}

std::string diagnosis_text(const DiagRun& run) {
  const DiagnoseResult& r = run.result;
  std::ostringstream o;
  o << "coefficients tested: " << (run.fitted_first ? "bench fit of this recording" : "given") << "; " << r.parents
    << " blocks, " << fmt(r.data_s, 4) << " s of plan steps\n";
  if (r.findings.empty())
    o << (r.unexplained.empty() ? "no finding: the residual is consistent with the model and the sensor's noise\n"
                                : "no catalogue finding, but the residual is NOT consistent: see unexplained below\n");
  for (const auto& f : r.findings) o << "* " << finding_sentence(f) << "\n";
  for (const auto& w : r.withdrawn) o << withdrawn_text(w) << "\n";
  for (const auto& u : r.unexplained) {
    o << "? unexplained (no catalogue effect explains it): " << kSensor[u.sensor] << " " << kAxis[u.axis] << " residual χ²/dof " << fmt(u.chi2_dof)
      << " (within steps " << fmt(u.high_chi2_dof) << "), Ljung–Box p " << fmt(u.ljung_box_p) << "; worst steps";
    for (int s : u.worst_steps) o << " " << s;
    o << "; correlates with";
    for (const auto& c : u.correlations) o << " " << c.condition << " (r " << fmt(c.r, 2) << ")";
    if (u.angle_harmonic > 0) o << "; angle harmonic " << u.angle_harmonic << " amplitude " << fmt(u.angle_harmonic_amp);
    o << "\n";
  }
  o << "per axis (systematic RMS, χ²/dof, Ljung–Box p) before → after:\n";
  for (int a = 0; a < 6; ++a) {
    o << "  " << kSensor[a / 3] << " " << kAxis[a % 3] << ": " << human_rms(a / 3, r.before[a].systematic_rms) << " → "
      << human_rms(a / 3, r.after[a].systematic_rms) << ";  " << fmt(r.before[a].chi2_dof) << " → "
      << fmt(r.after[a].chi2_dof) << ";  " << fmt(r.before[a].ljung_box_p, 2) << " → " << fmt(r.after[a].ljung_box_p, 2)
      << "\n";
  }
  return o.str();
}

namespace {

std::string html_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;";
    else if (c == '>') o += "&gt;";
    else if (c == '&') o += "&amp;";
    else o += c;
  }
  return o;
}

// One before/after plot of axis a's residual against a condition; returns inline SVG or a note.
std::string plot_svg(const std::filesystem::path& tmp, const std::string& tag, const DiagInput& in,
                     const DiagnoseResult& r, int a, const std::string& cond) {
  using namespace units;
  const DiagData& d = in.data;
  const double scale = a < 3 ? 1.0 / kDegPerHour : 1.0 / kMilliG;
  const std::string unit = a < 3 ? "°/h" : "mg";
  const std::string cname = cond == "f" ? "f_z" : cond;
  const auto& rb = r.residual[a].before;
  const auto& ra = r.residual[a].after;
  const std::filesystem::path dat = tmp / (tag + ".dat"), gp = tmp / (tag + ".gp"), svg = tmp / (tag + ".svg");
  {
    std::ofstream o(dat);
    // Angle: within-block deviations of rotating sub-blocks; otherwise 1 s block means.
    if (cname == "angle") {
      for (const auto& p : d.parents) {
        double mb = 0, ma = 0;
        for (int j = p.first; j < p.first + p.count; ++j) {
          mb += d.subs[j].n * rb[j];
          ma += d.subs[j].n * ra[j];
        }
        mb /= p.n;
        ma /= p.n;
        for (int j = p.first; j < p.first + p.count; ++j)
          if (d.subs[j].rotating() && std::isfinite(d.subs[j].angle))
            o << condition_value(d, d.subs[j], "angle") << " " << (rb[j] - mb) * scale << " " << (ra[j] - ma) * scale << "\n";
      }
    } else {
      for (const auto& p : d.parents) {
        double mb = 0, ma = 0;
        for (int j = p.first; j < p.first + p.count; ++j) {
          mb += d.subs[j].n * rb[j];
          ma += d.subs[j].n * ra[j];
        }
        double x = condition_value(d, d.subs[p.first + p.count / 2], cname);
        if (cname == "dT/dt") x = p.dtemp;
        o << x << " " << mb / p.n * scale << " " << ma / p.n * scale << "\n";
      }
    }
  }
  {
    std::ofstream g(gp);
    g << "set terminal svg size 720,360 dynamic font 'sans,11'\nset output '" << svg.string() << "'\n"
      << "set xlabel '" << condition_axis_label(cname) << "'\nset ylabel 'residual (" << unit
      << ")'\nset key outside top\nset grid\n"
      // "before" as open circles under the smaller, half-transparent "after" dots: both stay visible.
      << "plot '" << dat.string() << "' using 1:2 with points pt 6 ps 0.6 lc rgb '#d62728' title 'before', '"
      << dat.string() << "' using 1:3 with points pt 7 ps 0.35 lc rgb '#601f77b4' title 'after'\n";
  }
  const std::string cmd = "gnuplot '" + gp.string() + "' 2>/dev/null";
  if (std::system(cmd.c_str()) != 0 || !std::filesystem::exists(svg)) return "<p><i>(plot unavailable: gnuplot failed)</i></p>";
  std::ifstream s(svg);
  std::stringstream b;
  b << s.rdbuf();
  std::string text = b.str();
  const auto pos = text.find("<svg");
  return pos == std::string::npos ? text : text.substr(pos);
}

}  // namespace

void write_diagnosis_report(const std::filesystem::path& html, const DiagInput& in, const DiagRun& run,
                            const std::string& title) {
  const DiagnoseResult& r = run.result;
  std::filesystem::path tmp = std::filesystem::temp_directory_path() /
                              ("calbench-diagnose-" + std::to_string(::getpid()));
  std::filesystem::create_directories(tmp);
  std::ostringstream o;
  o << "<!DOCTYPE html><html><head><meta charset='utf-8'><title>calbench diagnose: " << html_escape(title)
    << "</title><style>body{font-family:sans-serif;max-width:1000px;margin:auto;padding:0 1em}"
       "table{border-collapse:collapse}svg{max-width:100%;height:auto}p,pre{overflow-wrap:anywhere}"
       "td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}</style></head><body>\n";
  o << "<h1>Diagnosis of " << html_escape(title) << "</h1>\n";
  o << "<p>Coefficients tested: " << (run.fitted_first ? "bench fit of this recording" : "given") << ". " << r.parents
    << " blocks of ~1 s, " << r.subs << " sub-blocks of 0.05 s, " << fmt(r.data_s, 4) << " s of plan steps.</p>\n";
  o << "<h2>Findings</h2>\n";
  if (r.findings.empty()) o << "<p>No finding: the residual is consistent with the model and the sensor's noise.</p>\n";
  int k = 0;
  for (const auto& f : r.findings) {
    o << "<h3>" << effect_name(f.term.effect) << "</h3><p>" << html_escape(finding_sentence(f)) << "</p>\n";
    o << "<p>Evidence: Δχ² " << fmt(f.delta_chi2) << ", ΔBIC " << fmt(f.delta_bic) << ", held-out Δχ² "
      << fmt(f.heldout_delta_chi2) << ".</p>\n";
    const int a = finding_axis_index(f, r);
    o << "<p>Residual of " << kSensor[a / 3] << " " << kAxis[a % 3] << " against " << html_escape(f.condition)
      << ", before (red circles) and after (blue dots):</p>\n"
      << plot_svg(tmp, std::string("f").append(std::to_string(k++)), in, r, a, f.condition);
  }
  if (!r.unexplained.empty()) {
    o << "<h2>Unexplained</h2>\n";
    for (const auto& u : r.unexplained) {
      o << "<p>" << kSensor[u.sensor] << " " << kAxis[u.axis] << ": χ²/dof " << fmt(u.chi2_dof) << ", within steps "
        << fmt(u.high_chi2_dof) << ", Ljung–Box p " << fmt(u.ljung_box_p) << "; worst steps";
      for (int s : u.worst_steps) o << " " << s;
      o << "; correlates with";
      for (const auto& c : u.correlations) o << " " << html_escape(c.condition) << " (r " << fmt(c.r, 2) << ")";
      o << "</p>\n";
      const std::string c = u.correlations.empty() ? "time" : u.correlations.front().condition;
      o << plot_svg(tmp, std::string("u").append(std::to_string(k++)), in, r, u.sensor * 3 + u.axis, c);
    }
  }
  o << "<h2>Per axis, before → after</h2><table><tr><th>axis</th><th>systematic RMS</th><th>χ²/dof (1 s blocks)</th>"
       "<th>χ²/dof (within steps)</th><th>Ljung–Box p</th><th>criterion</th></tr>\n";
  for (int a = 0; a < 6; ++a) {
    const auto &b = r.before[a], &f = r.after[a];
    o << "<tr><td>" << kSensor[a / 3] << " " << kAxis[a % 3] << "</td><td>" << html_escape(human_rms(a / 3, b.systematic_rms))
      << " → " << html_escape(human_rms(a / 3, f.systematic_rms)) << "</td><td>" << fmt(b.chi2_dof) << " → "
      << fmt(f.chi2_dof) << "</td><td>" << fmt(b.high_chi2_dof) << " → " << fmt(f.high_chi2_dof) << "</td><td>"
      << fmt(b.ljung_box_p, 2) << " → " << fmt(f.ljung_box_p, 2) << "</td><td>" << fmt(b.bic, 6) << " → "
      << fmt(f.bic, 6) << "</td></tr>\n";
  }
  o << "</table>\n<p>Systematic RMS: RMS of per-step mean residuals (estimated drift removed) and of within-step "
       "residuals binned by table angle, with the white-noise expectation subtracted. Criterion: −2 log-likelihood of "
       "the 1 s block residuals plus parameters·ln N.</p></body></html>\n";
  std::error_code ec;
  std::filesystem::remove_all(tmp, ec);
  write_text_atomic(html, o.str());
}

}  // namespace calbench
