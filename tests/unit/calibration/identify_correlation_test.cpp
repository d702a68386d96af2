// Statistical correlation function (eq 25) by FFT against the direct sum, and the paper's and the
// NLS estimators on exact (noise-free) correlation functions, where each must be exact.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "calibration/identification/correlation.hpp"
#include "calibration/identification/correlation_fit.hpp"
#include "calibration/identification/noise_processes.hpp"

namespace calbench::identification {
namespace {

TEST(IdentifyCorrelation, FftMatchesDirectSumWithoutWrapAround) {
  std::mt19937_64 rng(7);
  // Odd length, large offset, every lag up to N − 1 (the wrap-around would show at long lags).
  std::vector<double> x = simulate_gauss_markov(1001, 1.0, 2.0, 30.0, rng);
  for (double& v : x) v += 1e3;
  const auto a = autocovariance(x, 1000);
  const auto b = autocovariance_direct(x, 1000);
  ASSERT_EQ(a.size(), 1001u);
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_NEAR(a[k], b[k], 1e-9 * b[0]) << "lag " << k;
}

TEST(IdentifyCorrelation, DefinitionOnATinySeries) {
  // x = 1,2,3,4: mean 2.5, x̃ = −1.5,−0.5,0.5,1.5; K̂(1) = (0.75 − 0.25 + 0.75)/4.
  const std::vector<double> x{1, 2, 3, 4};
  const auto k = autocovariance(x, 3);
  EXPECT_NEAR(k[0], 5.0 / 4.0, 1e-14);
  EXPECT_NEAR(k[1], 1.25 / 4.0, 1e-14);
  EXPECT_NEAR(k[2], (-0.75 - 0.75) / 4.0, 1e-14);
  EXPECT_NEAR(k[3], -2.25 / 4.0, 1e-14);
  EXPECT_EQ(autocovariance(x, 99).size(), 4u);  // clamped to N − 1
}

TEST(IdentifyCorrelation, FftSizeIsSmoothAndLargeEnough) {
  for (std::size_t n : {1u, 2u, 11u, 97u, 1000003u}) {
    const std::size_t m = fft_size(n);
    EXPECT_GE(m, n);
    std::size_t r = m;
    EXPECT_LE(static_cast<double>(m), 1.25 * static_cast<double>(n) + 64);
    for (std::size_t p : {2u, 3u, 5u})
      while (r % p == 0) r /= p;
    EXPECT_EQ(r, 1u);
  }
}

std::vector<double> exact_K(const DriftModel& m, double dt, std::size_t L) {
  std::vector<double> K(L + 1);
  for (std::size_t j = 0; j <= L; ++j) K[j] = m.correlation(static_cast<double>(j) * dt);
  return K;
}

TEST(IdentifyCorrelation, PaperEstimatesAreExactOnExactCurves) {
  const DriftModel e{DriftModelKind::exponential, 3.0, 0.02, 0};
  const auto Ke = exact_K(e, 1.0, 200);
  const PaperExponential pe = paper_exponential(Ke, 1.0, 200);
  ASSERT_TRUE(pe.valid);
  EXPECT_NEAR(pe.sigma, 3.0, 1e-12);
  EXPECT_NEAR(pe.alpha, 0.02, 1e-12);
  EXPECT_EQ(pe.lags_used, 200u);

  // τ_β = 0.5π/β = 15.708 s lies between lags (dt = 1 s): linear interpolation of K̂ around the
  // zero costs a little accuracy in β, which then biases α (the paper's formula divides by Στ).
  const DriftModel c{DriftModelKind::exp_cosine, 2.0, 0.05, 0.1, };
  const auto Kc = exact_K(c, 1.0, 100);
  const PaperExpCosine pc = paper_exp_cosine(Kc, 1.0, 100);
  ASSERT_TRUE(pc.valid);
  EXPECT_NEAR(pc.sigma, 2.0, 1e-12);
  EXPECT_NEAR(pc.beta, 0.1, 2e-3);
  EXPECT_NEAR(pc.alpha, 0.05, 5e-3);
  EXPECT_EQ(pc.lags_used, 15u);
  // With a step that puts the zero on a lag, β is exact and so is α.
  const double dt = 0.5 * std::numbers::pi / 0.1 / 20.0;
  const PaperExpCosine pc2 = paper_exp_cosine(exact_K(c, dt, 60), dt, 60);
  ASSERT_TRUE(pc2.valid);
  EXPECT_NEAR(pc2.beta, 0.1, 1e-9);
  EXPECT_NEAR(pc2.alpha, 0.05, 1e-9);
  // No sign change: the exp-cosine estimate is not available.
  EXPECT_FALSE(paper_exp_cosine(Ke, 1.0, 200).valid);
}

TEST(IdentifyCorrelation, NlsIsExactOnExactCurves) {
  const DriftModel e{DriftModelKind::exponential, 3.0, 0.02, 0};
  const NlsFit fe = fit_exponential(exact_K(e, 1.0, 300), 1.0, 100000, 1, 300);
  ASSERT_TRUE(fe.converged);
  EXPECT_NEAR(fe.sigma, 3.0, 1e-7);
  EXPECT_NEAR(fe.alpha, 0.02, 1e-9);
  EXPECT_NEAR(fe.white_var, 0.0, 1e-6);
  EXPECT_GT(fe.se_alpha, 0.0);

  const DriftModel c{DriftModelKind::exp_cosine, 2.0, 0.05, 0.1};
  const NlsFit fc = fit_exp_cosine(exact_K(c, 1.0, 150), 1.0, 100000, 1, 150);
  ASSERT_TRUE(fc.converged);
  EXPECT_NEAR(fc.sigma, 2.0, 1e-7);
  EXPECT_NEAR(fc.alpha, 0.05, 1e-9);
  EXPECT_NEAR(fc.beta, 0.1, 1e-9);
}

TEST(IdentifyCorrelation, WhiteNoiseGoesToLagZeroNotToSigma) {
  // GM drift plus white noise 3× its σ: K̂(0) = σ² + σ_w², the paper's σ² = K̂(0) absorbs the
  // white noise, the NLS (lags ≥ 1) does not and reports it as white_var.
  std::mt19937_64 rng(3);
  const double sigma = 1.0, T = 50.0, sw = 3.0;
  auto x = simulate_gauss_markov(200000, 1.0, sigma, T, rng);
  std::normal_distribution<double> n01;
  for (double& v : x) v += sw * n01(rng);
  const Identification id = identify(x, 1.0);
  EXPECT_NEAR(id.paper_exp.sigma, std::sqrt(sigma * sigma + sw * sw), 0.05);
  EXPECT_NEAR(id.exp.sigma, sigma, 0.1);
  EXPECT_NEAR(1.0 / id.exp.alpha, T, 0.15 * T);
  EXPECT_NEAR(id.exp.white_var, sw * sw, 0.1 * sw * sw);
}

TEST(IdentifyCorrelation, RejectsBadSeries) {
  std::vector<double> shortx(10, 1.0);
  EXPECT_THROW(identify(shortx, 1.0), std::invalid_argument);
  std::vector<double> constant(1000, 4.2);
  EXPECT_THROW(identify(constant, 1.0), std::invalid_argument);
  std::mt19937_64 rng(1);
  auto x = simulate_gauss_markov(1000, 1.0, 1.0, 10.0, rng);
  x[500] = std::nan("");
  EXPECT_THROW(identify(x, 1.0), std::invalid_argument);
  x[500] = 0;
  EXPECT_THROW(identify(x, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace calbench::identification
