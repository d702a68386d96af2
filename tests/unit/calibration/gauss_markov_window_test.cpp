// Covariance of window means of a first-order Gauss–Markov process (gauss_markov_window.hpp):
// against a direct numerical double integral of e^{−|s−t|/τ}, in every branch (disjoint, same
// window, overlapping, point in a window), and against the sample covariance of simulated means.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "calibration/gauss_markov_window.hpp"
#include "calibration/identification/noise_processes.hpp"

namespace calbench {
namespace {

// Midpoint-rule double integral of e^{−|s−t|/τ} over the two windows, divided by d1·d2.
double numeric(double c1, double d1, double c2, double d2, double tau) {
  const int n = 2000;
  double s = 0;
  for (int i = 0; i < n; ++i) {
    const double t1 = c1 - 0.5 * d1 + (i + 0.5) * d1 / n;
    for (int j = 0; j < n; ++j) {
      const double t2 = c2 - 0.5 * d2 + (j + 0.5) * d2 / n;
      s += std::exp(-std::abs(t1 - t2) / tau);
    }
  }
  return s / (static_cast<double>(n) * n);
}

TEST(GaussMarkovWindow, MatchesTheDoubleIntegralInEveryBranch) {
  struct Case {
    double c1, d1, c2, d2, tau;
  };
  const Case cases[] = {
      {10, 8, 30, 8, 60},     // disjoint
      {10, 8, 18, 8, 60},     // touching
      {0, 60, 200, 20, 60},   // disjoint, windows of τ and more
      {5, 10, 5, 10, 60},     // same window
      {5, 120, 5, 120, 60},   // same window, two correlation times long
      {5, 10, 8, 10, 60},     // overlapping
      {0, 30, 4, 6, 20},      // one inside the other
      {3, 0, 0, 10, 60},      // a point inside a window (checked against the 1-D integral below)
  };
  for (const Case& c : cases) {
    double expect;
    if (c.d1 == 0) {
      double s = 0;
      const int n = 200000;
      for (int j = 0; j < n; ++j) s += std::exp(-std::abs(c.c1 - (c.c2 - 0.5 * c.d2 + (j + 0.5) * c.d2 / n)) / c.tau);
      expect = s / n;
    } else {
      expect = numeric(c.c1, c.d1, c.c2, c.d2, c.tau);
    }
    const double got = gm_window_correlation(c.c1, c.d1, c.c2, c.d2, c.tau);
    EXPECT_NEAR(got, expect, 1e-6) << c.c1 << ' ' << c.d1 << ' ' << c.c2 << ' ' << c.d2 << ' ' << c.tau;
    EXPECT_DOUBLE_EQ(got, gm_window_correlation(c.c2, c.d2, c.c1, c.d1, c.tau));  // symmetric
  }
}

TEST(GaussMarkovWindow, PointLimitAndContinuityBetweenBranches) {
  // Windows of length 0 are point values.
  EXPECT_DOUBLE_EQ(gm_window_correlation(0, 0, 30, 0, 60), std::exp(-0.5));
  EXPECT_DOUBLE_EQ(gm_window_correlation(7, 0, 7, 0, 60), 1.0);
  // Averaging lowers the variance and raises the correlation of neighbours.
  EXPECT_LT(gm_window_correlation(0, 8, 0, 8, 60), 1.0);
  EXPECT_GT(gm_window_correlation(0, 8, 20, 8, 60), std::exp(-20.0 / 60));
  // Continuous where the branch changes: just disjoint vs just overlapping, same vs nearly same,
  // tiny window vs point.
  EXPECT_NEAR(gm_window_correlation(0, 8, 8 + 1e-7, 8, 60), gm_window_correlation(0, 8, 8 - 1e-7, 8, 60), 1e-8);
  EXPECT_NEAR(gm_window_correlation(0, 8, 1e-5, 8, 60), gm_window_correlation(0, 8, 0, 8, 60), 1e-6);
  EXPECT_NEAR(gm_window_correlation(0, 8, 0, 8 + 1e-5, 60), gm_window_correlation(0, 8, 0, 8, 60), 1e-6);
  EXPECT_NEAR(gm_window_correlation(1, 1e-6, 0, 10, 60), gm_window_correlation(1, 0, 0, 10, 60), 1e-6);
  EXPECT_NEAR(gm_window_correlation(0, 1e-4, 0, 1e-4, 60), 1.0, 1e-6);
}

TEST(GaussMarkovWindow, MatchesTheSampleCovarianceOfSimulatedMeans) {
  // Means of a simulated process (dt 0.1 s, τ 20 s) over 10 s windows, consecutive and 30 s apart.
  std::mt19937_64 rng(7);
  const double dt = 0.1, tau = 20, sigma = 2.0;
  const int w = 100;  // samples per window
  double v0 = 0, c1 = 0, c3 = 0;
  int n = 0;
  for (int rep = 0; rep < 800; ++rep) {
    const auto x = identification::simulate_gauss_markov(40 * w, dt, sigma, tau, rng);
    for (int k = 0; k + 3 < 40; k += 4) {
      double m[4] = {0, 0, 0, 0};
      for (int q = 0; q < 4; ++q)
        for (int i = 0; i < w; ++i) m[q] += x[(k + q) * w + i] / w;
      v0 += m[0] * m[0];
      c1 += m[0] * m[1];
      c3 += m[0] * m[3];
      ++n;
    }
  }
  // 8000 pairs: the sample (co)variances are good to a few per cent of σ².
  EXPECT_NEAR(v0 / n / (sigma * sigma), gm_window_correlation(0, 10, 0, 10, tau), 0.06);
  EXPECT_NEAR(c1 / n / (sigma * sigma), gm_window_correlation(0, 10, 10, 10, tau), 0.06);
  EXPECT_NEAR(c3 / n / (sigma * sigma), gm_window_correlation(0, 10, 30, 10, tau), 0.06);
  // The point model is off by more than that for the variance of a window mean.
  EXPECT_GT(std::abs(v0 / n / (sigma * sigma) - 1.0), 0.1);
}

}  // namespace
}  // namespace calbench
