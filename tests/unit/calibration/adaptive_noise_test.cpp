// The adaptive process noise (calibration/inmotion/adaptive_noise.hpp): covariance matching of the
// innovations, tested with innovations drawn from known covariances (fixed seeds).
#include "calibration/inmotion/adaptive_noise.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace calbench::inmotion {
namespace {

// Innovations of 3 components at 10 Hz with tr R = 3·r, tr(HPHᵀ) = 3·p and actual covariance
// (k·p + r)·I: k = 1 is a consistent filter, k > 1 one whose process noise is too small.
AdaptiveNoiseConfig on() {
  AdaptiveNoiseConfig c;
  c.enabled = true;
  return c;
}

struct Stream {
  std::mt19937_64 rng;
  double t = 0, r = 0.5, p = 0.5;
  explicit Stream(unsigned seed) : rng(seed) {}
  AdaptiveSample next(double k, double nis_cap = 1e300) {
    std::normal_distribution<double> n(0.0, 1.0);
    const double var = k * p + r, pred = p + r;
    double nu2 = 0;
    for (int i = 0; i < 3; ++i) {
      const double x = n(rng) * std::sqrt(var);
      nu2 += x * x;
    }
    double nis = nu2 / pred;
    if (nis > nis_cap) {
      nu2 *= nis_cap / nis;
      nis = nis_cap;
    }
    t += 0.1;
    return AdaptiveSample{t, nis, 3, nu2, 3 * r, 3 * p};
  }
};

TEST(AdaptiveNoise, ConsistentInnovationsLeaveTheNoiseAlone) {
  // 1000 blocks of 10 s (about 28 h at 10 Hz) drawn from the model itself: q stays 1.
  for (unsigned seed : {1u, 2u, 3u}) {
    AdaptiveNoise a(on());
    Stream s(seed);
    for (int i = 0; i < 100000; ++i) a.add(0, s.next(1.0));
    EXPECT_EQ(a.scale(), 1.0) << "seed " << seed;
    EXPECT_EQ(a.increases(), 0) << "seed " << seed;
  }
}

TEST(AdaptiveNoise, TooLittleProcessNoiseIsMatched) {
  // The actual HPHᵀ part is 4x the predicted (p = r: the block's NIS ratio is 2.5): the first
  // increase, in the first block, is the smaller of the covariance-matching estimate (4) and the
  // NIS ratio (2.5) — an excess R could explain as well never buys more than the NIS shows.
  AdaptiveNoise a(on());
  Stream s(7);
  double first = 0;
  int at = -1;
  for (int i = 0; i < 2000 && at < 0; ++i)
    if (a.add(0, s.next(4.0))) {
      first = a.scale();
      at = i;
    }
  ASSERT_GE(at, 0);
  EXPECT_LE(at, 101);  // the first block: 10 s of epochs at 10 Hz (stamps summed in steps of 0.1 s)
  EXPECT_NEAR(first, 2.5, 0.5);
}

TEST(AdaptiveNoise, OneOutlierMovesNothingARunOfRejectionsDoes) {
  const double gate = 50;
  AdaptiveNoise a(on());
  Stream s(11);
  for (int i = 0; i < 300; ++i) a.add(0, s.next(1.0, gate));
  // One wild innovation (NIS 1e6, capped at the gate as the filter passes rejected ones).
  AdaptiveSample wild = s.next(1.0);
  wild.nu2 *= 1e6 / wild.nis;  // an innovation of NIS 1e6 ...
  wild.nis = 1e6;
  const double cap = gate / wild.nis;  // ... as the filter passes it on once rejected
  wild.nis *= cap;
  wild.nu2 *= cap;
  a.add(0, wild);
  for (int i = 0; i < 300; ++i) a.add(0, s.next(1.0, gate));
  EXPECT_EQ(a.scale(), 1.0);
  // Every innovation rejected for 10 s (a filter that lost track): q is raised.
  for (int i = 0; i < 120; ++i) a.add(0, s.next(1e4, gate));
  EXPECT_GT(a.scale(), 10.0);
}

TEST(AdaptiveNoise, RelaxesOnceConsistentAndTypesAreTestedApart) {
  AdaptiveNoise a(on());
  Stream s(5), v(6);
  for (int i = 0; i < 200; ++i) a.add(0, s.next(9.0));
  const double raised = a.scale();
  ASSERT_GT(raised, 2.0);
  // Consistent innovations of another type do not mix into type 0's blocks, but relax q.
  for (int i = 0; i < 6000; ++i) a.add(1, v.next(1.0));
  EXPECT_LT(a.scale(), raised);
  EXPECT_GE(a.scale(), 1.0);
  EXPECT_EQ(a.max_scale_reached(), raised);
}

TEST(AdaptiveNoise, OneMisfitRaisesOnceNotOncePerType) {
  // Position and velocity innovations of the same second both far too large (10 epochs each, the
  // early decision's size): one increase spends that evidence, and the other type's open block,
  // predicted under the old q, does not raise q again (before, each type multiplied q in turn).
  AdaptiveNoise a(on());
  Stream s(21), v(22);
  for (int i = 0; i < 10; ++i) {
    a.add(0, s.next(30.0));
    a.add(1, v.next(30.0));
  }
  ASSERT_EQ(a.increases(), 1);
  EXPECT_GT(a.scale(), 5.0);
  ASSERT_EQ(a.events().size(), 1u);
  EXPECT_EQ(a.events()[0].q_from, 1.0);
}

TEST(AdaptiveNoise, HealsOnceTheInnovationsAreConsistentAgain) {
  // A stretch whose innovations need q ~ 1e4 (a filter that was wrong there), then innovations
  // consistent with the model itself: q comes back to 1 within a few blocks, not minutes, and the
  // stretch above the fail scale is reported while it lasts.
  AdaptiveNoise a(on());
  Stream s(31);
  for (int i = 0; i < 400 && a.scale() < 1e3; ++i) a.add(0, s.next(1e4));
  ASSERT_GT(a.scale(), AdaptiveNoise::kFailScale);
  ASSERT_NE(a.above_fail_since(), nullptr);
  // Innovations of a filter the model fits again: the predicted process-noise part grows with q
  // (tr HPHᵀ = 3·p·q), the actual one is the model's (p).
  std::mt19937_64 rng(32);
  std::normal_distribution<double> n(0.0, 1.0);
  int blocks = 0;
  double t = s.t;
  for (int i = 0; i < 3000 && a.scale() > 1.0; ++i) {
    const double q = a.scale(), pred = s.p * q + s.r;
    double nu2 = 0;
    for (int k = 0; k < 3; ++k) nu2 += std::pow(n(rng) * std::sqrt(s.p + s.r), 2);
    t += 0.1;
    if (a.add(0, AdaptiveSample{t, nu2 / pred, 3, nu2, 3 * s.r, 3 * s.p * q})) ++blocks;
  }
  EXPECT_EQ(a.scale(), 1.0);
  EXPECT_LE(blocks, 6);  // at most ×0.1 per 10-s block: ~1e3 → 1 in 3 to 4 blocks when the evidence says so
  EXPECT_EQ(a.above_fail_since(), nullptr);
  EXPECT_GT(a.decreases(), 0);
}

TEST(AdaptiveNoise, OffChangesNothing) {
  AdaptiveNoiseConfig c;
  c.enabled = false;
  AdaptiveNoise a(c);
  Stream s(3);
  for (int i = 0; i < 500; ++i) EXPECT_FALSE(a.add(0, s.next(100.0)));
  EXPECT_EQ(a.scale(), 1.0);
}

}  // namespace
}  // namespace calbench::inmotion
