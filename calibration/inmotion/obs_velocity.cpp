// Eq 14: velocity difference, INS-MEMS moved to the reference body origin minus the reference
// (NED). v̂_b = v̂_m − Ĉ_nb(ω_eb^b × r); with u = C_nb(ω_eb^b × r):
//   z = δv − u×φ + u×C_nb·δμ   (the gyro-error part of ω in the lever-arm term is neglected).
#include "calibration/inmotion/observation.hpp"

namespace calbench::inmotion {

Observation velocity_observation(const ObsContext& c, const RefObs& r) {
  Observation o;
  o.H.setZero(3, c.n_states);
  const Mat3 C_nb = predicted_body_attitude(c);
  const Vec3 u = C_nb * c.w_eb_b.cross(c.lever);
  o.z = (c.mems->v - u) - r.v_ned;
  o.H.block<3, 3>(0, c.vel) = Mat3::Identity();
  o.H.block<3, 3>(0, c.att) = -ins::skew(u);
  if (c.mount >= 0) o.H.block<3, 3>(0, c.mount) = ins::skew(u) * C_nb;
  o.R = Mat3::Identity() * (r.sigma_vel * r.sigma_vel);
  return o;
}

}  // namespace calbench::inmotion
