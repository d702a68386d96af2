// Proof on concealed data (issue 7): the bench simulator injects each catalogue effect while the
// estimator's model (the spec's b, M) lacks it; `diagnose` must name the effect, sensor and axis,
// recover the value within 20 % and cut the systematic residual by ≥ 80 %. Clean recordings must
// give no finding; two effects at once must both be found. Short plan (bench/plans/diagnose.toml),
// in-memory simulation; the long sweep is tests/perf/diagnose_sweep_bench.cpp.
#include <gtest/gtest.h>

#include <cmath>

#include "bench/diagnose/diagnose_run.hpp"
#include "bench/io/plan_toml.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

const BenchPlan& plan() {
  static const BenchPlan p = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/diagnose.toml");
  return p;
}

// unit_seed 0: the unit of seed `seed` (500 + seed); else that unit (the sweep draws 5000 + seed).
DiagRun diagnose_sim(const EffectTerms& fx, std::uint64_t seed, std::uint64_t unit_seed = 0) {
  BenchSimOptions so;
  so.seed = seed;
  so.effects = fx;
  const DiagInput in = simulate_diag_input(plan(), draw_random_unit(unit_seed ? unit_seed : 500 + seed), so);
  return run_diagnosis(in, nullptr, plan().table);
}

const DiagFinding* find(const DiagRun& r, EffectId e) {
  for (const auto& f : r.result.findings)
    if (f.term.effect == e) return &f;
  return nullptr;
}

std::string summary(const DiagRun& r) {
  std::string s;
  for (const auto& f : r.result.findings) s += "\n  " + f.term.label() + ": " + finding_sentence(f);
  return s.empty() ? " (no finding)" : s;
}

// One concealed effect: expects exactly that effect (sensor, axis), value within 20 %, cut ≥ 80 %.
void expect_found(const EffectTerms& fx, EffectId e, int sensor, int axis, int param, double truth, std::uint64_t seed,
                  std::uint64_t unit_seed = 0) {
  const DiagRun r = diagnose_sim(fx, seed, unit_seed);
  const DiagFinding* f = find(r, e);
  ASSERT_NE(f, nullptr) << effect_name(e) << " not found; seed " << seed << summary(r);
  EXPECT_EQ(f->report_sensor, sensor) << summary(r);
  EXPECT_EQ(f->report_axis, axis) << summary(r);
  EXPECT_NEAR(f->value[param], truth, 0.2 * std::abs(truth)) << summary(r);
  // The systematic residual was measurable (the effect showed beyond the noise model) and is cut.
  EXPECT_GT(f->rms_before, 0.0) << summary(r);
  EXPECT_LE(f->rms_after, 0.2 * f->rms_before) << summary(r);
  EXPECT_EQ(r.result.findings.size(), 1u) << "seed " << seed << summary(r);
  std::printf("%-20s truth %.4g found %.4g ± %.2g  rms %.3g → %.3g\n", effect_name(e), truth, f->value[param],
              f->sigma[param], f->rms_before, f->rms_after);
}

using namespace units;

TEST(DiagnoseEffects, GSensitivity) {
  for (int k = 0; k < 2; ++k) {
    EffectTerms fx;
    const int i = 2 * k, j = (2 * k + 1) % 3;
    const double v = (k ? -1 : 1) * (0.007 + 0.004 * k) * kDeg / kG0;  // 0.007, −0.011 °/s/g
    effect_matrix(fx, EffectId::g_sensitivity)(i, j) = v;
    expect_found(fx, EffectId::g_sensitivity, 0, i, j, v, 11 + k);
  }
}

TEST(DiagnoseEffects, ScaleNonlinearity) {
  EffectTerms fx;
  effect_triad(fx, EffectId::scale_nonlinearity, 0)(1) = -2e-5;
  expect_found(fx, EffectId::scale_nonlinearity, 0, 1, 0, -2e-5, 22);
  EffectTerms fa;
  effect_triad(fa, EffectId::scale_nonlinearity, 1)(2) = 6e-5;
  expect_found(fa, EffectId::scale_nonlinearity, 1, 2, 0, 6e-5, 23);
}

TEST(DiagnoseEffects, ScaleAsymmetry) {
  EffectTerms fx;
  effect_triad(fx, EffectId::scale_asymmetry, 0)(1) = 200e-6;
  expect_found(fx, EffectId::scale_asymmetry, 0, 1, 0, 200e-6, 31);
  EffectTerms fa;
  effect_triad(fa, EffectId::scale_asymmetry, 1)(0) = -300e-6;
  expect_found(fa, EffectId::scale_asymmetry, 1, 0, 0, -300e-6, 32);
}

TEST(DiagnoseEffects, TemperatureBias) {
  // The short plan's warm-up spans only ~2 K: the gyro term must stand out of the 5 °/h drift.
  EffectTerms fx;
  effect_triad(fx, EffectId::temperature_bias, 0)(2) = 100 * kDegPerHour;
  expect_found(fx, EffectId::temperature_bias, 0, 2, 0, effect_triad(fx, EffectId::temperature_bias, 0)(2), 41);
  // Accelerometer temperature bias is not required here: on this 2 K warm-up it does not stand out
  // of the 0.1 mg Gauss–Markov drift at 0.5 mg/K (docs/diagnosis.md, detection limits).
}

TEST(DiagnoseEffects, TemperatureScale) {
  EffectTerms fx;
  effect_triad(fx, EffectId::temperature_scale, 0)(0) = 400e-6;
  expect_found(fx, EffectId::temperature_scale, 0, 0, 0, 400e-6, 51);
}

TEST(DiagnoseEffects, TimeOffset) {
  for (double tau : {0.3e-3}) {
    EffectTerms fx;
    effect_vector<1>(fx, EffectId::time_offset)(0) = tau;
    expect_found(fx, EffectId::time_offset, 2, -1, 0, tau, 61 + (tau > 0));
  }
}

TEST(DiagnoseEffects, LeverArm) {
  for (int k = 1; k < 2; ++k) {
    EffectTerms fx;
    effect_vector<3>(fx, EffectId::lever_arm)(k * 2) = k ? 0.004 : -0.002;
    expect_found(fx, EffectId::lever_arm, 1, k * 2, k * 2, effect_vector<3>(fx, EffectId::lever_arm)(k * 2), 71 + k);
  }
}

TEST(DiagnoseEffects, TableWobble) {
  EffectTerms fx;
  effect_vector<2>(fx, EffectId::table_wobble)(0) = 20.0 / 3600 * kDeg;
  expect_found(fx, EffectId::table_wobble, 2, -1, 0, effect_vector<2>(fx, EffectId::table_wobble)(0), 81);
}

// The static-position part of the wobble (the table stands at θ + δ(θ), gravity turns about the
// inner axis, derived from the recording): two sweep runs (seed, unit) at 40″ whose systematic
// residual was cut only 73 % and 51 % while the model covered rotating steps only (per-step means
// of accel x/y/z remained); now ≥ 80 %.
TEST(DiagnoseEffects, TableWobbleStaticPositions) {
  const struct {
    double arcsec;
    std::uint64_t seed;
  } cases[] = {{40, 353}, {-40, 387}};
  for (const auto& c : cases) {
    EffectTerms fx;
    effect_vector<2>(fx, EffectId::table_wobble)(1) = c.arcsec / 3600 * kDeg;
    expect_found(fx, EffectId::table_wobble, 2, -1, 1, effect_vector<2>(fx, EffectId::table_wobble)(1), c.seed, 5000 + c.seed);
  }
}

// Table tilt: modelled in static and rotating steps (the IMU attitude is reconstructed from
// gravity and the Earth rate, north ⟂ the spinning IMU axis); two magnitudes, both axes (more in
// the sweep, tests/perf/diagnose_sweep_bench.cpp).
TEST(DiagnoseEffects, Misalignment) {
  const struct {
    int axis;
    double arcsec;
    std::uint64_t seed;
  } cases[] = {{1, 60, 91}, {0, -30, 92}};
  for (const auto& c : cases) {
    EffectTerms fx;
    effect_vector<2>(fx, EffectId::misalignment)(c.axis) = c.arcsec / 3600 * kDeg;
    expect_found(fx, EffectId::misalignment, 2, -1, c.axis, effect_vector<2>(fx, EffectId::misalignment)(c.axis), c.seed);
  }
}

TEST(DiagnoseEffects, CleanRecordingsHaveNoFinding) {
  int with_finding = 0;
  const int n = 4;
  for (int s = 0; s < n; ++s) {
    const DiagRun r = diagnose_sim(EffectTerms{}, 100 + s);
    if (!r.result.findings.empty()) {
      ++with_finding;
      std::printf("clean seed %d:%s\n", 100 + s, summary(r).c_str());
    }
  }
  EXPECT_LE(with_finding, 0) << with_finding << " of " << n << " clean recordings gave a finding";
}

TEST(DiagnoseEffects, TwoEffectsAtOnce) {
  EffectTerms fx;
  effect_matrix(fx, EffectId::g_sensitivity)(0, 2) = 0.008 * kDeg / kG0;
  effect_vector<3>(fx, EffectId::lever_arm)(1) = 0.003;
  const DiagRun r = diagnose_sim(fx, 201);
  const DiagFinding* g = find(r, EffectId::g_sensitivity);
  const DiagFinding* l = find(r, EffectId::lever_arm);
  ASSERT_NE(g, nullptr) << summary(r);
  ASSERT_NE(l, nullptr) << summary(r);
  EXPECT_NEAR(g->value[2], effect_matrix(fx, EffectId::g_sensitivity)(0, 2), 0.2 * effect_matrix(fx, EffectId::g_sensitivity)(0, 2));
  EXPECT_NEAR(l->value[1], 0.003, 0.2 * 0.003);
  EXPECT_EQ(r.result.findings.size(), 2u) << summary(r);
}

}  // namespace
}  // namespace calbench
