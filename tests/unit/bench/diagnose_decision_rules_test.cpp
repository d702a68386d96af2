// Issue 36, the diagnosis's decision rules: a finding is established only when the accepted model
// cuts the systematic residual of its axis by ≥ DiagnoseOptions::established_cut and leaves a
// remainder consistent with noise; otherwise it is "partial" with the fraction it explains, and an
// alternative explaining it as well makes it "not told apart" (docs/diagnosis.md, "Decision rules").
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "bench/diagnose/diagnose_run.hpp"
#include "bench/io/plan_toml.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

DiagFinding gyro_x_finding(double before, double after) {
  DiagFinding f;
  f.term = Term{EffectId::scale_asymmetry, 0, 0};
  f.report_sensor = 0;
  f.report_axis = 0;
  f.rms_before = before;
  f.rms_after = after;
  return f;
}

// The memory case: two names together cut 29.8 → 23.9 °/h (20 %): partial, never established.
TEST(DiagnoseDecisionRules, ExplainedFractionBelowCutIsPartial) {
  const DiagnoseOptions opt;
  DiagnoseResult res;
  DiagFinding f = gyro_x_finding(29.8, 23.9);
  finding_status(f, res, opt);
  EXPECT_STREQ(f.status, "partial");
  EXPECT_NEAR(f.explained_fraction, 1 - 23.9 / 29.8, 1e-12);
  // The same finding cutting 29.8 → 3 (90 %) with a noise-like remainder is established.
  f = gyro_x_finding(29.8, 3.0);
  finding_status(f, res, opt);
  EXPECT_STREQ(f.status, "established");
  EXPECT_TRUE(f.remainder_is_noise);
  // ... but not when its axis is left unexplained: the remainder is not noise.
  DiagUnexplained u;
  u.sensor = 0;
  u.axis = 0;
  res.unexplained.push_back(u);
  finding_status(f, res, opt);
  EXPECT_STREQ(f.status, "partial");
  EXPECT_FALSE(f.remainder_is_noise);
  // Another axis's remainder does not concern it.
  res.unexplained[0].axis = 1;
  finding_status(f, res, opt);
  EXPECT_STREQ(f.status, "established");
  // An alternative that explains it as well: not told apart, whatever the cut.
  f.alternatives.push_back(DiagAlternative{});
  finding_status(f, res, opt);
  EXPECT_STREQ(f.status, "not told apart");
}

// A gyro whose range (250 °/s) is exceeded by the plan's 300 °/s steps: the output clips. No
// polynomial or scale term may come out established on calbench's own diagnosis of it.
TEST(DiagnoseDecisionRules, ClippedGyroNamesNoEstablishedScaleTerm) {
  const BenchPlan plan = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/diagnose.toml");
  BenchSimOptions so;
  so.seed = 3601;
  so.noise.gyro.range = 250 * units::kDeg;
  const DiagInput in = simulate_diag_input(plan, draw_random_unit(3601), so);
  const DiagRun r = run_diagnosis(in, nullptr, plan.table);
  std::string all;
  for (const auto& f : r.result.findings) all += "\n  " + f.term.label() + " [" + f.status + "]: " + finding_sentence(f);
  bool gyro_left = false;
  for (const auto& u : r.result.unexplained) gyro_left = gyro_left || u.sensor == 0;
  for (const auto& f : r.result.findings) {
    if (f.report_sensor != 0) continue;
    EXPECT_STRNE(f.status, "established") << all;
    gyro_left = true;
  }
  EXPECT_TRUE(gyro_left) << "the clipped gyro must leave something reported" << all;
  std::printf("clipped gyro: %zu findings, %zu unexplained%s\n", r.result.findings.size(), r.result.unexplained.size(),
              all.c_str());
}

}  // namespace
}  // namespace calbench
