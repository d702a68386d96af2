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

void FAccumulator::resize(int n) {
  sum.setZero(3, n);
  clear();
}

void FAccumulator::add(const StateLayout& L, const Mat3& C_nb, const SensorCorrection& c, const Vec3& w_b, const Vec3& f_b,
                       double dt) {
  const ImuSample s{C_nb, {w_b, f_b}, dt, {C_nb * c.A[kGyro] * dt, C_nb * c.A[kAccel] * dt}};
  for (const BlockSpec* b : L.specs)
    if (b->accumulate) b->accumulate(s, sum.middleCols(L.L.offset(static_cast<int>(b->id)), b->size));
  f_n += C_nb * f_b * dt;
  if (track_jumps) {
    if (have_m) {
      const Vec3 jw = C_nb * (w_b - m_w), jf = C_nb * (f_b - m_f);
      jump_w += jw * jw.transpose();
      jump_f += jf * jf.transpose();
    }
    m_w = w_b;
    m_f = f_b;
    have_m = true;
  }
  T += dt;
}

void FAccumulator::clear() {
  T = 0;
  f_n.setZero();
  jump_w.setZero();
  jump_f.setZero();
  sum.setZero();
}

void nav_block(const NavBlockInputs& in, int pos, int vel, int att, FRef F) {
  const ins::LocalEarth& e = in.earth;
  const double rm = e.r.RM + in.h, rn = e.r.RN + in.h;
  const Vec3 w_in = e.w_ie + e.w_en;
  // δṙ = δv (curvature terms of order v/R neglected).
  F.block<3, 3>(pos, vel) = Mat3::Identity();
  // δv̇ = f^n×φ − (2ω_ie + ω_en)×δv + δg (vertical: ∂g/∂(down) = 2g/R) + C δf.
  F.block<3, 3>(vel, att) = skew(in.f_n);
  F.block<3, 3>(vel, vel) = -skew(2 * e.w_ie + e.w_en);
  F(vel + 2, pos + 2) = 2.0 * e.g(2) / std::sqrt(rm * rn);
  // φ̇ = −ω_in×φ + δω_in − C δω_ib; δω_en from δv.
  F.block<3, 3>(att, att) = -skew(w_in);
  F(att + 0, vel + 1) = 1.0 / rn;
  F(att + 1, vel + 0) = -1.0 / rm;
  F(att + 2, vel + 1) = -std::tan(in.lat) / rn;
  // δω_ie from the latitude error δr_N/(R_M + h).
  const double W = units::kEarthRate;
  F(att + 0, pos + 0) = -W * std::sin(in.lat) / rm;
  F(att + 2, pos + 0) = -W * std::cos(in.lat) / rm;
}

void sensor_jacobian(const FAccumulator& acc, int sensor, int rows, int col, int size, FRef F) {
  if (!(acc.T > 0)) return;
  const double k = 1.0 / acc.T;
  if (sensor == kGyro) F.block(rows, col, 3, size) = acc.sum.middleCols(col, size) * k;
  else F.block(rows, col, 3, size) = -acc.sum.middleCols(col, size) * k;
}

void drift_jacobian(const Vec3& alpha, int off, FRef F) {
  for (int i = 0; i < 3; ++i) F(off + i, off + i) = -alpha(i);
}

}  // namespace calbench::inmotion
