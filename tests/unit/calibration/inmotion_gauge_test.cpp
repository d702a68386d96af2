// The covariance operations on the in-motion filter's unobservable rotation (calibration/inmotion/
// gauge.hpp), on random covariances: the carry keeps the rotation's conditional covariance while
// its direction moves and leaves P a covariance; the restore after a widening sets it back; states of
// exactly zero variance (the augmented layout's unused exp-cosine axes) do not switch it off.
#include <gtest/gtest.h>

#include <random>

#include "calibration/inmotion/gauge.hpp"

using namespace calbench::inmotion;
using Mat = Eigen::MatrixXd;

namespace {

Mat random_cov(int n, std::mt19937& rng) {
  std::normal_distribution<double> g;
  Mat A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = g(rng);
  return A * A.transpose() / n + 1e-3 * Mat::Identity(n, n);
}

Mat random_dir(int n, std::mt19937& rng, double scale = 1.0) {
  std::normal_distribution<double> g;
  Mat N(n, 3);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) N(i, k) = scale * g(rng);
  return N;
}

Eigen::Matrix3d S_of(const Mat& P, const Mat& N) {
  return (N.transpose() * P.llt().solve(N)).inverse();
}

// P's conditional covariance along N is S0 (to rounding), and P is still a covariance.
void expect_held(const Mat& P, const Mat& N, const Eigen::Matrix3d& S0) {
  EXPECT_LT((S_of(P, N) - S0).cwiseAbs().maxCoeff(), 1e-9 * S0.cwiseAbs().maxCoeff());
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Mat>(P).eigenvalues().minCoeff(), -1e-12);
}

}  // namespace

TEST(InMotionGauge, CarryKeepsTheConditionalCovarianceAndPositiveness) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 42;
    Mat P = random_cov(n, rng);
    const Mat N0 = random_dir(n, rng), N1 = N0 + random_dir(n, rng, 0.3);
    const Eigen::Matrix3d S0 = S_of(P, N0);
    const Eigen::Vector3d sig = carry_unobservable_rotation(P, N0, N1);
    ASSERT_TRUE(sig.allFinite());
    EXPECT_NEAR((sig - S0.diagonal().cwiseSqrt()).norm(), 0, 1e-12);
    EXPECT_EQ((P - P.transpose()).cwiseAbs().maxCoeff(), 0.0);
    // The conditional covariance along the new direction is the old one along the old.
    expect_held(P, N1, S0);
  }
}

TEST(InMotionGauge, RestoreSetsItBackAfterAWidening) {
  std::mt19937 rng(11);
  const int n = 30;
  Mat P = random_cov(n, rng);
  const Mat N = random_dir(n, rng);
  const Eigen::Matrix3d S0 = S_of(P, N);
  P.topRows(9) *= 3.0;  // a widening of the first block, D·P·D
  P.leftCols(9) *= 3.0;
  ASSERT_GT((S_of(P, N) - S0).cwiseAbs().maxCoeff(), 1e-3 * S0.cwiseAbs().maxCoeff());  // the widening moved it
  restore_unobservable_rotation(P, N, S0);
  expect_held(P, N, S0);
}

TEST(InMotionGauge, ZeroVarianceStatesAreLeftOut) {
  std::mt19937 rng(3);
  const int n = 48;
  Mat P = random_cov(n, rng);
  Mat N = random_dir(n, rng);
  for (int i : {44, 45, 46}) {  // three states never used: zero rows and columns, N zero there
    P.row(i).setZero();
    P.col(i).setZero();
    N.row(i).setZero();
  }
  ASSERT_NE(P.llt().info(), Eigen::Success);  // the whole P does not factorise
  Eigen::Matrix3d S;
  ASSERT_TRUE(unobservable_rotation_covariance(P, N, S));
  std::vector<int> keep;
  for (int i = 0; i < n; ++i)
    if (i < 44 || i > 46) keep.push_back(i);
  const Mat Pk = P(keep, keep), Nk = N(keep, Eigen::all);
  EXPECT_LT((S - S_of(Pk, Nk)).cwiseAbs().maxCoeff(), 1e-12 * S.cwiseAbs().maxCoeff());
  // A direction reaching into a state of zero variance has no finite conditional covariance.
  N(45, 1) = 0.5;
  EXPECT_FALSE(unobservable_rotation_covariance(P, N, S));
  EXPECT_TRUE(carry_unobservable_rotation(P, N, N).isZero());
}
