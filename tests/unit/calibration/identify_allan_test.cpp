// Overlapping Allan deviation and the noise-term fit on simulated gyro noise of known levels.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "calibration/identification/allan.hpp"
#include "calibration/identification/noise_processes.hpp"

namespace calbench::identification {
namespace {

constexpr double kDegPerHour = 3.141592653589793 / 180.0 / 3600.0;  // rad/s per °/h
constexpr double kSqrtHour = 60.0;

TEST(IdentifyAllan, WhiteNoiseFollowsNOverRootTauWithinItsIntervals) {
  std::mt19937_64 rng(11);
  const double dt = 0.01, N = 0.2 * kDegPerHour * 60.0;  // 0.2 °/√h in rad/√s
  const auto y = simulate_white(1 << 20, dt, N, rng);
  const auto pts = allan_deviation(y, dt);
  ASSERT_GE(pts.size(), 15u);
  int inside = 0;
  for (const auto& p : pts) {
    const double truth = N / std::sqrt(p.tau);
    EXPECT_LT(p.lo, p.adev);
    EXPECT_GT(p.hi, p.adev);
    inside += (p.lo <= truth && truth <= p.hi);
    // τ = dt: σ² = N²/dt exactly the sample variance (within sampling error).
    if (p.m == 1) {
      EXPECT_NEAR(p.adev, truth, 0.01 * truth);
    }
  }
  // 68 % intervals: most of them contain the truth (not asserting exactly 68 %).
  EXPECT_GE(inside, static_cast<int>(0.5 * static_cast<double>(pts.size())));
  const AllanFit f = fit_allan(pts);
  EXPECT_NEAR(f.N.value, N, 0.03 * N);
}

TEST(IdentifyAllan, FitRecoversWhiteFlickerAndRandomWalkLevels) {
  // A MEMS-gyro-like mixture: ARW 0.1 °/√h, bias instability 5 °/h, rate random walk chosen so
  // that it overtakes the flicker plateau near 1000 s. 5 Hz, 2^21 samples (4.9 days).
  const double dt = 0.2;
  const std::size_t n = 1u << 21;
  const double N = 0.1 * kDegPerHour * kSqrtHour;  // rad/√s
  const double B = 5.0 * kDegPerHour;              // rad/s
  const double K = B * std::sqrt(3.0 * 2.0 * std::log(2.0) / 3.141592653589793 / 1000.0);  // rad/s/√s
  std::vector<double> eN, eB, eK;
  for (int seed = 0; seed < 3; ++seed) {
    std::mt19937_64 rng(500 + seed);
    auto y = simulate_white(n, dt, N, rng);
    const auto fl = simulate_flicker(n, dt, B, rng);
    const auto rw = simulate_random_walk(n, dt, K, rng);
    for (std::size_t i = 0; i < n; ++i) y[i] += fl[i] + rw[i];
    const auto pts = allan_deviation(y, dt);
    const AllanFit f = fit_allan(pts);
    std::printf("seed %d: N %.4f (true %.4f) deg/sqrt(h)  B %.3f (true %.3f) deg/h  K %.3f (true %.3f) deg/h/sqrt(h)"
                "  Q %.3g R %.3g  B from min %.3f\n",
                seed, f.N.value / (kDegPerHour * kSqrtHour), N / (kDegPerHour * kSqrtHour),
                f.B.value / kDegPerHour, B / kDegPerHour, f.K.value / (kDegPerHour / kSqrtHour),
                K / (kDegPerHour / kSqrtHour), f.Q.value, f.R.value, f.B_from_min / kDegPerHour);
    eN.push_back(std::abs(f.N.value / N - 1));
    eB.push_back(std::abs(f.B.value / B - 1));
    eK.push_back(std::abs(f.K.value / K - 1));
    // The fitted standard errors are finite and positive for the terms present.
    EXPECT_TRUE(f.N.present && f.B.present && f.K.present);
    EXPECT_GT(f.K.se, 0.0);
  }
  std::sort(eN.begin(), eN.end());
  std::sort(eB.begin(), eB.end());
  std::sort(eK.begin(), eK.end());
  // Median over the seeds, each term within 10 %.
  EXPECT_LT(eN[1], 0.10);
  EXPECT_LT(eB[1], 0.10);
  EXPECT_LT(eK[1], 0.10);
}

TEST(IdentifyAllan, GaussMarkovAlternativeFindsTheCorrelationTime) {
  std::mt19937_64 rng(21);
  const double dt = 1.0, sigma = 1e-4, T = 200.0, N = 2e-4;
  auto y = simulate_white(1 << 20, dt, N, rng);
  const auto gm = simulate_gauss_markov(1 << 20, dt, sigma, T, rng);
  for (std::size_t i = 0; i < y.size(); ++i) y[i] += gm[i];
  const AllanFit f = fit_allan(allan_deviation(y, dt));
  std::printf("GM alternative: sigma %.3g (true %.3g)  T %.1f (true %.1f)  chi2 %.2f vs five-term %.2f\n",
              f.gm_sigma, sigma, f.gm_T, T, f.gm_chi2, f.chi2);
  ASSERT_TRUE(f.gm_present);
  EXPECT_NEAR(f.gm_sigma, sigma, 0.2 * sigma);
  EXPECT_NEAR(f.gm_T, T, 0.3 * T);
  EXPECT_LT(f.gm_chi2, f.chi2);  // the GM shape describes a GM process better than B + K
}

TEST(IdentifyAllan, TermFormulas) {
  // Values from the definitions (IEEE Std 952 annex C).
  EXPECT_DOUBLE_EQ(avar_white(2.0, 4.0), 1.0);
  EXPECT_DOUBLE_EQ(avar_rate_random_walk(3.0, 2.0), 6.0);
  EXPECT_DOUBLE_EQ(avar_quantisation(1.0, 3.0), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(avar_rate_ramp(2.0, 1.0), 2.0);
  EXPECT_NEAR(std::sqrt(avar_bias_instability(1.0)), 0.6643, 1e-4);
  // Gauss–Markov limits: (2/3)σ²τ/T for τ ≪ T, 2σ²T/τ for τ ≫ T.
  EXPECT_NEAR(avar_gauss_markov(1.0, 100.0, 0.01) / (2.0 / 3.0 * 0.01 / 100.0), 1.0, 1e-3);
  EXPECT_NEAR(avar_gauss_markov(1.0, 1.0, 1e6) / (2.0 / 1e6), 1.0, 1e-5);
}

TEST(IdentifyAllan, RejectsTooShort) {
  std::vector<double> y(5, 1.0);
  EXPECT_THROW(allan_deviation(y, 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace calbench::identification
