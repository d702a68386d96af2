// Eq 14: velocity difference, INS-MEMS moved to the reference body origin minus the reference
// (NED). v̂_b = v̂_m − Ĉ_nb(ω̂_eb^b × r) = v̂_m + Ĉ_nb(r × ω̂_eb^b); with u = C_nb(ω_eb^b × r) and
// J the dependence of r × ω̂_eb^b on φ and δμ (lever_rate_jacobian, observation.hpp):
//   z = δv − u×φ + u×C_nb·δμ + C_nb·(J_att·φ + J_mount·δμ)
// (the gyro sensor model's part of ω̂_eb^b, |δb_g|·|r| ≲ 1e-4 m/s, is neglected).
#include "calibration/inmotion/observation.hpp"

#include "calibration/ins/nav_math.hpp"

namespace calbench::inmotion {

Vec3 body_rate_wrt_earth(const ins::NavState& mems, const Mat3& C_mb, const Vec3& w_m) {
  return C_mb * (w_m - mems.C_nb().transpose() * ins::earth_rate_ned_at(mems.lat));
}

LeverRateJacobian lever_rate_jacobian(const ObsContext& c, const Vec3& lever) {
  const Mat3 C_bn = predicted_body_attitude(c).transpose();
  const Mat3 R = ins::skew(lever);
  return {R * C_bn * ins::skew(ins::earth_rate_ned_at(c.mems->lat)), R * ins::skew(c.w_eb_b)};
}

Observation velocity_observation(const ObsContext& c, const RefObs& r) {
  Observation o;
  o.H.setZero(3, c.n_states);
  const Mat3 C_nb = predicted_body_attitude(c);
  const Vec3 u = C_nb * c.w_eb_b.cross(c.lever);
  const LeverRateJacobian J = lever_rate_jacobian(c, c.lever);
  o.z = (c.mems->v - u) - r.v_ned;
  o.H.block<3, 3>(0, c.vel) = Mat3::Identity();
  o.H.block<3, 3>(0, c.att) = -ins::skew(u) + C_nb * J.att;
  if (c.mount >= 0) o.H.block<3, 3>(0, c.mount) = ins::skew(u) * C_nb + C_nb * J.mount;
  o.R = Mat3::Identity() * (r.sigma_vel * r.sigma_vel);
  return o;
}

}  // namespace calbench::inmotion
