#include "calibration/inmotion/obs_names.hpp"
#include "bench/diagnose/gnss_run.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <ctime>
#include <functional>
#include <limits>
#include <map>
#include <tuple>

#include "bench/diagnose/diagnose_text.hpp"
#include "calibration/diagnosis/innovation_conditions.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "bench/diagnose/finding_text.hpp"
#include "bench/drive/fit_drive.hpp"
#include "bench/drive/recording_scan.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/hdf5_recording.hpp"
#include "bench/io/recording.hpp"
#include "calibration/diagnosis/diagnosis_engine.hpp"
#include "calibration/ins/nav_math.hpp"
#include "common/drive_result.hpp"
#include "common/units.hpp"
#include "common/input_error.hpp"

// `calbench diagnose` on a GNSS-only drive: the candidates as hypotheses of the GNSS-aided filter,
// the search (hypothesis_search), the findings and IMPROVED.json, JSON and text.

namespace calbench {

bool drive_is_gnss_only(const std::filesystem::path& dir) {
  return !recording_has_table(dir, "reference") && recording_has_table(dir, "gnss");
}

namespace {

// What a hypothesis switches on in the filter, and how its estimate is read from RESULT.json. One
// row per candidate; the scale rows only with given coefficients (without them the filter fits the
// scale from its raw priors: there is no calibration for it to differ from).
struct CandidateRow {
  const char* name;
  Term term;
  int nparams;
  bool needs_coeffs;
  void (*configure)(FitDriveArgs& a, bool on);
  // Value (SI, the registry's convention) and σ per parameter (nullptr: a profiled candidate).
  void (*read)(const DriveResult& result, const CoefficientSet& given, std::vector<double>& v, std::vector<double>& s);
  // A profiled candidate (no filter state): the first `nparams` parameters of `term`, compensated on
  // the IMU samples (the coefficients' catalogue keys), profile_quadratic with step `step`.
  bool profiled = false;
  double step = 0;
};

void add_estimate(FitDriveArgs& a, const char* block) { a.estimate += (a.estimate.empty() ? "" : ",") + std::string(block); }

// Priors of the hypotheses' states, wide enough that the estimate is the data's, not the prior's (a
// concealed 0.1 m lever arm under fit drive's default 0.1 m prior came out 83 mm, 2.5σ short): lever
// arm 0.3 m per axis, time offset 50 ms, scale 5000 ppm.
constexpr double kLeverSigma = 0.3, kTimeSigma = 0.05, kScaleAllowancePpm = 5000;

// The scale hypotheses: off = the scale as calibrated (stability allowance 0: the prior is the given
// set's σ); on = a wide allowance (kScaleAllowancePpm).
template <int Sensor>
void scale_configure(FitDriveArgs& a, bool on) {
  (Sensor == 0 ? a.allowance.gyro_scale_ppm : a.allowance.accel_scale_ppm) = on ? kScaleAllowancePpm : 0.0;
}
template <int Sensor>
void scale_read(const DriveResult& r, const CoefficientSet& given, std::vector<double>& v, std::vector<double>& s) {
  const TriadErrors& g = Sensor == 0 ? given.errors.gyro : given.errors.accel;
  const TriadErrors& e = Sensor == 0 ? r.coefficients.errors.gyro : r.coefficients.errors.accel;
  for (int i = 0; i < 3; ++i) {
    v.push_back(e.M(i, i) - g.M(i, i));
    s.push_back(e.sigma_M(i, i));
  }
}

const std::vector<CandidateRow>& candidate_rows() {
  static const std::vector<CandidateRow> rows = {
      {"time_offset", {EffectId::time_offset, 2, -1}, 1, false,
       [](FitDriveArgs& a, bool on) {
         if (on) add_estimate(a, "time");
         a.time_offset_sigma = kTimeSigma;
       },
       // The block's δt: the fix stamped t describes the antenna at t − δt; relative to the fixes the
       // IMU is then late by τ = −δt (the registry's time_offset: the IMU sample stamped t saw t − τ).
       [](const DriveResult& r, const CoefficientSet&, std::vector<double>& v, std::vector<double>& s) {
         v.push_back(-r.time_offset.value().value);
         s.push_back(r.time_offset.value().sigma);
       }},
      {"lever_arm", {EffectId::lever_arm, 1, -1}, 3, false,
       [](FitDriveArgs& a, bool on) {
         if (on) add_estimate(a, "lever");
         a.lever_arm_sigma = kLeverSigma;
       },
       // Where the MEMS sits relative to meta.json's lever arm (the antenna is the reference point).
       [](const DriveResult& r, const CoefficientSet&, std::vector<double>& v, std::vector<double>& s) {
         for (int i = 0; i < 3; ++i) {
           v.push_back(r.lever_arm.value().correction(i));
           s.push_back(r.lever_arm.value().sigma(i));
         }
       }},
      {"scale_factor gyro", {EffectId::scale_factor, 0, -1}, 3, true, scale_configure<0>, scale_read<0>},
      {"scale_factor accel", {EffectId::scale_factor, 1, -1}, 3, true, scale_configure<1>, scale_read<1>},
      // The gyro z g-sensitivity to the horizontal forces (a car turns and brakes; to f_z, gravity, it
      // is a bias): compensated with the given coefficients, so with --coeffs only.
      {"g_sensitivity gyro z", {EffectId::g_sensitivity, 0, 2}, 2, true, [](FitDriveArgs&, bool) {}, nullptr, true, 2e-5},
  };
  return rows;
}

struct FilterRun {
  DriveResult result;
  std::vector<InnovationSample> x[2];  // position, velocity
};

// Which of the logger's measured terms a run leaves out (the logger tests).
struct LoggerOff {
  bool timing = false, latency = false;
  bool any() const { return timing || latency; }
  int key() const { return (timing ? 1 : 0) + (latency ? 2 : 0); }
};

double deviance_of(const FilterRun& fr) { return innovation_deviance(fr.x[0]) + innovation_deviance(fr.x[1]); }
// A run's overdispersion: the worse of its position and velocity innovations'.
double phi_of(const FilterRun& fr) {
  return std::max(innovation_overdispersion(innovation_stats(fr.x[0], nullptr)), innovation_overdispersion(innovation_stats(fr.x[1], nullptr)));
}

// The logger's measured terms (issue 53 item 1) as candidates tested by the innovations: the base
// filter against the same filter with the term off (Δχ², divided by the base run's overdispersion),
// and where the innovations grow without any of them.
void logger_tests(GnssDiagRun& run, const FilterRun& base, const std::function<const FilterRun&(const LoggerOff&)>& without) {
  const nlohmann::json& ex = base.result.extra;
  const double phi = phi_of(base);  // ≥ 1
  run.conditions.phi_base = phi;
  LoggerOff all;
  auto test = [&](const char* name, const std::string& value, double value_ms, LoggerOff off) {
    GnssLoggerTest t;
    t.name = name;
    t.value = value;
    t.value_ms = value_ms;
    // Over the epochs both runs have: without a term the heading may be chosen at another time.
    const FilterRun& w = without(off);
    for (int k = 0; k < 2; ++k) {
      long n = 0;
      const auto [d_without, d_base] = paired_deviance(w.x[k], base.x[k], &n);
      t.dchi2 += d_without - d_base;
      t.epochs_compared += n;
    }
    t.dchi2_over_phi = t.dchi2 / phi;
    t.confirmed = t.dchi2_over_phi >= DriveDiagnoseOptions{}.min_delta_chi2;
    run.logger_tests.push_back(t);
  };
  if (ex.contains("sample_timing") && ex["sample_timing"].value("used_ms", 0.0) > 0) {
    all.timing = true;
    const nlohmann::json& st = ex["sample_timing"];
    const double sigma_ms = st["used_ms"].get<double>();
    std::string v = "(stamp scatter σ " + fmt(sigma_ms, 3) + " ms";
    if (applied_logger_correction(st).drop_repeats) v += "; with it the second reads dropped";
    test("sample timing", v + ")", sigma_ms, LoggerOff{true, false});
  }
  if (ex.contains("gnss_velocity_latency") && ex["gnss_velocity_latency"].value("used_s", 0.0) != 0) {
    all.latency = true;
    const double ms = 1e3 * ex["gnss_velocity_latency"]["used_s"].get<double>();
    test("fix velocity latency", "(" + fmt(ms, 3) + " ms)", ms, LoggerOff{false, true});
  }
  if (!all.any()) return;
  const FilterRun& none = without(all);
  for (int k = 0; k < 2; ++k) run.conditions.without_logger[k] = innovation_conditions(none.x[k]);
  if (none.result.extra.contains("adaptive_noise")) {
    run.conditions.without_scale_max = none.result.extra["adaptive_noise"].value("scale_max", 1.0);
    run.conditions.without_scale_end = none.result.extra["adaptive_noise"].value("scale_end", 1.0);
  }
  run.conditions.logger_compared = true;
}

}  // namespace

GnssDiagRun run_gnss_diagnosis(const std::string& dir, const DriveCoeffs* coeffs, const std::string& device_class) {
  GnssDiagRun run;
  const std::clock_t c0 = std::clock();
  run.dir = dir;
  run.device_class = device_class;
  run.meta = read_meta(dir);
  const std::string mf = (std::filesystem::path(dir) / "meta.json").string();
  if (!run.meta.mounting) throw InputError(mf, 0, "mounting", "a drive recording needs a mounting (the antenna lever arm)");
  run.coeffs_given = coeffs != nullptr;
  if (coeffs) run.current = coeffs->set;
  else run.current.device = run.meta.device;
  const auto& rows = candidate_rows();
  std::vector<int> idx;  // hypotheses tested → row
  std::vector<int> nparams;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    GnssHypothesis h{rows[k].name, rows[k].term, rows[k].nparams, true, ""};
    if (rows[k].needs_coeffs && !coeffs) {
      h.tested = false;
      h.why_not = rows[k].profiled
                      ? "needs --coeffs: the effect is compensated on the IMU samples through the given coefficients"
                      : "needs --coeffs: without given coefficients the filter fits the scale on the drive (nothing to differ from)";
    } else {
      idx.push_back(static_cast<int>(k));
      nparams.push_back(rows[k].nparams);
    }
    run.hypotheses.push_back(h);
  }
  int profiled = -1;  // hypothesis index of the profiled candidate
  for (std::size_t h = 0; h < idx.size(); ++h)
    if (rows[idx[h]].profiled) profiled = static_cast<int>(h);
  // Every filter run, by model, profiled θ and the logger terms left out (LoggerOff::key, 0: none).
  std::map<std::tuple<std::vector<int>, std::vector<double>, int>, FilterRun> runs;
  std::map<std::vector<int>, ProfileFit> profiles;  // per model with the profiled candidate
  auto run_filter = [&](const std::vector<int>& model, const std::vector<double>& theta, const LoggerOff& logger_off = {}) -> const FilterRun& {
    const auto key = std::make_tuple(model, theta, logger_off.key());
    const auto it = runs.find(key);
    if (it != runs.end()) return it->second;
    FitDriveArgs a;
    a.dir = dir;
    a.aiding = "gnss";
    a.obs_given = false;
    a.device_class = device_class;
    a.qc = false;
    a.write_out = false;
    a.outages.enabled = false;
    if (logger_off.timing) a.sample_time = "off";
    if (logger_off.latency) a.gnss_vel_latency = "off";
    if (coeffs) {
      a.coeffs = coeffs->file;
      a.coeffs_set = coeffs->set;
      if (!theta.empty()) {
        EffectTerms e = coeffs->carried, sg;
        for (std::size_t p = 0; p < theta.size(); ++p) rows[idx[profiled]].term.add_param(e, static_cast<int>(p), theta[p]);
        nlohmann::json& x = a.coeffs_set->extra;
        for (const auto& k : effect_json_keys()) x.erase(k);
        effects_to_json(e, sg, x);
      }
    }
    for (std::size_t h = 0; h < idx.size(); ++h) {
      const bool on = std::find(model.begin(), model.end(), static_cast<int>(h)) != model.end();
      rows[idx[h]].configure(a, on);
    }
    FilterRun fr;
    a.on_innovation = [&](int type, const inmotion::InnovationRecord& r) {
      if (type < 2) fr.x[type].push_back(innovation_sample(r));
    };
    fr.result = fit_drive(a);
    return runs[key] = std::move(fr);
  };
  // A model's run: with the profiled candidate at its profile's θ̂ when the model holds it.
  auto filter = [&](const std::vector<int>& model) -> const FilterRun& {
    if (profiled < 0 || std::find(model.begin(), model.end(), profiled) == model.end()) return run_filter(model, {});
    auto pit = profiles.find(model);
    if (pit == profiles.end()) {
      std::vector<int> others;
      for (int h : model)
        if (h != profiled) others.push_back(h);
      const CandidateRow& row = rows[idx[profiled]];
      const ProfileFit pf = profile_quadratic(row.nparams, row.step, [&](const Eigen::VectorXd& t) {
        return t.isZero() ? deviance_of(run_filter(others, {})) : deviance_of(run_filter(others, std::vector<double>(t.data(), t.data() + t.size())));
      });
      pit = profiles.emplace(model, pf).first;
    }
    const ProfileFit& pf = pit->second;
    if (!pf.ok) return run_filter(model, std::vector<double>(static_cast<std::size_t>(rows[idx[profiled]].nparams), 0.0));
    return run_filter(model, std::vector<double>(pf.theta.data(), pf.theta.data() + pf.theta.size()));
  };
  const FilterRun& base = filter({});
  for (const char* k : {"sample_timing", "gnss_velocity_latency", "adaptive_noise"})
    if (base.result.extra.contains(k)) run.logger[k] = base.result.extra[k];
  run.epochs = static_cast<long>(base.x[0].size() + base.x[1].size());
  run.rows = 3 * run.epochs;
  if (base.x[0].empty())
    throw InputError((std::filesystem::path(dir) / "gnss.csv").string(), 0, "", "the GNSS-aided filter took no fix: nothing to diagnose");
  logger_tests(run, base, [&](const LoggerOff& off) -> const FilterRun& { return run_filter({}, {}, off); });
  DriveDiagnoseOptions opt;
  GreedyPolicy policy = diag::search_policy(opt);
  run.search = hypothesis_search(nparams, run.rows, policy, [&](const std::vector<int>& m) { return deviance_of(filter(m)); });
  // Overdispersed innovations (not white, or NIS/dof above 1: a model error the candidates do not
  // cover, as on the real walk): each accepted candidate's Δχ² in the final model is divided by the
  // worse observation type's φ and must still pass, else it is withdrawn (overdispersed).
  std::vector<int> final_model;
  for (;;) {
    final_model = run.search.model;
    std::sort(final_model.begin(), final_model.end());
    if (final_model.empty()) break;
    const FilterRun& f = filter(final_model);
    run.phi = phi_of(f);
    std::size_t weakest = 0;
    for (std::size_t k = 1; k < run.search.steps.size(); ++k)
      if (run.search.steps[k].dchi2_final < run.search.steps[weakest].dchi2_final) weakest = k;
    if (run.search.steps[weakest].dchi2_final / run.phi >= policy.min_delta_chi2) break;
    run.overdispersed.push_back(run.search.steps[weakest]);
    run.overdispersed_phi.push_back(run.phi);
    run.search.model.erase(run.search.model.begin() + static_cast<long>(weakest));
    run.search.steps.erase(run.search.steps.begin() + static_cast<long>(weakest));
  }
  const FilterRun& fin = filter(final_model);
  // φ of the final model: when every candidate was withdrawn, that is the base filter's (not the φ of
  // the last model the withdrawal was judged in).
  run.phi = phi_of(fin);

  // Findings: the final model's estimates, with the Δχ² that accepted each.
  run.improved = run.current;
  run.improved.device = run.current.device.serial.empty() ? run.meta.device : run.current.device;
  DiagnoseResult& r = run.core;
  r.improved = run.current.errors;
  if (coeffs) r.improved_terms = coeffs->carried;  // the filter ran with them compensated: estimates add to them
  if (!coeffs)  // b and M: none given, and the filter's fit of them on this drive is not a calibration: not known
    for (TriadErrors* te : {&r.improved.gyro, &r.improved.accel}) {
      te->sigma_bias.setConstant(kUnknownSigma);
      te->sigma_M.setConstant(kUnknownSigma);
    }
  for (std::size_t s = 0; s < run.search.model.size(); ++s) {
    const int h = run.search.model[s];
    const CandidateRow& row = rows[idx[h]];
    const HypothesisStep& step = run.search.steps[s];
    std::vector<double> v, sg;
    if (row.profiled) {
      const ProfileFit& pf = profiles.at(final_model);
      for (int p = 0; p < row.term.nparams(); ++p) {
        v.push_back(p < row.nparams ? pf.theta(p) : 0.0);
        sg.push_back(p < row.nparams ? pf.sigma(p) : std::numeric_limits<double>::quiet_NaN());
      }
    } else {
      row.read(fin.result, run.current, v, sg);
    }
    auto finding = [&](const Term& t, std::vector<double> value, std::vector<double> sigma) {
      DiagFinding f;
      f.term = t;
      f.value = std::move(value);
      f.sigma = std::move(sigma);
      f.unit = term_unit(t);
      f.delta_chi2 = step.dchi2;
      f.delta_chi2_final = step.dchi2_final;
      f.delta_bic = step.dbic;
      f.report_sensor = t.sensor;
      f.report_axis = t.axis;
      f.explained_fraction = std::numeric_limits<double>::quiet_NaN();  // no per-axis residual here
      f.remainder_is_noise = run.remainder_is_noise();
      f.status = f.remainder_is_noise ? "established" : "partial";
      r.findings.push_back(f);
    };
    if (row.term.effect == EffectId::scale_factor) {
      // A triad's scale moved: a finding per axis beyond 3σ (at least the most significant one),
      // folded into M as the drive diagnosis does.
      const int sensor = row.term.sensor;
      int best = 0;
      for (int i = 1; i < 3; ++i)
        if (std::abs(v[i]) / sg[i] > std::abs(v[best]) / sg[best]) best = i;
      TriadErrors& te = sensor == 0 ? r.improved.gyro : r.improved.accel;
      for (int i = 0; i < 3; ++i) {
        if (i != best && !(std::abs(v[i]) >= 3 * sg[i])) continue;
        finding({EffectId::scale_factor, sensor, i}, {v[i]}, {sg[i]});
        te.M(i, i) += v[i];
        te.sigma_M(i, i) = sg[i];
      }
      continue;
    }
    if (row.term.effect == EffectId::lever_arm) {
      // RESULT.json gives the correction in reference body axes; the registry's lever arm (and the
      // accelerometer compensation of IMPROVED.json) is in IMU axes: r_m = C_mbᵀ r_b, σ propagated
      // without the (unreported) cross-covariances.
      const Mat3 C_bm = ins::dcm_from_rpy(run.meta.mounting->rpy_deg * units::kDeg).transpose();
      const Vec3 rb(v[0], v[1], v[2]);
      const Vec3 rm = C_bm * rb, sb(sg[0], sg[1], sg[2]);
      for (int i = 0; i < 3; ++i) {
        double var = 0;
        for (int j = 0; j < 3; ++j) var += C_bm(i, j) * C_bm(i, j) * sb(j) * sb(j);
        v[i] = rm(i);
        sg[i] = std::sqrt(var);
      }
    }
    finding(row.term, v, sg);
    for (int p = 0; p < row.term.nparams(); ++p) {
      row.term.add_param(r.improved_terms, p, v[p]);
      if (std::isfinite(sg[p])) row.term.add_param(r.terms_sigma, p, sg[p]);
    }
  }
  for (const auto& [list, why] : {std::pair{&run.search.withdrawn, WithdrawnWhy::weak}, std::pair{&run.overdispersed, WithdrawnWhy::overdispersed}})
    for (std::size_t i = 0; i < list->size(); ++i) {
      const HypothesisStep& w = (*list)[i];
      DiagWithdrawn x;
      x.term = rows[idx[w.candidate]].term;
      x.delta_chi2_when_accepted = w.dchi2;
      // an overdispersed one: against the φ of the model it was judged in
      x.delta_chi2_final = why == WithdrawnWhy::overdispersed ? w.dchi2_final / run.overdispersed_phi[i] : w.dchi2_final;
      x.why = why;
      r.withdrawn.push_back(x);
    }
  run.improved.errors = r.improved;
  nlohmann::json added = nlohmann::json::array();
  for (const auto& f : r.findings) added.push_back(f.term.label());
  diagnose_out::improved_extra(run.improved.extra, r,
                               {{"effects_added", added}, {"recording_kind", "drive"}, {"aiding", "gnss"},
                                {"note", "GNSS-only drive: the effects found by the aided filter's innovations against the fixes "
                                         "(docs/diagnosis.md, GNSS-only drives)"}});

  // Innovations of the base filter and of the final model.
  DriveInnovations& in = run.innovations;
  in.compared = !final_model.empty();
  for (int k = 0; k < 2; ++k) {
    in.before[k] = innovation_stats(base.x[k], nullptr);
    in.after[k] = innovation_stats(fin.x[k], nullptr);
    run.conditions.base[k] = innovation_conditions(base.x[k]);
    run.conditions.final_model[k] = innovation_conditions(fin.x[k]);
  }
  run.cpu_s = in.cpu_s = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  return run;
}

nlohmann::json gnss_diagnosis_json(const GnssDiagRun& run) {
  using namespace diagnose_out;
  const DiagnoseResult& r = run.core;
  nlohmann::json j;
  j["kind"] = "drive";
  j["aiding"] = "gnss";
  j["method"] = "GNSS-only drive: each candidate is a hypothesis of the GNSS-aided in-motion filter (fit drive --aiding gnss), "
                "judged by the generalised likelihood ratio of its innovations against the fixes (Δχ² = Δ Σ νᵀS⁻¹ν + ln det S), "
                "greedy, Δχ² ≥ 40 and ΔBIC > 0, backward check in the final model";
  nlohmann::json fs = nlohmann::json::array();
  for (const DiagFinding& f : r.findings) {
    nlohmann::json x = finding_head_json(f);
    x["evidence"] = {{"delta_chi2", f.delta_chi2}, {"delta_bic", f.delta_bic}, {"overdispersion_phi", run.phi},
                     {"delta_chi2_final", f.delta_chi2_final}, {"delta_chi2_final_over_phi", f.delta_chi2_final / run.phi}, {"source", "innovations against the GNSS fixes"}};
    not_established(f, x);
    x["explained_fraction"] = nullptr;  // innovations, not a per-axis residual
    x["sentence"] = gnss_finding_sentence(f, run.phi);
    fs.push_back(x);
  }
  j["findings"] = fs;
  j["withdrawn"] = withdrawn_json(r.withdrawn);
  nlohmann::json hs = nlohmann::json::array();
  for (std::size_t k = 0, t = 0; k < run.hypotheses.size(); ++k) {
    const GnssHypothesis& h = run.hypotheses[k];
    nlohmann::json x = {{"name", h.name}, {"params", h.nparams}, {"tested", h.tested}};
    if (!h.tested) x["why_not"] = h.why_not;
    else {
      if (t < run.search.first_round_dchi2.size()) x["delta_chi2_vs_base"] = run.search.first_round_dchi2[t];
      ++t;
    }
    hs.push_back(x);
  }
  j["hypotheses"] = hs;
  j["search"] = {{"base_deviance", run.search.base_deviance}, {"final_deviance", run.search.final_deviance},
                 {"filter_runs", run.search.evaluations}, {"overdispersion_phi", run.phi}, {"innovation_epochs", run.epochs}, {"rows", run.rows},
                 {"min_delta_chi2", DriveDiagnoseOptions{}.min_delta_chi2}};
  j["coefficients_tested"] = run.coeffs_given ? "given (scale tested against them)" : "none given: the filter fits b and M on this drive";
  j["mounting"] = {{"tested_rpy_deg", to_json(run.meta.mounting->rpy_deg)},
                   {"lever_arm_m", to_json(run.meta.mounting->lever_arm_m)},
                   {"source", "meta.json (nominal; the lever arm is the MEMS relative to the GNSS antenna)"}};
  nlohmann::json inn;
  inn["method"] = "GNSS-aided in-motion filter (obs pos,vel of the fixes); before: the base model, after: the final one";
  inn["compared"] = run.innovations.compared;
  inn["cpu_s"] = run.cpu_s;
  for (int k = 0; k < 2; ++k)
    inn[inmotion::obs_type_name(k)] = {{"before", innovation_stats_json(run.innovations.before[k])},
                        {"after", innovation_stats_json(run.innovations.after[k])},
                        {"sentence", innovation_sentence(k, run.innovations)}};
  j["innovations"] = inn;
  j["logger"] = run.logger;
  j["conditions"] = gnss_conditions_json(run);
  return j;
}

// The logger and receiver properties every run of the diagnosis modelled, as fit drive measured
// them, and where the base filter needed its noise raised (issue 53, items 1 and 5).
std::string logger_sentence(const nlohmann::json& l) {
  std::ostringstream o;
  if (l.contains("sample_timing") && l["sample_timing"].value("scanned", false)) {
    const auto& st = l["sample_timing"];
    o << "logger (measured, modelled in every run): IMU stamp scatter σ " << fmt(st["sigma_ms"].get<double>(), 3)
      << " ms about the sensor's clock (" << st["repeated_rows"].get<long>() << " of " << st["rows"].get<long>()
      << " rows repeated reads";
    if (applied_logger_correction(st).drop_repeats) o << ", dropped";
    o << ")";
    if (l.contains("gnss_velocity_latency")) {
      const auto& g = l["gnss_velocity_latency"];
      o << "; the fix velocity " << fmt(1e3 * g["used_s"].get<double>(), 3) << " ms late ("
        << (g.value("established", false) ? "measured" : "not established: taken at its stamp") << ")";
    }
    o << "\n";
  }
  if (l.contains("adaptive_noise") && l["adaptive_noise"].value("scale_max", 1.0) > 1) {
    const auto& an = l["adaptive_noise"];
    o << "base filter's navigation noise: scaled up to x" << fmt(an["scale_max"].get<double>(), 3) << ", x"
      << fmt(an["scale_end"].get<double>(), 3) << " at the end";
    int n = 0;
    for (const auto& e : an.value("events", nlohmann::json::array()))
      if (e["to"].get<double>() > e["from"].get<double>() && n++ < 4)
        o << (n == 1 ? "; raised at " : ", ") << fmt(e["t_s"].get<double>(), 4) << " s (" << e["observation"].get<std::string>()
          << ", NIS/dof " << fmt(e["nis_per_dof"].get<double>(), 3) << ", " << fmt(e.value("speed_m_s", 0.0), 2) << " m/s, turning "
          << fmt(e.value("turn_rate_deg_s", 0.0), 2) << " °/s, " << fmt(e.value("accel_m_s2", 0.0), 2) << " m/s²)";
    o << (an.value("failed", false) ? " — above the fail scale at the end: the IMU did not carry the navigation\n" : "\n");
  }
  return o.str();
}

std::string gnss_diagnosis_text(const GnssDiagRun& run) {
  using namespace diagnose_out;
  const DiagnoseResult& r = run.core;
  std::ostringstream o;
  o << "GNSS-only drive: " << run.epochs << " innovation epochs (position and velocity fixes); evidence: the GNSS-aided "
    << "filter's innovations, " << run.search.evaluations << " filter runs; coefficients tested: "
    << (run.coeffs_given ? "given" : "none (b and M fitted by the filter)") << "\n";
  o << "hypotheses (Δχ² against the base filter; a finding needs ≥ " << fmt(DriveDiagnoseOptions{}.min_delta_chi2)
    << " and ΔBIC > 0):";
  for (std::size_t k = 0, t = 0; k < run.hypotheses.size(); ++k) {
    const GnssHypothesis& h = run.hypotheses[k];
    o << (k ? "; " : " ") << h.name << " ";
    if (!h.tested) o << "not tested (needs --coeffs)";
    else o << fmt(t < run.search.first_round_dchi2.size() ? run.search.first_round_dchi2[t] : 0.0), ++t;
  }
  o << "\n";
  if (r.findings.empty()) o << "no finding: no hypothesis explains the innovations better than the base filter by the threshold\n";
  for (const DiagFinding& f : r.findings) o << "* " << gnss_finding_sentence(f, run.phi) << "\n";
  if (!run.remainder_is_noise())
    o << "! the innovations of the final model are overdispersed (φ " << fmt(run.phi)
      << ": not white or NIS/dof above 1): the Δχ² were divided by φ before the threshold; the σ are the filter's and "
         "do not include it (scale them by √φ ≈ " << fmt(std::sqrt(run.phi), 2) << " for a conservative figure)\n";
  for (const auto& w : r.withdrawn) o << withdrawn_text(w) << "\n";
  o << "in-motion filter innovations (GNSS-aided; " << (run.innovations.compared ? "base → final model" : "no finding")
    << ", " << fmt(run.cpu_s, 2) << " s CPU):\n";
  for (int k = 0; k < 2; ++k) o << "  " << innovation_sentence(k, run.innovations) << "\n";
  o << logger_sentence(run.logger);
  o << gnss_conditions_text(run);
  return o.str();
}

}  // namespace calbench
