// Eq 14: velocity difference, INS-MEMS moved to the reference body origin minus the reference
// (NED). v̂_b = v̂_m − Ĉ_nb(ω̂_eb^b × r) = v̂_m + Ĉ_nb(r × ω̂_eb^b); with u = C_nb(ω_eb^b × r) and
// J = ∂(r × ω̂_eb^b)/∂δx (attitude, mounting and the gyro's sensor model: set_body_rate,
// lever_rate_jacobian in observation.hpp):
//   z = δv − u×φ + u×C_nb·δμ + C_nb·J·δx.
#include "calibration/inmotion/observation.hpp"

#include <stdexcept>

#include "calibration/ins/nav_math.hpp"

namespace calbench::inmotion {

void set_body_rate(ObsContext& c, const StateLayout& L, const SensorCorrection& corr, const Vec3& w_m) {
  const Mat3 C_nm = c.mems->C_nb(), C_bn = c.C_mb * C_nm.transpose();
  const Vec3 w_ie = ins::earth_rate_ned_at(c.mems->lat);
  c.w_eb_b = c.C_mb * (w_m - C_nm.transpose() * w_ie);
  c.w_eb_jac.setZero(3, L.size());
  if (c.att >= 0) c.w_eb_jac.middleCols<3>(c.att) = C_bn * ins::skew(w_ie);
  if (c.mount >= 0) c.w_eb_jac.middleCols<3>(c.mount) = ins::skew(c.w_eb_b);
  // The gyro blocks' columns: one interval of 1 s with the accelerometer's map zero, so only the
  // blocks that act on the rate write (F_φx = +sum/T for the gyro, error_model.cpp).
  const ImuSample s{C_nm, {w_m, Vec3::Zero()}, 1.0, {C_nm * corr.A[kGyro], Mat3::Zero()}};
  Eigen::Matrix<double, 3, Eigen::Dynamic> sum = Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, L.size());
  for (const BlockSpec* b : L.specs)
    if (b->accumulate) b->accumulate(s, sum.middleCols(L.offset(b->id), b->size));
  c.w_eb_jac -= C_bn * sum;
}

Eigen::Matrix<double, 3, Eigen::Dynamic> lever_rate_jacobian(const ObsContext& c, const Vec3& lever) {
  if (c.w_eb_jac.cols() != c.n_states) throw std::logic_error("ObsContext built without set_body_rate");
  return ins::skew(lever) * c.w_eb_jac;
}

Observation velocity_observation(const ObsContext& c, const RefObs& r) {
  Observation o;
  const Mat3 C_nb = predicted_body_attitude(c);
  const Vec3 u = C_nb * c.w_eb_b.cross(c.lever);
  o.z = (c.mems->v - u) - r.v_ned;
  o.H = C_nb * lever_rate_jacobian(c, c.lever);
  o.H.block<3, 3>(0, c.vel) += Mat3::Identity();
  o.H.block<3, 3>(0, c.att) -= ins::skew(u);
  if (c.mount >= 0) o.H.block<3, 3>(0, c.mount) += ins::skew(u) * C_nb;
  o.R = Mat3::Identity() * (r.sigma_vel * r.sigma_vel);
  return o;
}

}  // namespace calbench::inmotion
