// Shaping filters, paper eqs 22–23 (exponential) and 34–36 (exponential-cosine); see the header.
#include "calibration/identification/shaping_filter.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <unsupported/Eigen/MatrixFunctions>

namespace calbench::identification {

const char* drift_model_name(DriftModelKind k) {
  return k == DriftModelKind::exponential ? "exponential" : "exp_cosine";
}

double DriftModel::correlation(double tau) const {
  const double t = std::abs(tau);
  const double c = kind == DriftModelKind::exp_cosine ? std::cos(beta * t) : 1.0;
  return sigma * sigma * std::exp(-alpha * t) * c;
}

namespace {
// Continuous Lyapunov equation A P + P Aᵀ + Q = 0 for the leading n×n block (n ≤ 2).
Eigen::Matrix2d stationary_covariance(const Eigen::Matrix2d& A, const Eigen::Matrix2d& Q, int n) {
  Eigen::Matrix2d P = Eigen::Matrix2d::Zero();
  if (n == 1) {
    P(0, 0) = -Q(0, 0) / (2.0 * A(0, 0));
    return P;
  }
  // vec(A P + P Aᵀ) = (I ⊗ A + A ⊗ I) vec(P), column-major vec.
  Eigen::Matrix4d K = Eigen::Matrix4d::Zero();
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k) {
        // (I ⊗ A): block (j,j) is A → row i+2j, col k+2j gets A(i,k)
        K(i + 2 * j, k + 2 * j) += A(i, k);
        // (A ⊗ I): block (j,k) is A(j,k)·I → row i+2j, col i+2k gets A(j,k)
        K(i + 2 * j, i + 2 * k) += A(j, k);
      }
  Eigen::Vector4d q(Q(0, 0), Q(1, 0), Q(0, 1), Q(1, 1));
  Eigen::Vector4d p = K.fullPivLu().solve(-q);
  P << p(0), p(2), p(1), p(3);
  return 0.5 * (P + P.transpose());
}
}  // namespace

ShapingFilter shaping_filter(const DriftModel& m) {
  if (!(m.sigma > 0) || !(m.alpha > 0) || !(m.beta >= 0) || !std::isfinite(m.sigma) ||
      !std::isfinite(m.alpha) || !std::isfinite(m.beta))
    throw std::invalid_argument("shaping_filter: need sigma > 0, alpha > 0, beta >= 0 (finite)");
  ShapingFilter f;
  f.kind = m.kind;
  const double g = m.sigma * std::sqrt(2.0 * m.alpha);  // σ√(2α)
  if (m.kind == DriftModelKind::exponential) {
    // Eq 22/23: Δμ̇ = −α Δμ + σ√(2α) ξ.
    f.n = 1;
    f.A(0, 0) = -m.alpha;
    f.G(0) = g;
    f.H(0) = 1.0;
  } else {
    // Eqs 35–36 in the paper's vector-matrix form, x = [Δμ, Δμ̃]; the drift is x[1] (see header).
    const double b2 = m.alpha * m.alpha + m.beta * m.beta;
    const double b = std::sqrt(b2);
    f.n = 2;
    f.A << -2.0 * m.alpha, -b2, 1.0, 0.0;
    f.G << (b - 2.0 * m.alpha) * g, g;
    f.H << 0.0, 1.0;
  }
  f.P_inf = stationary_covariance(f.A, f.G * f.G.transpose(), f.n);
  return f;
}

DiscreteShapingFilter discretise(const ShapingFilter& f, double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) throw std::invalid_argument("discretise: dt must be > 0");
  DiscreteShapingFilter d;
  d.n = f.n;
  d.dt = dt;
  if (f.n == 1) {
    const double a = -f.A(0, 0);
    d.Phi(0, 0) = std::exp(-a * dt);
    // σ²(1 − e^{−2α dt}) with σ² = G²/(2α); expm1 keeps precision for small α dt.
    d.Qd(0, 0) = f.G(0) * f.G(0) / (2.0 * a) * -std::expm1(-2.0 * a * dt);
    return d;
  }
  if (f.A.norm() * dt > 1.0) {
    // Long steps: exp(−A dt) in Van Loan's matrix would grow like e^{2α dt} and lose precision.
    // The process is stationary, so P∞ = Φ P∞ Φᵀ + Qd exactly, and the difference is well
    // conditioned when Φ is not close to I.
    const Eigen::Matrix2d Ad = f.A * dt;
    d.Phi = Ad.exp();
    d.Qd = f.P_inf - d.Phi * f.P_inf * d.Phi.transpose();
    d.Qd = 0.5 * (d.Qd + d.Qd.transpose()).eval();
    return d;
  }
  // Short steps, Van Loan (1978): exp([[−A, G Gᵀ], [0, Aᵀ]] dt) = [[·, Φ⁻¹Qd], [0, Φᵀ]].
  Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
  M.topLeftCorner<2, 2>() = -f.A * dt;
  M.topRightCorner<2, 2>() = f.G * f.G.transpose() * dt;
  M.bottomRightCorner<2, 2>() = f.A.transpose() * dt;
  const Eigen::Matrix4d E = M.exp();
  d.Phi = E.bottomRightCorner<2, 2>().transpose();
  d.Qd = d.Phi * E.topRightCorner<2, 2>();
  d.Qd = 0.5 * (d.Qd + d.Qd.transpose()).eval();
  return d;
}

}  // namespace calbench::identification
