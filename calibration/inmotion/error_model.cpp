#include "calibration/inmotion/error_model.hpp"

#include <cmath>

#include "common/units.hpp"

namespace calbench::inmotion {

using ins::skew;

Eigen::Matrix<double, 3, 9> m_jacobian(const Vec3& x) {
  Eigen::Matrix<double, 3, 9> J = Eigen::Matrix<double, 3, 9>::Zero();
  for (int i = 0; i < 3; ++i) J.block<1, 3>(i, 3 * i) = x.transpose();
  return J;
}

void FAccumulator::add(const Mat3& C_nb, const Mat3& A_g, const Mat3& A_a, const Vec3& w_b, const Vec3& f_b, double dt) {
  const Mat3 CAg = C_nb * A_g * dt, CAa = C_nb * A_a * dt;
  att_bg += CAg;
  vel_ba += CAa;
  // (C A) W(x): column block i is (C A)(:, i)·xᵀ.
  for (int i = 0; i < 3; ++i) {
    att_mg.block<3, 3>(0, 3 * i) += CAg.col(i) * w_b.transpose();
    vel_ma.block<3, 3>(0, 3 * i) += CAa.col(i) * f_b.transpose();
  }
  f_n += C_nb * f_b * dt;
  T += dt;
}

void nav_block(const NavBlockInputs& in, FRef F) {
  const ins::LocalEarth& e = in.earth;
  const double rm = e.r.RM + in.h, rn = e.r.RN + in.h;
  const Vec3 w_in = e.w_ie + e.w_en;
  // δṙ = δv (curvature terms of order v/R neglected).
  F.block<3, 3>(kPos, kVel) = Mat3::Identity();
  // δv̇ = f^n×φ − (2ω_ie + ω_en)×δv + δg (vertical: ∂g/∂(down) = 2g/R) + C δf.
  F.block<3, 3>(kVel, kAtt) = skew(in.f_n);
  F.block<3, 3>(kVel, kVel) = -skew(2 * e.w_ie + e.w_en);
  F(kVel + 2, kPos + 2) = 2.0 * e.g(2) / std::sqrt(rm * rn);
  // φ̇ = −ω_in×φ + δω_in − C δω_ib; δω_en from δv.
  F.block<3, 3>(kAtt, kAtt) = -skew(w_in);
  F(kAtt + 0, kVel + 1) = 1.0 / rn;
  F(kAtt + 1, kVel + 0) = -1.0 / rm;
  F(kAtt + 2, kVel + 1) = -std::tan(in.lat) / rn;
  // δω_ie from the latitude error δr_N/(R_M + h).
  const double W = units::kEarthRate;
  F(kAtt + 0, kPos + 0) = -W * std::sin(in.lat) / rm;
  F(kAtt + 2, kPos + 0) = -W * std::cos(in.lat) / rm;
}

void gyro_bias_jacobian(const FAccumulator& acc, int col, FRef F) {
  if (!(acc.T > 0)) return;
  const double k = 1.0 / acc.T;
  F.block<3, 3>(kAtt, col) = acc.att_bg * k;
}

void gyro_M_jacobian(const FAccumulator& acc, int col, FRef F) {
  if (!(acc.T > 0)) return;
  const double k = 1.0 / acc.T;
  F.block<3, 9>(kAtt, col) = acc.att_mg * k;
}

void accel_bias_jacobian(const FAccumulator& acc, int col, FRef F) {
  if (!(acc.T > 0)) return;
  const double k = 1.0 / acc.T;
  F.block<3, 3>(kVel, col) = -acc.vel_ba * k;
}

void accel_M_jacobian(const FAccumulator& acc, int col, FRef F) {
  if (!(acc.T > 0)) return;
  const double k = 1.0 / acc.T;
  F.block<3, 9>(kVel, col) = -acc.vel_ma * k;
}

void drift_jacobian(const Vec3& alpha, int off, FRef F) {
  for (int i = 0; i < 3; ++i) F(off + i, off + i) = -alpha(i);
}

}  // namespace calbench::inmotion
