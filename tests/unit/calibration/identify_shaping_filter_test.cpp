// Shaping filters (eqs 22, 35–36): the output H·x of the discretised filter must have exactly the
// identified correlation function, and the discretisation must be consistent.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "calibration/identification/shaping_filter.hpp"

namespace calbench::identification {
namespace {

// Stationary correlation of the output at lag k·dt: H Φ^k P∞ Hᵀ.
double output_correlation(const ShapingFilter& f, const DiscreteShapingFilter& d, int k,
                          const Eigen::RowVector2d& H) {
  Eigen::Matrix2d Pk = f.P_inf;
  for (int i = 0; i < k; ++i) Pk = d.Phi * Pk;
  return H * Pk * H.transpose();
}

TEST(IdentifyShapingFilter, ExponentialEq22) {
  const DriftModel m{DriftModelKind::exponential, 0.3, 1.0 / 300.0, 0};
  const ShapingFilter f = shaping_filter(m);
  EXPECT_EQ(f.n, 1);
  EXPECT_DOUBLE_EQ(f.A(0, 0), -1.0 / 300.0);
  EXPECT_DOUBLE_EQ(f.G(0), 0.3 * std::sqrt(2.0 / 300.0));
  EXPECT_NEAR(f.P_inf(0, 0), 0.09, 1e-15);
  const DiscreteShapingFilter d = discretise(f, 2.0);
  EXPECT_NEAR(d.Phi(0, 0), std::exp(-2.0 / 300.0), 1e-15);
  EXPECT_NEAR(d.Qd(0, 0), 0.09 * (1.0 - std::exp(-4.0 / 300.0)), 1e-15);
  for (int k : {0, 1, 10, 150})
    EXPECT_NEAR(output_correlation(f, d, k, f.H), m.correlation(2.0 * k), 1e-12);
}

class ExpCosineFilter : public ::testing::TestWithParam<double> {};

TEST_P(ExpCosineFilter, OutputHasTheExpCosineCorrelationEq32) {
  const double dt = GetParam();
  const DriftModel m{DriftModelKind::exp_cosine, 0.5, 0.01, 0.03};
  const ShapingFilter f = shaping_filter(m);
  ASSERT_EQ(f.n, 2);
  // The paper's vector-matrix form.
  const double b2 = 0.01 * 0.01 + 0.03 * 0.03;
  EXPECT_DOUBLE_EQ(f.A(0, 0), -0.02);
  EXPECT_DOUBLE_EQ(f.A(0, 1), -b2);
  EXPECT_DOUBLE_EQ(f.A(1, 0), 1.0);
  EXPECT_DOUBLE_EQ(f.A(1, 1), 0.0);
  // Stationary covariance solves the Lyapunov equation; variance of the output is σ².
  const Eigen::Matrix2d lyap = f.A * f.P_inf + f.P_inf * f.A.transpose() + f.G * f.G.transpose();
  EXPECT_LT(lyap.norm(), 1e-12);
  EXPECT_NEAR(f.H * f.P_inf * f.H.transpose(), 0.25, 1e-12);
  const DiscreteShapingFilter d = discretise(f, dt);
  // Discrete consistency: P∞ = Φ P∞ Φᵀ + Qd, Qd symmetric positive semi-definite.
  EXPECT_LT((d.Phi * f.P_inf * d.Phi.transpose() + d.Qd - f.P_inf).norm(), 1e-10);
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(d.Qd).eigenvalues().minCoeff(), -1e-15);
  // The output H·x (= the paper's Δμ̃) has K(τ) = σ² e^{−ατ} cos βτ at every lag …
  for (int k = 0; k <= static_cast<int>(400.0 / dt); k += std::max(1, static_cast<int>(7.0 / dt)))
    EXPECT_NEAR(output_correlation(f, d, k, f.H), m.correlation(k * dt), 1e-10) << "lag " << k * dt;
  // … while the state the paper's text calls the sensor error (x[0]) does not.
  const Eigen::RowVector2d first(1.0, 0.0);
  const double r0 = output_correlation(f, d, 0, first);
  EXPECT_GT(std::abs(r0 - 0.25), 0.01);
}

INSTANTIATE_TEST_SUITE_P(Identify, ExpCosineFilter, ::testing::Values(0.01, 1.0, 50.0, 500.0));

TEST(IdentifyShapingFilter, ShortAndLongStepDiscretisationsAgree) {
  // Van Loan (short steps) and the stationary-difference path (long steps) at the switch-over.
  const DriftModel m{DriftModelKind::exp_cosine, 1.0, 0.2, 0.5};
  const ShapingFilter f = shaping_filter(m);
  const double dt_switch = 1.0 / f.A.norm();
  const auto a = discretise(f, dt_switch * 0.999), b = discretise(f, dt_switch * 1.001);
  EXPECT_LT((a.Qd - b.Qd).norm(), 0.01 * a.Qd.norm());
  // Two half steps equal one step.
  const auto h = discretise(f, 0.3), w = discretise(f, 0.6);
  EXPECT_LT((h.Phi * h.Phi - w.Phi).norm(), 1e-12);
  EXPECT_LT((h.Phi * h.Qd * h.Phi.transpose() + h.Qd - w.Qd).norm(), 1e-12);
}

TEST(IdentifyShapingFilter, RejectsInvalidParameters) {
  EXPECT_THROW(shaping_filter({DriftModelKind::exponential, 0.0, 1.0, 0}), std::invalid_argument);
  EXPECT_THROW(shaping_filter({DriftModelKind::exponential, 1.0, 0.0, 0}), std::invalid_argument);
  EXPECT_THROW(shaping_filter({DriftModelKind::exp_cosine, 1.0, 1.0, -1}), std::invalid_argument);
  EXPECT_THROW(discretise(shaping_filter({DriftModelKind::exponential, 1.0, 1.0, 0}), 0.0),
               std::invalid_argument);
}

}  // namespace
}  // namespace calbench::identification
