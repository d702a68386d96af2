// Acceptance of the bench calibration (issue 2): 20 random units on the factory plan, both
// methods. The estimator sees only the simulated recording (IMU output + nominal reference).
#include <gtest/gtest.h>

#include <cmath>

#include "bench/io/plan_toml.hpp"
#include "calibration/bench_fit.hpp"
#include "calibration/bench_sim.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

std::vector<BenchBlock> simulate_blocks(const BenchPlan& plan, const SensorErrors& truth, std::uint64_t seed) {
  BenchBlockBuilder bb(1.0);
  BenchSimOptions so;
  so.seed = seed;
  const double dt = 1.0 / so.noise.output_rate_hz;
  simulate_bench(plan, plan.site, truth, so, [&](const BenchSample& s) {
    bb.add(s.t, dt, s.gyro, s.accel, s.w_ref, s.f_ref, s.step, s.temp_c, s.saturated);
  });
  return bb.finish();
}

struct Tally {
  int total = 0, within3 = 0;
  double max_gyro_m = 0, max_accel_m = 0, max_accel_b = 0;
  void add(double est, double sig, double truth) {
    ++total;
    if (std::abs(est - truth) <= 3 * sig) ++within3;
  }
};

void tally(const SensorErrors& est, const SensorErrors& truth, Tally& t) {
  for (int i = 0; i < 3; ++i) {
    t.add(est.gyro.bias(i), est.gyro.sigma_bias(i), truth.gyro.bias(i));
    t.add(est.accel.bias(i), est.accel.sigma_bias(i), truth.accel.bias(i));
    t.max_accel_b = std::max(t.max_accel_b, std::abs(est.accel.bias(i) - truth.accel.bias(i)));
    for (int j = 0; j < 3; ++j) {
      t.add(est.gyro.M(i, j), est.gyro.sigma_M(i, j), truth.gyro.M(i, j));
      t.add(est.accel.M(i, j), est.accel.sigma_M(i, j), truth.accel.M(i, j));
      t.max_gyro_m = std::max(t.max_gyro_m, std::abs(est.gyro.M(i, j) - truth.gyro.M(i, j)));
      t.max_accel_m = std::max(t.max_accel_m, std::abs(est.accel.M(i, j) - truth.accel.M(i, j)));
    }
  }
}

TEST(BenchFitAccuracy, TwentyRandomUnitsOnFactoryPlan) {
  const BenchPlan plan = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/factory.toml");
  Tally lsq, ekf;
  double max_disagreement_sigma = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const SensorErrors truth = draw_random_unit(1000 + seed);
    const auto blocks = simulate_blocks(plan, truth, seed);
    BenchFitOptions o;
    o.table = plan.table;
    o.method = BenchMethod::lsq;
    const BenchFitResult a = fit_bench(blocks, o);
    o.method = BenchMethod::ekf;
    const BenchFitResult b = fit_bench(blocks, o);
    EXPECT_TRUE(a.unobservable.empty()) << a.unobservable.front().param << ": " << a.unobservable.front().reason;
    tally(a.estimate, truth, lsq);
    tally(b.estimate, truth, ekf);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        max_disagreement_sigma = std::max(max_disagreement_sigma, std::abs(a.estimate.gyro.M(i, j) - b.estimate.gyro.M(i, j)) / a.estimate.gyro.sigma_M(i, j));
        max_disagreement_sigma = std::max(max_disagreement_sigma, std::abs(a.estimate.accel.M(i, j) - b.estimate.accel.M(i, j)) / a.estimate.accel.sigma_M(i, j));
      }
  }
  using namespace units;
  for (const Tally* t : {&lsq, &ekf}) {
    const double frac = static_cast<double>(t->within3) / t->total;
    std::printf("within 3σ: %d/%d (%.1f %%); max |gyro M err| %.1f ppm; max |accel M err| %.1f ppm; max |accel b err| %.3f mg\n",
                t->within3, t->total, 100 * frac, t->max_gyro_m / kPpm, t->max_accel_m / kPpm, t->max_accel_b / kMilliG);
    EXPECT_GE(frac, 0.95);
    EXPECT_LT(t->max_gyro_m, 30 * kPpm);
    EXPECT_LT(t->max_accel_m, 200 * kPpm);
    EXPECT_LT(t->max_accel_b, 0.3 * kMilliG);
  }
  std::printf("max |lsq − ekf| / σ over M: %.2e\n", max_disagreement_sigma);
  EXPECT_LT(max_disagreement_sigma, 0.1);
}

}  // namespace
}  // namespace calbench
