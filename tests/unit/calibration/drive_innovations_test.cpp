// Innovation statistics of the drive diagnosis (calibration/diagnosis/drive_innovations.hpp):
// consistent white innovations give NIS/dof ≈ 1 and pass the whiteness test; correlated ones fail
// it; a burst is found as the worst 20 s window; a magnitude that grows with the yaw rate
// correlates with |w_z|; gated epochs are counted, not averaged in.
#include <gtest/gtest.h>

#include <random>

#include "calibration/diagnosis/drive_innovations.hpp"

using namespace calbench;

namespace {

// 120 one-second blocks; the yaw rate swings ±0.3 rad/s with a 30 s period.
DriveDiagData blocks() {
  DriveDiagData d;
  for (int k = 0; k < 120; ++k) {
    ParentBlock p;
    p.t_mid = k + 0.5;
    p.duration = 1.0;
    p.w = Vec3(0.01, 0.0, 0.3 * std::sin(2 * M_PI * k / 30.0));
    p.f = Vec3(0.1, 0.0, -9.81);
    d.parents.push_back(p);
    d.info.push_back(DriveParentInfo{});
  }
  return d;
}

// 10 Hz innovations with S = diag(s²); `scale(t)` multiplies the standard deviation.
template <class Scale>
std::vector<InnovationSample> innovations(std::uint64_t seed, double ar, Scale scale) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<InnovationSample> x;
  const Vec3 s(0.02, 0.03, 0.05);
  Vec3 e = Vec3::Zero();
  for (int k = 0; k < 1200; ++k) {
    InnovationSample v;
    v.t = 0.1 * k;
    const Vec3 w(n(rng), n(rng), n(rng));
    e = ar * e + std::sqrt(1 - ar * ar) * w;  // unit variance, lag-1 correlation ar
    v.nu = (scale(v.t) * e).cwiseProduct(s);
    v.S = s.cwiseAbs2().asDiagonal();
    v.nis = v.nu.dot(v.S.inverse() * v.nu);
    v.status = v.nis > 50 ? 1 : 0;
    x.push_back(v);
  }
  return x;
}

}  // namespace

TEST(DriveInnovations, WhiteConsistentInnovations) {
  const DriveDiagData d = blocks();
  const InnovationStats s = innovation_stats(innovations(1, 0.0, [](double) { return 1.0; }), &d);
  EXPECT_EQ(s.epochs, 1200);
  EXPECT_NEAR(s.nis_per_dof, 1.0, 0.1);
  EXPECT_NEAR(s.fraction_within_95, 0.95, 0.02);
  EXPECT_GT(s.ljung_box_p_min, 1e-3);
  EXPECT_EQ(s.correlation_blocks, 120);
  ASSERT_FALSE(s.correlations.empty());
  EXPECT_LT(std::abs(s.correlations[0].r), 0.35);  // nothing to find (largest of 27 by chance)
}

TEST(DriveInnovations, CorrelatedInnovationsAreNotWhite) {
  const InnovationStats s = innovation_stats(innovations(2, 0.6, [](double) { return 1.0; }), nullptr);
  EXPECT_LT(s.ljung_box_p_min, 1e-6);
  for (double r : s.lag1_autocorr) EXPECT_NEAR(r, 0.6, 0.1);
  EXPECT_TRUE(s.correlations.empty());
}

TEST(DriveInnovations, BurstIsTheWorstWindowAndGatedEpochsAreCounted) {
  const InnovationStats s =
      innovation_stats(innovations(3, 0.0, [](double t) { return t >= 40 && t < 60 ? 4.0 : 1.0; }), nullptr);
  ASSERT_FALSE(s.worst_windows.empty());
  EXPECT_DOUBLE_EQ(s.worst_windows[0].t0, 40.0);
  EXPECT_DOUBLE_EQ(s.worst_windows[0].t1, 60.0);
  EXPECT_NEAR(s.worst_windows[0].nis_per_dof, 16.0, 3.0);
  EXPECT_GT(s.rejected, 5);
  EXPECT_EQ(s.used + s.rejected + s.forced, s.epochs);
  // The used epochs' mean excludes the gated ones (≤ 50/3 each), so it stays below the burst's level.
  EXPECT_LT(s.nis_per_dof, 4.0);
}

TEST(DriveInnovations, MagnitudeFollowingTheYawRateIsFound) {
  const DriveDiagData d = blocks();
  const InnovationStats s = innovation_stats(
      innovations(4, 0.0, [](double t) { return 1.0 + 6.0 * std::abs(std::sin(2 * M_PI * std::floor(t) / 30.0)); }), &d);
  ASSERT_FALSE(s.correlations.empty());
  EXPECT_EQ(s.correlations[0].condition, "|w_z|");
  EXPECT_GT(s.correlations[0].r, 0.8);
}
