// The IEEE model-equation terms of the catalogue (issue 20; docs/effect-catalogue.md): each injected
// concealed (apply_inject_option, as `simulate bench --inject`) on a plan that excites it, on two
// axes, must be named with the right sensor and axis, its value within 20 %, the residual cut ≥ 80 %.
// Where the plan cannot tell two shapes apart the finding must list both and carry no σ; a term the
// plan cannot excite must be reported as such and never named. The full sweep (≥ 3 magnitudes × 5
// seeds) and the confusion table are bench/diagnose/sweep.sh and confusion.sh.
#include <gtest/gtest.h>

#include <cmath>

#include "bench/diagnose/diagnose_run.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "bench/io/plan_toml.hpp"

namespace calbench {
namespace {

const BenchPlan& plan(const char* name) {
  static const BenchPlan diag = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/diagnose.toml");
  static const BenchPlan factory = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/factory.toml");
  static const BenchPlan wedge = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/wedge.toml");
  const std::string n = name;
  return n == "factory" ? factory : n == "wedge" ? wedge : diag;
}

std::string summary(const DiagRun& r) {
  std::string s;
  for (const auto& f : r.result.findings) s += "\n  " + f.term.label() + ": " + finding_sentence(f);
  return s.empty() ? " (no finding)" : s;
}

DiagRun run(const char* plan_name, const std::string& inject, std::uint64_t seed) {
  BenchSimOptions so;
  so.seed = seed;
  apply_inject_option(inject, so.effects);
  const DiagInput in = simulate_diag_input(plan(plan_name), draw_random_unit(600 + seed), so);
  return run_diagnosis(in, nullptr, plan(plan_name).table);
}

const DiagFinding* named(const DiagRun& r, EffectId e) {
  for (const auto& f : r.result.findings)
    if (f.term.effect == e) return &f;
  return nullptr;
}

struct Case {
  const char* plan;
  const char* inject;
  EffectId effect;
  int sensor, axis, param;
  double value;
};

// Named alone, right place, within 20 %, cut ≥ 80 %, told apart (no alternative, σ given).
TEST(DiagnoseModelTerms, NamedOnTwoAxes) {
  const Case cases[] = {
      {"diagnose", "scale_k2:sensor=accel,axis=y,value=6e-5", EffectId::scale_k2, 1, 1, 0, 6e-5},
      {"diagnose", "scale_k2:sensor=accel,axis=z,value=-6e-5", EffectId::scale_k2, 1, 2, 0, -6e-5},
      {"diagnose", "g2_sensitivity:axis=y,term=xy,value=8e-6", EffectId::g2_sensitivity, 0, 1, 2, 8e-6},
      {"diagnose", "g2_sensitivity:axis=z,term=yz,value=-8e-6", EffectId::g2_sensitivity, 0, 2, 3, -8e-6},
      {"diagnose", "cross_coupling:sensor=accel,axis=x,with=y,value=8e-5", EffectId::cross_coupling, 1, 0, 0, 8e-5},
      {"diagnose", "cross_coupling:sensor=accel,axis=z,with=y,value=-8e-5", EffectId::cross_coupling, 1, 2, 1, -8e-5},
      {"diagnose", "cross_axis_rate:axis=x,with=y,value=2e-5", EffectId::cross_axis_rate, 0, 0, 0, 2e-5},
      {"diagnose", "cross_axis_rate:axis=z,with=y,value=-2e-5", EffectId::cross_axis_rate, 0, 2, 1, -2e-5},
      // Gyro cross-coupling ω_i·ω_j: rates about the face diagonals (45° wedge fixture).
      {"wedge", "cross_coupling:sensor=gyro,axis=x,with=y,value=2e-5", EffectId::cross_coupling, 0, 0, 0, 2e-5},
      {"wedge", "cross_coupling:sensor=gyro,axis=z,with=x,value=-2e-5", EffectId::cross_coupling, 0, 2, 0, -2e-5},
      // An accelerometer's proof mass off the origin across its axis: ω_i·ω_j·r_ij on the diagonals.
      {"wedge", "proof_mass_offset:axis=y,with=z,value=4e-4", EffectId::proof_mass_offset, 1, 1, 0, 4e-4},
      {"wedge", "proof_mass_offset:axis=z,with=y,value=-4e-4", EffectId::proof_mass_offset, 1, 2, 1, -4e-4},
      // The wedge plan tells the size effect from a lever arm (named alone, no alternative).
      {"wedge", "size_effect:axis=y,value=2e-3", EffectId::size_effect, 1, 1, 0, 2e-3},
  };
  std::uint64_t seed = 71;
  for (const Case& c : cases) {
    const DiagRun r = run(c.plan, c.inject, ++seed);
    const DiagFinding* f = named(r, c.effect);
    ASSERT_NE(f, nullptr) << c.inject << summary(r);
    EXPECT_EQ(r.result.findings.size(), 1u) << c.inject << summary(r);
    EXPECT_EQ(f->report_sensor, c.sensor) << c.inject << summary(r);
    EXPECT_EQ(f->report_axis, c.axis) << c.inject << summary(r);
    EXPECT_NEAR(f->value[c.param], c.value, 0.2 * std::abs(c.value)) << c.inject << summary(r);
    EXPECT_GT(f->rms_before, 0.0) << c.inject;
    EXPECT_LE(f->rms_after, 0.2 * f->rms_before) << c.inject << summary(r);
    EXPECT_TRUE(f->alternatives.empty()) << c.inject << summary(r);
    // Issue 36: a catalogue term named alone and cutting ≥ 80 % stays established.
    EXPECT_STREQ(f->status, "established") << c.inject << summary(r);
    std::printf("%s: %s value %.4g ± %.2g, rms %.3g → %.3g\n", c.inject, f->term.label().c_str(), f->value[c.param],
                f->sigma[c.param], f->rms_before, f->rms_after);
  }
}

// x³ and x·|x| correlate 0.994 after the scale factor over ±20…300 °/s: whichever is named lists
// the other as not told apart, and the sentence carries no σ.
TEST(DiagnoseModelTerms, CubicAndOddQuadraticAreAlternatives) {
  const DiagRun r = run("factory", "scale_k3:sensor=gyro,axis=z,value=2e-5", 81);
  ASSERT_EQ(r.result.findings.size(), 1u) << summary(r);
  const DiagFinding& f = r.result.findings[0];
  EXPECT_EQ(f.report_sensor, 0);
  EXPECT_EQ(f.report_axis, 2);
  const EffectId other = f.term.effect == EffectId::scale_k3 ? EffectId::scale_nonlinearity : EffectId::scale_k3;
  ASSERT_TRUE(f.term.effect == EffectId::scale_k3 || f.term.effect == EffectId::scale_nonlinearity) << summary(r);
  bool listed = false;
  for (const auto& a : f.alternatives) listed = listed || (a.term.effect == other && a.term.axis == 2);
  EXPECT_TRUE(listed) << summary(r);
  EXPECT_EQ(finding_sentence(f).find(" ± "), std::string::npos) << finding_sentence(f);
  if (f.term.effect == EffectId::scale_k3) EXPECT_NEAR(f.value[0], 2e-5, 0.2 * 2e-5) << summary(r);
}

// The size effect of one accelerometer is, within constant-rate steps, a lever arm along that axis:
// the established lever arm is named and the size effect listed as not told apart.
TEST(DiagnoseModelTerms, SizeEffectIsALeverArmLookAlike) {
  const DiagRun r = run("diagnose", "size_effect:axis=x,value=0.006", 91);
  const DiagFinding* f = named(r, EffectId::lever_arm);
  ASSERT_NE(f, nullptr) << summary(r);
  EXPECT_NEAR(f->value[0], 0.006, 0.2 * 0.006) << summary(r);
  bool listed = false;
  for (const auto& a : f->alternatives) listed = listed || (a.term.effect == EffectId::size_effect && a.term.axis == 0);
  EXPECT_TRUE(listed) << summary(r);
}

// Gyro cross-coupling needs rates about two axes at once, which the diagnosis plan does not have
// (bench/plans/wedge.toml has): there it is not a candidate, it is reported as not excited, with
// the plan that excites it, and injected it is never named with a σ.
TEST(DiagnoseModelTerms, NotExcitedIsReportedAndNeverNamed) {
  const DiagRun r = run("diagnose", "cross_coupling:sensor=gyro,axis=x,with=y,value=1e-3", 95);
  int listed = 0;
  for (const auto& n : r.result.not_excited) listed += n.term.effect == EffectId::cross_coupling && n.term.sensor == 0;
  EXPECT_EQ(listed, 3) << summary(r);
  EXPECT_EQ(named(r, EffectId::cross_coupling), nullptr) << summary(r);
  EXPECT_NE(diagnosis_text(r).find("not excited by this recording"), std::string::npos);
  EXPECT_NE(diagnosis_text(r).find("wedge.toml"), std::string::npos) << diagnosis_text(r);
}

// Temperature or drift, by likelihood: on a 5 → 45 °C ramp a temperature bias explains the record
// better than a drift of the triad with its own σ, τ, and the finding says so.
TEST(DiagnoseModelTerms, TemperatureOrDriftDecidedByLikelihood) {
  static const BenchPlan thermal = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/tests/data/thermal_short.toml");
  BenchSimOptions so;
  so.seed = 12;
  apply_inject_option("temperature_bias:sensor=gyro,axis=z,value=2e-5", so.effects);
  const DiagRun r = run_diagnosis(simulate_diag_input(thermal, draw_random_unit(612), so), nullptr, thermal.table);
  const DiagFinding* f = named(r, EffectId::temperature_bias);
  ASSERT_NE(f, nullptr) << summary(r);
  ASSERT_TRUE(f->versus_drift.tested);
  EXPECT_GE(f->versus_drift.delta_score, 10.0) << summary(r);
  EXPECT_STREQ(f->versus_drift.verdict, "temperature");
  EXPECT_NE(finding_sentence(*f).find("in favour of the temperature term"), std::string::npos);
}

}  // namespace
}  // namespace calbench
