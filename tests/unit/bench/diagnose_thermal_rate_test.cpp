// Issue 7: thermal lag — a bias proportional to dT/dt (the gradient-driven term seen during warm-up
// and chamber ramps), effect ID temperature_rate. It can only be told from temperature_bias when the
// same temperatures are crossed while heating and while cooling: tests/data/thermal_updown.toml
// (chamber 10 → 35 → 10 °C at 5 K/min, 3-mount cycle of statics and ±300 °/s). The recording is
// simulated in memory with the term concealed (the simulator takes dT/dt from its temperature
// profile; the diagnosis only sees the quantised temperature column and differentiates it itself).
//
// Magnitudes (an assumption, not a data-sheet figure — the ADIS16488A data sheet gives no thermal-
// gradient coefficient): a MEMS gyro of this class shows a few to tens of °/h of extra bias per K/min
// during a ramp, the accelerometers some 0.01–0.1 mg per K/min. The tests use values near the
// detection limit measured on this plan (docs/diagnosis.md), at the low end of that range.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "bench/diagnose/diagnose_run.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "bench/io/plan_toml.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

using namespace units;

constexpr double kPerKPerMin = 60.0;  // a coefficient per (K/min) is 60× the one per (K/s)

const BenchPlan& plan() {
  static const BenchPlan p = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/tests/data/thermal_updown.toml");
  return p;
}

DiagRun diagnose_sim(const EffectTerms& fx, std::uint64_t seed) {
  BenchSimOptions so;
  so.seed = seed;
  so.effects = fx;
  const DiagInput in = simulate_diag_input(plan(), draw_random_unit(900 + seed), so);
  return run_diagnosis(in, nullptr, plan().table);
}

std::string summary(const DiagRun& r) {
  std::string s;
  for (const auto& f : r.result.findings) s += "\n  " + f.term.label() + ": " + finding_sentence(f);
  return s.empty() ? " (no finding)" : s;
}

// Exactly one finding: the given effect, sensor and axis, value within 20 %, systematic residual cut
// by ≥ 80 %: both the finding's figure (rms_before/after) and its per-step part on the finding's
// axis (AxisStats::step_rms, noise removed; a bias ∝ dT/dt or ∝ T is constant within a 6 s step),
// each measurable before.
void expect_only(const EffectTerms& fx, EffectId effect, int sensor, int axis, double value, std::uint64_t seed) {
  const DiagRun r = diagnose_sim(fx, seed);
  ASSERT_EQ(r.result.findings.size(), 1u) << "seed " << seed << summary(r);
  const DiagFinding& f = r.result.findings[0];
  EXPECT_EQ(f.term.effect, effect) << summary(r);
  EXPECT_EQ(f.report_sensor, sensor) << summary(r);
  EXPECT_EQ(f.report_axis, axis) << summary(r);
  ASSERT_FALSE(f.value.empty());
  EXPECT_NEAR(f.value[0], value, 0.2 * std::abs(value)) << summary(r);
  const AxisStats& b = r.result.before[sensor * 3 + axis];
  const AxisStats& a = r.result.after[sensor * 3 + axis];
  EXPECT_GT(b.step_rms, 0.0) << summary(r);
  EXPECT_LE(a.step_rms, 0.2 * b.step_rms) << summary(r);
  EXPECT_GT(f.rms_before, 0.0) << summary(r);
  EXPECT_LE(f.rms_after, 0.2 * f.rms_before) << summary(r);
  std::printf("%-17s %-5s %c truth %.4g found %.4g ± %.2g  Δχ² %.0f  per-step rms %.3g → %.3g, combined %.3g → %.3g\n  %s\n",
              effect_name(f.term.effect), sensor ? "accel" : "gyro", "xyz"[axis], value, f.value[0],
              f.sigma.empty() ? 0.0 : f.sigma[0], f.delta_chi2, b.step_rms, a.step_rms, f.rms_before, f.rms_after,
              finding_sentence(f).c_str());
}

TEST(DiagnoseThermalRate, PlanHeatsAndCoolsOverTheSameRange) {
  ProfileTemperature T(plan().temperature);
  const double dur = plan_duration_s(plan());
  double up_min = 1e9, up_max = -1e9, down_min = 1e9, down_max = -1e9, rmin = 0, rmax = 0;
  for (double t = 0; t <= dur; t += 1.0) {
    const double v = T.at(t), r = T.rate();
    rmin = std::min(rmin, r);
    rmax = std::max(rmax, r);
    if (r > 0.02) up_min = std::min(up_min, v), up_max = std::max(up_max, v);
    if (r < -0.02) down_min = std::min(down_min, v), down_max = std::max(down_max, v);
  }
  std::printf("thermal_updown: %.0f s; heating %.1f…%.1f °C, cooling %.1f…%.1f °C; dT/dt %.3f…%.3f K/s\n", dur,
              up_min, up_max, down_min, down_max, rmin, rmax);
  EXPECT_GT(rmax, 0.05);
  EXPECT_LT(rmin, -0.05);
  // Heating and cooling overlap over at least 15 K.
  EXPECT_GT(std::min(up_max, down_max) - std::max(up_min, down_min), 15.0);
}

// The simulator's dT/dt is the derivative of its (unquantised) temperature.
TEST(DiagnoseThermalRate, ProfileRateIsTheDerivative) {
  ProfileTemperature a(plan().temperature), b(plan().temperature);
  double worst = 0;
  for (double t = 10; t < 800; t += 37) {
    a.at(t);
    const double r = a.rate();
    // Quantised readings 2 s apart: the secant is good to 0.006/2 K/s, plus curvature near corners.
    const double slope = (b.at(t + 1) - (ProfileTemperature(plan().temperature).at(t - 1))) / 2.0;
    EXPECT_NEAR(r, slope, 0.004) << "t " << t;
    worst = std::max(worst, std::abs(r - slope));
  }
  std::printf("profile rate vs 2 s secant of the quantised temperature: worst %.4f K/s\n", worst);
}

// The diagnosis differentiates the quantised temperature column itself (least-squares slope over
// ±30 s of 1 s blocks): it must follow the simulator's true dT/dt.
TEST(DiagnoseThermalRate, DiagnosisDerivativeFollowsTheTrueRate) {
  BenchSimOptions so;
  so.seed = 4;
  const DiagInput in = simulate_diag_input(plan(), draw_random_unit(904), so);
  ProfileTemperature T(plan().temperature);
  double worst = 0, ss = 0;
  int n = 0;
  for (const auto& p : in.data.parents) {
    T.at(p.t_mid);
    const double e = p.dtemp - T.rate();
    worst = std::max(worst, std::abs(e));
    ss += e * e;
    ++n;
  }
  std::printf("dT/dt of the diagnosis vs truth over %d blocks: rms %.4f K/s, worst %.4f K/s\n", n, std::sqrt(ss / n),
              worst);
  EXPECT_LT(std::sqrt(ss / n), 0.004);
}

// Gyro: 5 °/h per K/min on y (at 5 K/min: 25 °/h of extra bias while heating, −25 °/h cooling).
TEST(DiagnoseThermalRate, GyroThermalLag) {
  EffectTerms fx;
  effect_triad(fx, EffectId::temperature_rate, 0)(1) = 5 * kDegPerHour * kPerKPerMin;
  expect_only(fx, EffectId::temperature_rate, 0, 1, effect_triad(fx, EffectId::temperature_rate, 0)(1), 1);
}

// Accelerometer: −0.3 mg per K/min on x (±1.5 mg on the ramps; found by Δχ² from ~0.1 mg per K/min,
// but the drift model absorbs the per-step figure below ~0.3).
TEST(DiagnoseThermalRate, AccelThermalLag) {
  EffectTerms fx;
  effect_triad(fx, EffectId::temperature_rate, 1)(0) = -0.3 * kMilliG * kPerKPerMin;
  expect_only(fx, EffectId::temperature_rate, 1, 0, effect_triad(fx, EffectId::temperature_rate, 1)(0), 2);
}

// A temperature-dependent bias alone on the same up-and-down plan is named temperature_bias, not
// temperature_rate (and the rate terms above were not named temperature_bias: exactly one finding).
TEST(DiagnoseThermalRate, TemperatureBiasIsNotTakenForThermalLag) {
  EffectTerms fx;
  effect_triad(fx, EffectId::temperature_bias, 0)(2) = 9 * kDegPerHour;
  expect_only(fx, EffectId::temperature_bias, 0, 2, effect_triad(fx, EffectId::temperature_bias, 0)(2), 3);
}

// On a warm-up alone (the diagnosis plan: ~2 K, rising exponentially) T − T_end ∝ dT/dt, so a bias
// ∝ T and one ∝ dT/dt explain the recording equally well. The diagnosis must not pretend to know:
// whichever it names, the other is reported as an alternative it cannot tell apart.
TEST(DiagnoseThermalRate, WarmUpAloneDeclaresBiasAndLagIndistinguishable) {
  static const BenchPlan warmup = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/diagnose.toml");
  for (std::uint64_t seed : {41, 42}) {
    EffectTerms fx;
    const int axis = static_cast<int>(seed % 3);
    effect_triad(fx, EffectId::temperature_bias, 0)(axis) = 100 * kDegPerHour;
    BenchSimOptions so;
    so.seed = seed;
    so.effects = fx;
    const DiagRun r = run_diagnosis(simulate_diag_input(warmup, draw_random_unit(950 + seed), so), nullptr, warmup.table);
    ASSERT_EQ(r.result.findings.size(), 1u) << "seed " << seed << summary(r);
    const DiagFinding& f = r.result.findings[0];
    ASSERT_TRUE(f.term.effect == EffectId::temperature_bias || f.term.effect == EffectId::temperature_rate) << summary(r);
    EXPECT_EQ(f.report_sensor, 0);
    EXPECT_EQ(f.report_axis, axis);
    const EffectId other =
        f.term.effect == EffectId::temperature_bias ? EffectId::temperature_rate : EffectId::temperature_bias;
    bool declared = false;
    for (const auto& a : f.alternatives) declared |= a.term.effect == other && a.term.sensor == 0 && a.term.axis == axis;
    EXPECT_TRUE(declared) << summary(r);
    EXPECT_NE(finding_sentence(f).find("NOT told apart"), std::string::npos);
    std::printf("warm-up seed %d: %s\n", static_cast<int>(seed), finding_sentence(f).c_str());
  }
}

// The JSON key round trip (IMPROVED.json, --effects) and the --inject option.
TEST(DiagnoseThermalRate, JsonKeyAndInjectOption) {
  EffectTerms e, s;
  effect_triad(e, EffectId::temperature_rate, 0) = Vec3(1e-3, -2e-3, 3e-3);
  effect_triad(e, EffectId::temperature_rate, 1)(2) = 4e-2;
  effect_triad(s, EffectId::temperature_rate, 0) = Vec3(1e-4, 1e-4, 2e-4);
  nlohmann::json j = nlohmann::json::object();
  effects_to_json(e, s, j);
  ASSERT_TRUE(j.contains("temperature_rate"));
  EffectTerms s2;
  const EffectTerms e2 = effects_from_json(j, "test", &s2);
  EXPECT_TRUE(effect_triad(e2, EffectId::temperature_rate, 0).isApprox(effect_triad(e, EffectId::temperature_rate, 0)));
  EXPECT_TRUE(effect_triad(e2, EffectId::temperature_rate, 1).isApprox(effect_triad(e, EffectId::temperature_rate, 1)));
  EXPECT_TRUE(effect_triad(s2, EffectId::temperature_rate, 0).isApprox(effect_triad(s, EffectId::temperature_rate, 0)));
  EXPECT_TRUE(effect_triad(e2, EffectId::temperature_bias, 0).isZero(0));
  EffectTerms k;
  apply_inject_option("temperature_rate:sensor=accel,axis=y,value=0.02", k);
  EXPECT_DOUBLE_EQ(effect_triad(k, EffectId::temperature_rate, 1)(1), 0.02);
  EXPECT_TRUE(k.any_sensor_side());
  // The term adds r·dT/dt to the output.
  EffectContext c;
  c.dtemp_k_s = 0.1;
  Vec3 dg, da;
  sensor_side_terms(k, c, dg, da);
  EXPECT_NEAR(da(1), 0.002, 1e-15);
  EXPECT_NEAR(da(0), 0.0, 1e-15);
}

}  // namespace
}  // namespace calbench
