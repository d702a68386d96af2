// Non-holonomic constraint (NHC) of a land vehicle: a wheeled vehicle that neither skids nor
// jumps has no velocity across or out of its own x axis at its reference point. The vehicle frame
// is the reference body frame b (forward-right-down), so the MEMS velocity is moved to the
// reference body origin through the lever arm r (MEMS origin in b axes) and the rotation ω_eb^b,
// and turned into b through the MEMS attitude and the mounting (C_nb = C_nm·C_mbᵀ):
//   v^b = C_bn·(v_m^n − C_nb·(ω_eb^b × r)) = C_bn·v_m^n − ω_eb^b × r,
//   z = S·v̂^b − 0 = H·δx + n,   S = [0 1 0; 0 0 1],   n ~ N(0, σ²·I₂).
// With Ĉ_nb = (I − φ_b×)·C_nb, φ_b = φ − C_nb·δμ (obs_position.cpp), Ĉ_bn = C_bn·(I + φ_b×), and
// −ω̂_eb^b × r = r × ω̂_eb^b moving with φ, δμ and the gyro's sensor model (bias, drift, M columns) as lever_rate_jacobian
// (observation.hpp) says, J:
//   δv^b = C_bn·δv − C_bn·(v_m×)·φ + C_bn·(v_m×)·C_nb·δμ + J·δx,
// so H has rows in the velocity, the attitude AND the mounting block: once the vehicle moves, a
// mounting pitch or yaw error shows as a vertical or lateral velocity of the vehicle, which is what
// makes them observable without an attitude reference (Shin 2001; Niu et al. 2007).
// σ: the vehicle's departure from the constraint (sideslip, suspension, a reference point off
// the rear axle), not a sensor's noise; 0.1 m/s for a car by default (InMotionConfig::nhc_sigma).
#include "calibration/inmotion/observation.hpp"

namespace calbench::inmotion {

ObservationM<2> nhc_observation(const ObsContext& c, double sigma) {
  ObservationM<2> o;
  const Mat3 C_nb = predicted_body_attitude(c);
  const Mat3 C_bn = C_nb.transpose();
  const Vec3& v_m = c.mems->v;
  const Vec3 v_b = C_bn * v_m - c.w_eb_b.cross(c.lever);
  o.z = v_b.tail<2>();
  const Mat3 Cv = C_bn * ins::skew(v_m);
  o.H = lever_rate_jacobian(c, c.lever).bottomRows<2>();
  o.H.block<2, 3>(0, c.vel) += C_bn.bottomRows<2>();
  o.H.block<2, 3>(0, c.att) -= Cv.bottomRows<2>();
  if (c.mount >= 0) o.H.block<2, 3>(0, c.mount) += (Cv * C_nb).bottomRows<2>();
  o.R = Eigen::Matrix2d::Identity() * (sigma * sigma);
  return o;
}

}  // namespace calbench::inmotion
