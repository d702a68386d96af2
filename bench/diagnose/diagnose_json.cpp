#include <cmath>

#include "calibration/inmotion/obs_names.hpp"
#include "bench/diagnose/diagnose_run.hpp"
#include "bench/diagnose/diagnose_text.hpp"
#include "bench/diagnose/drive_run.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "bench/diagnose/finding_text.hpp"
#include "bench/io/json_util.hpp"

// The --json documents of `calbench diagnose`, bench and drive (docs/diagnosis.md: JSON schema).

namespace calbench {

namespace {
// The candidates a recording cannot excite (DiagnoseResult::not_excited).
nlohmann::json not_excited_json(const std::vector<NotExcited>& v) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& n : v) {
    const EffectSpec& x = effect_spec(n.term.effect);
    out.push_back({{"effect", x.key},
                   {"label", n.term.label()},
                   {"sigma_over_plausible", std::isfinite(n.sigma_ratio) ? nlohmann::json(n.sigma_ratio) : nlohmann::json(nullptr)},
                   {"needs", effect_excited_by(x)}});
  }
  return out;
}
// What the drift model absorbed on one axis (DiagDriftExcess), SI: in drift_excess[] and axes.*.drift.
nlohmann::json drift_figures_json(const DiagDriftExcess& x) {
  nlohmann::json j = {{"change", x.change},   {"class_stability", x.stability}, {"ratio", x.change / x.stability},
                      {"null_mean", x.null_mean}, {"null_sd", x.null_sd},       {"z", x.z},
                      {"null_exceed", x.null_exceed_count >= 0 ? nlohmann::json(x.null_exceed()) : nlohmann::json(nullptr)},
                      {"gain", x.gain},       {"drift_sigma", x.sigma},         {"drift_tau_s", x.tau_s}};
  if (x.has_temperature)
    j["temperature"] = {{"change_c", x.temperature_change},
                        {"r", x.temperature_r},
                        {"per_degree", x.per_degree},
                        {"follows", x.follows_temperature},
                        {"term_dchi2", x.temperature_dchi2},
                        {"term_coef", x.temperature_coef},
                        {"term_coef_sigma", x.temperature_coef_sigma}};
  return j;
}

}  // namespace

namespace diagnose_out {

void finding_value_json(const DiagFinding& f, nlohmann::json& value, nlohmann::json& sigma) {
  if (f.value.size() == 1) {
    value = f.value[0];
    sigma = std::isfinite(f.sigma[0]) ? nlohmann::json(f.sigma[0]) : nlohmann::json(nullptr);
  } else {
    value = f.value;
    sigma = f.sigma;
  }
}

nlohmann::json finding_head_json(const DiagFinding& f) {
  nlohmann::json x;
  x["effect"] = effect_name(f.term.effect);
  x["sensor"] = kSensor[f.term.sensor];
  x["axis"] = f.report_axis >= 0 ? kAxis[f.report_axis] : "all";
  finding_value_json(f, x["value"], x["sigma"]);
  x["unit"] = f.unit;
  return x;
}

nlohmann::json finding_evidence_json(const DiagFinding& f) {
  nlohmann::json ev = {{"delta_chi2", f.delta_chi2},
                       {"delta_bic", f.delta_bic},
                       {"heldout_delta_chi2", f.heldout_delta_chi2},
                       {"revealing_condition", f.condition},
                       {"correlation_before", f.condition_r}};
  if (effect_spec(f.term.effect).shape == EffectShape::noise) add_drift_tau_evidence(f, ev);
  ev["indistinguishable_from"] = alternatives_json(f);
  if (f.versus_drift.tested)
    ev["versus_drift"] = {{"delta_score", f.versus_drift.delta_score},
                          {"drift_sigma", f.versus_drift.drift_sigma},
                          {"drift_tau_s", f.versus_drift.drift_tau_s},
                          {"verdict", f.versus_drift.verdict}};
  return ev;
}

nlohmann::json correlations_json(const std::vector<ConditionCorrelation>& c, std::size_t most) {
  nlohmann::json j = nlohmann::json::array();
  for (std::size_t k = 0; k < c.size() && k < most; ++k) j.push_back({{"condition", c[k].condition}, {"r", c[k].r}});
  return j;
}

// A finding the recording cannot tell from an alternative is not established: no σ, as if it were.
void not_established(const DiagFinding& f, nlohmann::json& j) {
  // Issue 36: established only when told apart, cutting ≥ established_cut of its axis's systematic
  // residual and leaving a noise-like remainder; "partial" findings carry the fraction they explain.
  const bool established = f.told_apart() && std::string(f.status) == "established";
  j["established"] = established;
  j["status"] = established || f.told_apart() ? f.status : "not told apart";
  j["explained_fraction"] = f.explained_fraction;
  j["remainder_is_noise"] = f.remainder_is_noise;
  if (!f.told_apart()) j["sigma"] = nullptr;
}

void improved_extra(nlohmann::json& extra, const DiagnoseResult& r, const nlohmann::json& diagnosis) {
  for (const auto& k : effect_json_keys()) extra.erase(k);
  effects_to_json(r.improved_terms, r.terms_sigma, extra);
  extra["diagnosis"] = diagnosis;
  // Every term the set carries with the status the diagnosis gave it: a term that is not established
  // (not told apart, partial) fits this recording but is not proven; whoever applies the set to other
  // conditions reads it here.
  nlohmann::json st = nlohmann::json::array();
  for (const auto& f : r.findings) {
    nlohmann::json x = {{"effect", effect_name(f.term.effect)}, {"term", f.term.label()}};
    not_established(f, x);
    x.erase("sigma");
    st.push_back(x);
  }
  extra["diagnosis"]["finding_status"] = st;
}

}  // namespace diagnose_out

using namespace diagnose_out;

nlohmann::json diagnosis_json(const DiagRun& run) {
  const DiagnoseResult& r = run.result;
  nlohmann::json findings = nlohmann::json::array();
  for (const auto& f : r.findings) {
    nlohmann::json v, s;
    finding_value_json(f, v, s);
    const int ai = finding_axis_index(f, r);
    nlohmann::json ev = finding_evidence_json(f);
    ev["ljung_box_p_before"] = r.before[ai].ljung_box_p;
    ev["ljung_box_p_after"] = r.after[ai].ljung_box_p;
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
    not_established(f, findings.back());
  }
  nlohmann::json unexplained = nlohmann::json::array();
  for (const auto& u : r.unexplained) {
    const nlohmann::json corr = correlations_json(u.correlations, u.correlations.size());
    unexplained.push_back({{"sensor", kSensor[u.sensor]},
                           {"axis", kAxis[u.axis]},
                           {"chi2_per_dof", u.chi2_dof},
                           {"within_step_chi2_per_dof", u.high_chi2_dof},
                           {"ljung_box_p", u.ljung_box_p},
                           {"step_offset_p", u.step_p},
                           {"step_offset_family", u.step_family},
                           {"systematic_rms", u.systematic_rms},
                           {"worst_steps", u.worst_steps},
                           {"correlations", corr},
                           {"angle_harmonic", u.angle_harmonic},
                           {"angle_harmonic_amplitude", u.angle_harmonic_amp}});
    if (std::isfinite(u.angle_bin_deg[0]))
      unexplained.back()["angle_bin"] = {{"from_deg", u.angle_bin_deg[0]}, {"to_deg", u.angle_bin_deg[1]},
                                         {"mean", u.angle_bin_mean}, {"z", u.angle_bin_z}};
    if (u.period_hz > 0) unexplained.back()["periodic"] = {{"hz", u.period_hz}, {"amplitude", u.period_amp}};
  }
  nlohmann::json saturation = nlohmann::json::array();
  for (const auto& x : r.saturation) {
    auto level = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
    saturation.push_back({{"sensor", kSensor[x.sensor]},
                          {"axis", kAxis[x.axis]},
                          {"level_positive", level(x.level_pos)},
                          {"level_negative", level(x.level_neg)},
                          {"reference_max", x.reference_max},
                          {"frozen_fraction", x.frozen_fraction},
                          {"steps_left_out", x.steps},
                          {"seconds_left_out", x.excluded_s},
                          {"sentence", saturation_sentence(x)}});
  }
  nlohmann::json low_input = nullptr;  // not tested: no gyro axis passed the screen
  if (r.low_input.tested()) {
    nlohmann::json ax = nlohmann::json::array();
    for (const auto& x : r.low_input.axes)
      ax.push_back({{"axis", kAxis[x.axis]}, {"width_grid", x.width}, {"not_sensed_up_to", x.below_max},
                    {"sensed_from", x.above_min > 0 ? nlohmann::json(x.above_min) : nlohmann::json(nullptr)},
                    {"sub_blocks", x.blocks}, {"screen_delta_chi2", x.screen_gain}});
    low_input = {{"verdict", r.low_input.verdict}, {"axes", ax}, {"delta_score", r.low_input.delta_score},
                 {"penalty", r.low_input.penalty()}, {"catalogue_would_name", r.low_input.competing},
                 {"catalogue_left_unexplained", [&] {
                    nlohmann::json u = nlohmann::json::array();
                    for (int a : r.low_input.catalogue_unexplained) u.push_back(std::string("gyro ") + kAxis[a]);
                    return u;
                  }()},
                 {"sentence", low_input_sentence(r.low_input)}};
  }
  nlohmann::json drift_excess = nlohmann::json::array();
  for (const auto& x : r.drift_excess) {
    drift_excess.push_back({{"sensor", kSensor[x.sensor]},
                            {"axis", kAxis[x.axis]},
                            {"status", x.temperature_or_drift() ? "temperature or drift, not told apart" : "drift or an effect outside the catalogue, not told apart"}});
    drift_excess.back().update(drift_figures_json(x));
    drift_excess.back()["sentence"] = drift_excess_sentence(x);
  }
  nlohmann::json drift_noted = nlohmann::json::array();
  for (const auto& x : r.drift_noted) {
    drift_noted.push_back({{"sensor", kSensor[x.sensor]},
                           {"axis", kAxis[x.axis]},
                           {"status", drift_note_temperature(x) ? "noted, not a finding: temperature or drift, not told apart"
                                                                : "noted, not a finding: drift or an effect a drift imitates, not told apart"}});
    drift_noted.back().update(drift_figures_json(x));
    drift_noted.back()["sentence"] = drift_note_sentence(x);
  }
  nlohmann::json axes = nlohmann::json::object();
  for (int a = 0; a < 6; ++a) {
    auto st = [](const AxisStats& s) {
      return nlohmann::json{{"systematic_rms", s.systematic_rms}, {"step_rms", s.step_rms}, {"within_step_rms", s.within_rms},
                            {"chi2_per_dof", s.chi2_dof},        {"within_step_chi2_per_dof", s.high_chi2_dof},
                            {"ljung_box_q", s.ljung_box_q},      {"ljung_box_p", s.ljung_box_p},
                            {"step_offset_q", s.step_q},          {"step_offset_dof", s.step_dof},
                            {"step_offset_p", s.step_p},          {"step_offset_family", s.step_family},
                            {"criterion", s.bic}};
    };
    const nlohmann::json corr = correlations_json(r.correlations_before[a], 4);
    nlohmann::json& ax = axes[std::string(kSensor[a / 3]) + "_" + kAxis[a % 3]];
    ax = {{"before", st(r.before[a])}, {"after", st(r.after[a])}, {"white_sigma_per_sample", r.white_sigma[a]},
          {"correlations_before", corr}};
    for (const auto& x : r.drift_checked)
      if (x.sensor * 3 + x.axis == a) {
        ax["drift"] = drift_figures_json(x);
        ax["drift"]["reported"] = drift_excess_reported(x);
        ax["drift"]["noted"] = drift_excess_noted(x);
      }
  }
  return {{"findings", findings},
          {"unexplained", unexplained},
          {"saturation", saturation},
          {"low_input", low_input},
          {"drift_excess", drift_excess},
          {"drift_noted", drift_noted},
          {"withdrawn", withdrawn_json(r.withdrawn)},
          {"not_excited", not_excited_json(r.not_excited)},
          {"axes", axes},
          {"coefficients_tested", run.fitted_first ? "bench fit of this recording" : "given"},
          {"noise_model", {{"gyro_drift_sigma_rad_s", r.drift_sigma[0]}, {"gyro_drift_tau_s", r.drift_tau[0]},
                           {"accel_drift_sigma_m_s2", r.drift_sigma[1]}, {"accel_drift_tau_s", r.drift_tau[1]},
                           {"device_class", run.noise_class}}},
          {"data", {{"parent_blocks", r.parents}, {"sub_blocks", r.subs}, {"data_s", r.data_s}}}};
}

namespace diagnose_out {

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

}  // namespace diagnose_out

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
    j[inmotion::obs_type_name(k)] = {{"before", innovation_stats_json(v.before[k])}, {"after", innovation_stats_json(v.after[k])},
                      {"sentence", innovation_sentence(k, v)}};
  return j;
}

nlohmann::json drive_diagnosis_json(const DriveDiagInput& in, const DriveDiagRun& run) {
  const DriveDiagnoseResult& R = run.result;
  const DiagnoseResult& r = R.core;
  nlohmann::json j;
  j["kind"] = "drive";
  nlohmann::json fs = nlohmann::json::array();
  for (std::size_t fi = 0; fi < r.findings.size(); ++fi) {
    const DiagFinding& f = r.findings[fi];
    nlohmann::json x = finding_head_json(f);
    nlohmann::json ev = finding_evidence_json(f);
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
    not_established(f, x);
    fs.push_back(x);
  }
  j["findings"] = fs;
  nlohmann::json us = nlohmann::json::array();
  for (const auto& u : r.unexplained) {
    const nlohmann::json c = correlations_json(u.correlations, u.correlations.size());
    nlohmann::json w = nlohmann::json::array();
    for (int s : u.worst_steps) w.push_back({20.0 * s, 20.0 * (s + 1)});
    us.push_back({{"sensor", kSensor[u.sensor]}, {"axis", kAxis[u.axis]}, {"chi2_per_dof", u.chi2_dof},
                  {"ljung_box_p", u.ljung_box_p}, {"systematic_rms", u.systematic_rms}, {"worst_windows_s", w},
                  {"correlations", c}});
    if (u.period_hz > 0) us.back()["periodic"] = {{"hz", u.period_hz}, {"amplitude", u.period_amp}};
    if (!u.condition_test.empty())
      us.back()["follows_condition"] = {{"condition", u.condition_test}, {"delta_chi2", u.condition_dchi2}, {"r", u.condition_r}};
  }
  j["unexplained"] = us;
  j["withdrawn"] = withdrawn_json(r.withdrawn);
  nlohmann::json axes;
  for (int a = 0; a < 6; ++a) {
    auto st = [](const AxisStats& s) {
      return nlohmann::json{{"systematic_rms", s.systematic_rms}, {"chi2_per_dof", s.chi2_dof},
                            {"ljung_box_p", s.ljung_box_p}};
    };
    const nlohmann::json cb = correlations_json(r.correlations_before[a], 5);
    const nlohmann::json ca = correlations_json(R.correlations_after[a], 5);
    axes[kAxisName[a]] = {{"before", st(r.before[a])}, {"after", st(r.after[a])},
                          {"white_sigma_per_sample", r.white_sigma[a]}, {"white_scale", R.white_scale[a]},
                          {"block_noise_sigma", R.block_noise_sigma[a]},
                          {"correlations_before", cb}, {"correlations_after", ca}};
    if (const auto& ct = R.condition_test[a]; ct.tested)
      axes[kAxisName[a]]["condition_test"] = {{"condition", ct.condition}, {"delta_chi2", ct.dchi2}, {"r", ct.r},
                                              {"level", DriveDiagnoseResult::kConditionTestLevel}};
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
  if (run.coeffs_given) {
    const BiasChange c = bias_change(r);
    nlohmann::json b = {{"unit", "rad/s (gyro), m/s² (accel)"}};
    for (int a = 0; a < 6; ++a) b[kAxisName[a]] = {{"change", c.change[a]}, {"sigma", c.sigma[a]}};
    nlohmann::json beyond = nlohmann::json::array();
    for (int a : c.beyond_3sigma) beyond.push_back(kAxisName[a]);
    b["beyond_3sigma"] = beyond;
    j["bias_since_coefficients"] = b;
  }
  j["noise_model"] = {{"gyro_drift_sigma_rad_s", r.drift_sigma[0]}, {"gyro_drift_tau_s", r.drift_tau[0]},
                      {"accel_drift_sigma_m_s2", r.drift_sigma[1]}, {"accel_drift_tau_s", r.drift_tau[1]},
                      {"device_class", run.noise_class}};
  j["data"] = {{"blocks", r.parents}, {"intervals", r.subs}, {"seconds", r.data_s},
               {"imu_rate_hz", in.data.imu_rate_hz}, {"skipped_intervals", in.data.skipped_intervals}};
  if (run.innovations || !run.innovations_skipped.empty()) j["innovations"] = drive_innovations_json(run);
  return j;
}

}  // namespace calbench
