// The diagnosis engine shared by the bench and the drive diagnosis (calibration/diagnosis/
// diagnosis_engine.hpp, residual_stats.hpp): checked against plain dense linear algebra.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "calibration/diagnosis/diagnosis_engine.hpp"
#include "calibration/diagnosis/residual_stats.hpp"

namespace calbench::diag {
namespace {

struct Problem {
  Eigen::MatrixXd R, X;
  Eigen::VectorXd z;
};

// A random SPD covariance (banded plus a smooth part), regressors and data.
Problem random_problem(int n, int p, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  Problem P;
  P.R = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < n; ++k)
    for (int l = 0; l < n; ++l) P.R(k, l) = 0.5 * std::exp(-std::abs(k - l) / 3.0) + (k == l ? 1.0 + 0.1 * k : 0.0);
  P.X.resize(n, p);
  P.z.resize(n);
  for (int k = 0; k < n; ++k) {
    for (int c = 0; c < p; ++c) P.X(k, c) = g(rng) + (c == 0 ? 1.0 : 0.0);
    P.z(k) = g(rng);
  }
  return P;
}

TEST(DiagnosisEngine, WhitenGivesTheGlsNormalEquationsAndLogDet) {
  const Problem P = random_problem(30, 4, 1);
  LinearDataset S;
  whiten(S, P.R, P.z, P.X, 0);
  const Eigen::MatrixXd Ri = P.R.inverse();
  EXPECT_LT((S.G - P.X.transpose() * Ri * P.X).norm(), 1e-9 * S.G.norm());
  EXPECT_LT((S.g - P.X.transpose() * Ri * P.z).norm(), 1e-9 * S.g.norm());
  EXPECT_NEAR(S.zz, P.z.dot(Ri * P.z), 1e-9 * S.zz);
  EXPECT_NEAR(S.logdet, std::log(P.R.determinant()), 1e-9);
  EXPECT_EQ(S.n_low, 30);
}

TEST(DiagnosisEngine, WhitenRaisesTheDiagonalOfANearlySingularCovariance) {
  // Rank one: the Cholesky factorisation fails; with retries the diagonal is raised until it works.
  Eigen::MatrixXd R = Eigen::MatrixXd::Ones(5, 5);
  R.diagonal().array() -= 1e-3;  // slightly indefinite
  const Eigen::VectorXd z = Eigen::VectorXd::LinSpaced(5, 0, 1);
  const Eigen::MatrixXd X = Eigen::MatrixXd::Ones(5, 1);
  LinearDataset S;
  whiten(S, R, z, X, 8);
  EXPECT_TRUE(std::isfinite(S.logdet));
  EXPECT_TRUE(std::isfinite(S.zz));
  EXPECT_GT(S.G(0, 0), 0);
}

TEST(DiagnosisEngine, FitThroughAColumnMapIsTheGlsSolutionAndItsChi2) {
  const Problem P = random_problem(40, 3, 2);
  LinearDataset S;
  whiten(S, P.R, P.z, P.X, 0);
  // Parameters 0..2 map to columns 2, 0, 1 (a model's own order, as the drive maps global columns).
  const ColumnMap cm = {{2, 0}, {0, 1}, {1, 2}};
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(3, 3);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(3);
  accumulate_normal(A, b, S, cm);
  Eigen::VectorXd theta;
  Eigen::MatrixXd cov;
  double logdet_info = 0;
  solve_scaled(A, b, 0.0, theta, cov, logdet_info);
  const Eigen::MatrixXd Ri = P.R.inverse();
  const Eigen::MatrixXd info = P.X.transpose() * Ri * P.X;
  const Eigen::VectorXd gls = info.ldlt().solve(P.X.transpose() * Ri * P.z);
  EXPECT_NEAR(theta(0), gls(2), 1e-9);
  EXPECT_NEAR(theta(1), gls(0), 1e-9);
  EXPECT_NEAR(theta(2), gls(1), 1e-9);
  EXPECT_NEAR(cov(1, 1), info.inverse()(0, 0), 1e-9 * std::abs(info.inverse()(0, 0)));
  EXPECT_NEAR(logdet_info, std::log(info.determinant()), 1e-8);
  // χ² of the fit: the whitened residual's squared norm.
  const Eigen::VectorXd r = P.z - P.X * gls;
  EXPECT_NEAR(quadratic_chi2(S.G, S.g, S.zz, cm, theta), r.dot(Ri * r), 1e-8);
}

TEST(DiagnosisEngine, SmoothedDriftFollowsASlowResidual) {
  // Parents of 1 s; a residual that is a slow ramp is attributed to the drift almost entirely,
  // white noise mostly not.
  std::vector<ParentBlock> parents(60);
  for (int k = 0; k < 60; ++k) {
    parents[k].t_mid = k + 0.5;
    parents[k].duration = 1.0;
  }
  const double ds = 1.0, tau = 200.0, white = 0.01;
  LinearDataset S;
  S.drift_sigma = ds;
  S.drift_tau = tau;
  for (int k = 0; k < 60; ++k) S.parents.push_back(k);
  Eigen::MatrixXd R(60, 60);
  for (int k = 0; k < 60; ++k)
    for (int l = 0; l < 60; ++l) R(k, l) = drift_covariance(parents[k], parents[l], ds, tau) + (k == l ? white : 0.0);
  whiten(S, R, Eigen::VectorXd::Zero(60), Eigen::MatrixXd::Zero(60, 1), 0);
  const Eigen::VectorXd ramp = Eigen::VectorXd::LinSpaced(60, -0.5, 0.5);
  const Eigen::VectorXd d = smoothed_drift(parents, S, ramp);
  EXPECT_LT((d - ramp).norm(), 0.05 * ramp.norm());
  Eigen::VectorXd alt(60);
  for (int k = 0; k < 60; ++k) alt(k) = k % 2 ? 0.1 : -0.1;
  EXPECT_LT(smoothed_drift(parents, S, alt).norm(), 0.2 * alt.norm());
}

TEST(ResidualStats, WorstWindowsAreTheLargestMeansInTheirSigma) {
  // window → (Σ residual, weight): |mean|·√weight / σ.
  std::map<int, std::pair<double, double>> sums = {
      {0, {1.0, 4.0}},    // |0.25|·2 = 0.5
      {1, {-9.0, 9.0}},   // 1·3 = 3
      {2, {4.0, 16.0}},   // 0.25·4 = 1
      {3, {0.0, 1.0}},    // 0
      {4, {-2.0, 1.0}}};  // 2
  EXPECT_EQ(worst_windows(sums, 1.0), (std::vector<int>{1, 4, 2}));
  EXPECT_EQ(worst_windows(sums, 0.5), (std::vector<int>{1, 4, 2}));
  EXPECT_TRUE(worst_windows({}, 1.0).empty());
}

TEST(ResidualStats, UnexplainedKeepsTheFourStrongestCorrelations) {
  AxisStats s;
  s.chi2_dof = 3;
  s.high_chi2_dof = 2;
  s.ljung_box_p = 1e-6;
  s.systematic_rms = 0.5;
  std::vector<ConditionCorrelation> c;
  for (int k = 0; k < 6; ++k) c.push_back({"c" + std::to_string(k), 0.9 - 0.1 * k});
  const DiagUnexplained u = unexplained_axis(4, s, c);
  EXPECT_EQ(u.sensor, 1);
  EXPECT_EQ(u.axis, 1);
  EXPECT_EQ(u.chi2_dof, 3);
  EXPECT_EQ(u.high_chi2_dof, 2);
  EXPECT_EQ(u.systematic_rms, 0.5);
  ASSERT_EQ(u.correlations.size(), 4u);
  EXPECT_EQ(u.correlations.back().condition, "c3");
}

TEST(ResidualStats, WhitenessOfWhiteAndOfCorrelatedResiduals) {
  // Identity covariance: χ²/dof is the mean square; a random walk is not white (Ljung–Box p tiny).
  const int n = 200;
  LinearDataset S;
  for (int k = 0; k < n; ++k) S.parents.push_back(k);
  whiten(S, Eigen::MatrixXd::Identity(n, n), Eigen::VectorXd::Zero(n), Eigen::MatrixXd::Zero(n, 1), 0);
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  Eigen::VectorXd w(n), walk(n);
  double acc = 0;
  for (int k = 0; k < n; ++k) {
    w(k) = g(rng);
    acc += g(rng);
    walk(k) = acc;
  }
  AxisStats a, b;
  const Eigen::VectorXd rw = whiteness(S, w, 0, a);
  EXPECT_NEAR(a.chi2_dof, w.squaredNorm() / n, 1e-12);
  EXPECT_LT((rw - w).norm(), 1e-12);
  EXPECT_GT(a.ljung_box_p, 1e-3);
  whiteness(S, walk, 0, b);
  EXPECT_LT(b.ljung_box_p, 1e-6);
}

}  // namespace
}  // namespace calbench::diag
