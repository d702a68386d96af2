// Drive diagnosis on concealed effects (issue 7, docs/diagnosis.md "Drives"): drives simulated in
// memory on tests/data/drive_diag_route.toml (3.6 minutes, 200 Hz IMU, 50 Hz reference, random
// unit and mounting per seed), with one catalogue effect injected into the MEMS output while the
// diagnosis's model lacks it. No truth reaches the diagnosis: it fits b and M itself
// (no --coeffs) and predicts with the route's nominal mounting.
// Magnitudes are near this route's detection limit (docs/diagnosis.md lists it).
#include <gtest/gtest.h>

#include "bench/diagnose/drive_run.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

const std::string kRoute = std::string(CALBENCH_SOURCE_DIR) + "/tests/data/drive_diag_route.toml";

DriveDiagRun diagnose(std::uint64_t seed, const std::vector<std::string>& inject) {
  EffectTerms fx;
  for (const auto& o : inject) apply_inject_option(o, fx);
  const DriveDiagInput in = simulate_drive_diag_input(kRoute, seed, fx);
  return run_drive_diagnosis(in, nullptr);
}

struct Expect {
  EffectId effect;
  int sensor;      // as reported (term sensor: 0 gyro, 1 accel, 2 reference)
  int axis;        // −1 = all
  int param;       // which value to compare
  double value;
};

std::string describe(const DriveDiagRun& run) {
  std::string s;
  for (const auto& f : run.result.core.findings) {
    s += f.term.label() + " [";
    for (double v : f.value) s += std::to_string(v) + " ";
    s += "] rms " + std::to_string(f.rms_before) + " -> " + std::to_string(f.rms_after) + "; ";
  }
  for (double fl : run.result.rms_floor) s += "floor " + std::to_string(fl) + "; ";
  return s.empty() ? "no finding" : s;
}

const DiagFinding* find(const DriveDiagRun& run, EffectId e) {
  for (const auto& f : run.result.core.findings)
    if (f.term.effect == e) return &f;
  return nullptr;
}

void check_one(std::uint64_t seed, const std::string& inject, const Expect& x) {
  SCOPED_TRACE(inject + " seed " + std::to_string(seed));
  const DriveDiagRun run = diagnose(seed, {inject});
  const auto& fs = run.result.core.findings;
  ASSERT_EQ(fs.size(), 1u) << describe(run);
  const DiagFinding& f = fs[0];
  EXPECT_EQ(f.term.effect, x.effect) << describe(run);
  EXPECT_EQ(f.term.sensor, x.sensor);
  EXPECT_EQ(f.report_axis, x.axis);
  ASSERT_GT(static_cast<int>(f.value.size()), x.param);
  EXPECT_NEAR(f.value[x.param], x.value, 0.2 * std::abs(x.value)) << describe(run);
  // Systematic residual (binned by the term's signature, noise removed) cut by ≥ 80 %, or down to
  // the noise level of that figure.
  ASSERT_EQ(run.result.rms_floor.size(), 1u);
  EXPECT_GT(f.rms_before, 2 * run.result.rms_floor[0]) << describe(run);
  EXPECT_LE(f.rms_after, std::max(0.2 * f.rms_before, run.result.rms_floor[0])) << describe(run);
  EXPECT_TRUE(run.result.core.unexplained.empty());
}

TEST(DiagnoseDriveEffects, GSensitivity) {
  // 6e-5 rad/s per m/s² = 0.034 °/s/g (the data sheet's 0.009 °/s/g is below what 3.6 minutes show).
  check_one(21, "g_sensitivity:axis=x,f=y,value=6e-5", {EffectId::g_sensitivity, 0, 0, 1, 6e-5});
  check_one(22, "g_sensitivity:axis=z,f=x,value=-6e-5", {EffectId::g_sensitivity, 0, 2, 0, -6e-5});
}

TEST(DiagnoseDriveEffects, TimeOffset) {
  check_one(21, "time_offset:value=0.002", {EffectId::time_offset, 2, -1, 0, 0.002});
  check_one(23, "time_offset:value=-0.0015", {EffectId::time_offset, 2, -1, 0, -0.0015});
}

TEST(DiagnoseDriveEffects, LeverArm) {
  check_one(21, "lever_arm:x=0.03", {EffectId::lever_arm, 1, 0, 0, 0.03});
  check_one(22, "lever_arm:y=-0.04", {EffectId::lever_arm, 1, 1, 1, -0.04});
}

TEST(DiagnoseDriveEffects, ScaleAsymmetryAndNonlinearity) {
  check_one(21, "scale_asymmetry:sensor=gyro,axis=z,value=8e-4", {EffectId::scale_asymmetry, 0, 2, 0, 8e-4});
  check_one(22, "scale_nonlinearity:sensor=gyro,axis=z,value=4e-3", {EffectId::scale_nonlinearity, 0, 2, 0, 4e-3});
}

// A bias that wanders more than the data sheet says is named correlated_drift (noise side; σ of a
// drift on a drive 3.6 correlation times long is known to tens of per cent, so the value is
// checked to a factor of 2), not explained by spurious linear terms.
TEST(DiagnoseDriveEffects, CorrelatedDrift) {
  const DriveDiagRun run = diagnose(51, {"correlated_drift:sensor=gyro,sigma=5e-4,tau=60"});
  const auto& fs = run.result.core.findings;
  ASSERT_EQ(fs.size(), 1u) << describe(run);
  EXPECT_EQ(fs[0].term.effect, EffectId::correlated_drift);
  EXPECT_EQ(fs[0].term.sensor, 0);
  EXPECT_GT(fs[0].value[0], 2.5e-4);
  EXPECT_LT(fs[0].value[0], 1e-3);
}

TEST(DiagnoseDriveEffects, CleanDrivesHaveNoFinding) {
  for (std::uint64_t seed : {31, 32, 33, 34, 35, 36}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const DriveDiagRun run = diagnose(seed, {});
    EXPECT_TRUE(run.result.core.findings.empty()) << describe(run);
    EXPECT_TRUE(run.result.core.unexplained.empty());
    // The noise model is right: the whitened residual has χ²/dof ≈ 1 on every axis.
    for (int a = 0; a < 6; ++a) EXPECT_NEAR(run.result.core.before[a].chi2_dof, 1.0, 0.35) << "axis " << a;
  }
}

TEST(DiagnoseDriveEffects, TwoEffectsAtOnce) {
  {
    const DriveDiagRun run = diagnose(24, {"g_sensitivity:axis=x,f=y,value=6e-5", "lever_arm:x=0.03"});
    const DiagFinding* g = find(run, EffectId::g_sensitivity);
    const DiagFinding* l = find(run, EffectId::lever_arm);
    ASSERT_TRUE(g && l) << describe(run);
    EXPECT_EQ(g->term.axis, 0);
    EXPECT_NEAR(g->value[1], 6e-5, 1.2e-5);
    EXPECT_NEAR(l->value[0], 0.03, 0.006);
  }
  {
    const DriveDiagRun run = diagnose(25, {"time_offset:value=0.002", "scale_asymmetry:sensor=gyro,axis=z,value=8e-4"});
    const DiagFinding* t = find(run, EffectId::time_offset);
    const DiagFinding* a = find(run, EffectId::scale_asymmetry);
    ASSERT_TRUE(t && a) << describe(run);
    EXPECT_NEAR(t->value[0], 0.002, 0.0004);
    EXPECT_EQ(a->term.axis, 2);
    EXPECT_NEAR(a->value[0], 8e-4, 1.6e-4);
  }
}

// IMPROVED.json carries the found term; predicting with it (given coefficients, M fixed) finds
// nothing new.
TEST(DiagnoseDriveEffects, ImprovedCoefficientsExplainTheDrive) {
  EffectTerms fx;
  apply_inject_option("lever_arm:y=-0.04", fx);
  const DriveDiagInput in = simulate_drive_diag_input(kRoute, 22, fx);
  const DriveDiagRun first = run_drive_diagnosis(in, nullptr);
  ASSERT_EQ(first.result.core.findings.size(), 1u) << describe(first);
  DriveCoeffs c;
  c.set = first.improved;
  c.carried = effects_from_json(first.improved.extra, "IMPROVED.json");
  EXPECT_NEAR(effect_vector<3>(c.carried, EffectId::lever_arm)(1), -0.04, 0.008);
  const DriveDiagRun second = run_drive_diagnosis(in, &c);
  EXPECT_TRUE(second.result.core.findings.empty()) << describe(second);
}

// The workflow the docs recommend: the unit calibrated on the factory plan first (simulated and
// fitted here), the drive then diagnosed with those coefficients (M fixed, bias and mounting
// re-estimated). The drive's unit is mounted up to ~1° off the route's nominal mounting; the
// mounting correction must be applied exactly, not only to first order, or the fixed M leaves a
// scale error of 1 − cos θ (≈ 1e-4) that a scale-like catalogue term takes (a clean drive was
// named a gyro z nonlinearity of −4e-4/(rad/s) in 17 of 100 sweep seeds before).
TEST(DiagnoseDriveEffects, CleanDrivesWithBenchCoefficientsAndAMountingOffByADegree) {
  for (std::uint64_t seed : {57, 66}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const DriveCoeffs c = simulate_factory_coeffs(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/factory.toml", seed,
                                                  EffectTerms{}, seed + 900000);
    const DriveDiagRun run = run_drive_diagnosis(simulate_drive_diag_input(kRoute, seed, EffectTerms{}), &c);
    EXPECT_TRUE(run.result.core.findings.empty()) << describe(run);
    EXPECT_TRUE(run.result.core.unexplained.empty());
    // The mounting was off by more than half a degree (the case this test is about).
    EXPECT_GT(run.result.mounting_delta.norm(), 0.5 * units::kDeg);
  }
}

// The workflow the docs recommend: the unit calibrated on the factory plan first, the drive then
// diagnosed with those coefficients (M fixed). A unit's scale that changed since that calibration
// is a scale_factor on its axis, and IMPROVED.json carries it in M, not as an extra key.
DriveDiagRun diagnose_with_factory(std::uint64_t seed, const std::vector<std::string>& inject, SensorErrors* given) {
  EffectTerms fx;
  for (const auto& o : inject) apply_inject_option(o, fx);
  // simulate_factory_coeffs leaves an injected scale_factor out: the factory saw the unit before.
  const DriveCoeffs c =
      simulate_factory_coeffs(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/factory.toml", seed, fx, seed + 900000);
  if (given) *given = c.set.errors;
  return run_drive_diagnosis(simulate_drive_diag_input(kRoute, seed, fx), &c);
}

TEST(DiagnoseDriveEffects, ScaleChangedSinceTheFactoryCalibration) {
  struct Case {
    std::uint64_t seed;
    const char* inject;
    int sensor, axis;
    double value;
  };
  for (const Case& k : {Case{71, "scale_factor:sensor=gyro,axis=z,value=-8e-4", 0, 2, -8e-4},
                        Case{72, "scale_factor:sensor=accel,axis=x,value=2e-3", 1, 0, 2e-3}}) {
    SCOPED_TRACE(std::string(k.inject) + " seed " + std::to_string(k.seed));
    SensorErrors given;
    const DriveDiagRun run = diagnose_with_factory(k.seed, {k.inject}, &given);
    const auto& fs = run.result.core.findings;
    ASSERT_EQ(fs.size(), 1u) << describe(run);
    const DiagFinding& f = fs[0];
    EXPECT_EQ(f.term.effect, EffectId::scale_factor) << describe(run);
    EXPECT_EQ(f.term.sensor, k.sensor);
    EXPECT_EQ(f.report_axis, k.axis);
    EXPECT_NEAR(f.value[0], k.value, 0.2 * std::abs(k.value)) << describe(run);
    EXPECT_GT(f.rms_before, 2 * run.result.rms_floor[0]) << describe(run);
    EXPECT_LE(f.rms_after, std::max(0.2 * f.rms_before, run.result.rms_floor[0])) << describe(run);
    EXPECT_TRUE(run.result.core.unexplained.empty());
    // Folded into M_ii of the improved coefficients, with its σ; no extra key left.
    const TriadErrors& g = k.sensor == 0 ? given.gyro : given.accel;
    const TriadErrors& im = k.sensor == 0 ? run.result.core.improved.gyro : run.result.core.improved.accel;
    EXPECT_DOUBLE_EQ(im.M(k.axis, k.axis), g.M(k.axis, k.axis) + f.value[0]);
    EXPECT_DOUBLE_EQ(im.sigma_M(k.axis, k.axis), f.sigma[0]);
    EXPECT_TRUE(effect_triad(run.result.core.improved_terms, EffectId::scale_factor, 0).isZero(0));
    EXPECT_TRUE(effect_triad(run.result.core.improved_terms, EffectId::scale_factor, 1).isZero(0));
  }
}

// A nonlinearity the factory model lacks: the factory fit puts its mean slope over the plan's rates
// (up to 300 °/s) into M_zz, so at a car's rates the scale is below the given one — a scale_factor
// of the opposite sign — and the nonlinearity itself is found beside it with its own value (before
// the scale_factor candidate it was named with a value 350–590 % off and the wrong sign).
TEST(DiagnoseDriveEffects, NonlinearityWithFactoryCoefficients) {
  const DriveDiagRun run = diagnose_with_factory(73, {"scale_nonlinearity:sensor=gyro,axis=z,value=2.5e-3"}, nullptr);
  const DiagFinding* n = find(run, EffectId::scale_nonlinearity);
  const DiagFinding* s = find(run, EffectId::scale_factor);
  ASSERT_TRUE(n && s) << describe(run);
  EXPECT_EQ(run.result.core.findings.size(), 2u) << describe(run);
  EXPECT_EQ(n->term.sensor, 0);
  EXPECT_EQ(n->report_axis, 2);
  EXPECT_NEAR(n->value[0], 2.5e-3, 0.2 * 2.5e-3) << describe(run);
  EXPECT_EQ(s->term.sensor, 0);
  EXPECT_EQ(s->report_axis, 2);
  EXPECT_LT(s->value[0], 0) << describe(run);
  EXPECT_TRUE(run.result.core.unexplained.empty());
}

}  // namespace
}  // namespace calbench
