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
  // The actual HPHᵀ part is 4x the predicted: the first increase is the covariance-matching
  // estimate of that factor (a block of 100 epochs: within 25 %), and it happens in the first block.
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
  EXPECT_NEAR(first, 4.0, 1.0);
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
