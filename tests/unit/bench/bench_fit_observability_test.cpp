// What the bench fit says when a plan cannot determine a coefficient, and the paper's model.
#include <gtest/gtest.h>

#include <cmath>

#include "calibration/bench_fit.hpp"
#include "calibration/bench_sim.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {
using namespace units;

BenchPlan small_plan(bool rotate_x, bool rotate_y, bool rotate_z) {
  BenchPlan p;
  p.site = {45.0, 10.0, 100.0};
  p.table.max_rate = 500 * kDeg;
  p.table.max_accel = 200 * kDeg;
  p.table.slew_rate = 60 * kDeg;
  p.table.settle_s = 1;
  p.table.remount_s = 30;
  p.table.rate_accuracy_rel = 1e-6;
  p.table.position_accuracy = 2 * kDeg / 3600;
  p.table.axis_wobble = 1 * kDeg / 3600;
  const double statics[6][2] = {{0, 0}, {180, 0}, {90, 0}, {90, 180}, {90, 90}, {90, 270}};
  for (auto& s : statics) {
    PlanStep st;
    st.kind = StepKind::static_position;
    st.mount = 2;
    st.outer = s[0] * kDeg;
    st.inner = s[1] * kDeg;
    st.dwell_s = 8;
    p.steps.push_back(st);
  }
  const bool rot[3] = {rotate_x, rotate_y, rotate_z};
  for (int axis : {2, 0, 1}) {
    if (!rot[axis]) continue;
    for (double r : {100.0, -100.0, 300.0, -300.0}) {
      PlanStep st;
      st.kind = StepKind::rate;
      st.mount = axis;
      st.rate = r * kDeg;
      st.dwell_s = 8;
      p.steps.push_back(st);
    }
  }
  return p;
}

std::vector<BenchBlock> run(const BenchPlan& plan, const SensorErrors& truth, std::uint64_t seed) {
  BenchBlockBuilder bb(1.0);
  BenchSimOptions so;
  so.seed = seed;
  simulate_bench(plan, plan.site, truth, so, [&](const BenchSample& s) {
    bb.add(s.t, 1.0 / so.noise.output_rate_hz, s.gyro, s.accel, s.w_ref, s.f_ref, s.step);
  });
  return bb.finish();
}

TEST(BenchFitObservability, NoRotationAboutXYLeavesThoseColumnsUndetermined) {
  const BenchPlan plan = small_plan(false, false, true);
  const SensorErrors truth = draw_random_unit(5);
  const auto blocks = run(plan, truth, 5);
  BenchFitOptions o;
  o.table = plan.table;
  for (BenchMethod m : {BenchMethod::lsq, BenchMethod::ekf}) {
    o.method = m;
    const BenchFitResult r = fit_bench(blocks, o);
    std::set<std::string> names;
    for (const auto& u : r.unobservable) {
      EXPECT_EQ(u.triad, "gyro") << u.param << ": " << u.reason;
      EXPECT_NE(u.reason.find("no rotation about IMU"), std::string::npos) << u.reason;
      names.insert(u.param);
    }
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 2; ++j) {
        const std::string p = "M[" + std::to_string(i) + "][" + std::to_string(j) + "]";
        EXPECT_TRUE(names.count(p)) << p << " should be reported as not determined";
        EXPECT_TRUE(std::isinf(r.estimate.gyro.sigma_M(i, j))) << "no σ may be printed for " << p;
        EXPECT_EQ(r.estimate.gyro.M(i, j), 0.0) << "no value may be printed for " << p;
      }
    EXPECT_EQ(names.size(), 6u);
    // What the plan does determine is still right.
    for (int i = 0; i < 3; ++i) {
      EXPECT_LE(std::abs(r.estimate.gyro.M(i, 2) - truth.gyro.M(i, 2)), 4 * r.estimate.gyro.sigma_M(i, 2));
      EXPECT_LE(std::abs(r.estimate.accel.bias(i) - truth.accel.bias(i)), 4 * r.estimate.accel.sigma_bias(i));
      EXPECT_TRUE(std::isfinite(r.estimate.accel.sigma_M(i, i)));
    }
  }
}

TEST(BenchFitObservability, StaticOnlyZDownCannotSeparateAccelScaleFromBias) {
  BenchPlan plan = small_plan(false, false, false);
  plan.steps.resize(1);  // only "z down"
  plan.steps[0].dwell_s = 30;
  const auto blocks = run(plan, draw_random_unit(6), 6);
  BenchFitOptions o;
  o.table = plan.table;
  const BenchFitResult r = fit_bench(blocks, o);
  bool accel_zz = false;
  for (const auto& u : r.unobservable) accel_zz = accel_zz || (u.triad == "accel" && u.param == "M[2][2]");
  EXPECT_TRUE(accel_zz);
  EXPECT_TRUE(std::isfinite(r.estimate.accel.sigma_bias(2))) << "bias is kept, the scale is dropped";
}

TEST(BenchFitModel, PaperModelEstimatesDriftAndSkewsOnly) {
  const BenchPlan plan = small_plan(true, true, true);
  SensorErrors truth = draw_random_unit(7);
  for (int i = 0; i < 3; ++i) truth.gyro.M(i, i) = 0;  // the paper's model: no scale errors
  const auto blocks = run(plan, truth, 7);
  BenchFitOptions o;
  o.table = plan.table;
  o.model = BenchModel::paper;
  const BenchFitResult r = fit_bench(blocks, o);
  EXPECT_EQ(r.not_estimated.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(std::isinf(r.estimate.gyro.sigma_M(i, i)));
    EXPECT_LE(std::abs(r.estimate.gyro.bias(i) - truth.gyro.bias(i)), 4 * r.estimate.gyro.sigma_bias(i));
    for (int j = 0; j < 3; ++j)
      if (i != j) {
        EXPECT_LE(std::abs(r.estimate.gyro.M(i, j) - truth.gyro.M(i, j)), 4 * r.estimate.gyro.sigma_M(i, j));
      }
  }
  // With scale errors present, the paper's model leaves them in the residual of the rate steps.
  SensorErrors with_scale = truth;
  with_scale.gyro.M(2, 2) = 3e-3;
  const BenchFitResult r2 = fit_bench(run(plan, with_scale, 7), o);
  double worst = 0;
  for (const auto& s : r2.steps)
    if (s.rotating) worst = std::max(worst, std::abs(s.gyro_mean(2)) / s.rate_norm);
  EXPECT_GT(worst, 1e-3) << "an unmodelled 3000 ppm scale error must show in the z residuals";
}

}  // namespace
}  // namespace calbench
