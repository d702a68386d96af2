// Zero-velocity update (ZUPT) and zero angular-rate update (ZARU) at a standstill of the vehicle
// (detected from the IMU data, calibration/inmotion/standstill.hpp). Standing, every point of the
// vehicle has zero velocity w.r.t. the Earth, and the body turns with the Earth only.
//
// ZUPT: z = v̂_m^n − 0 = δv + n,   n ~ N(0, σ²·I₃)     (H: identity on the velocity block)
//   σ: what a standing vehicle still moves (engine, wind, occupants); 0.01 m/s by default.
//
// ZARU: the mean raw gyro rate ȳ over the interval, corrected by the current sensor model, minus
// the Earth rate the nominal attitude predicts in MEMS axes:
//   z = Â_g·(ȳ − b̂_g − d̂_g) − Ĉ_mn·ω_ie^n,   Â_g = (I + M̂_g)⁻¹.
// The correction error is Â_g(ȳ − b̂ − d̂) − ω = −Â_g·(δb_g + δd_g + δM_g·ω) (error_model.hpp), and
// with Ĉ_nm = (I − φ×)·C_nm, Ĉ_mn·ω_ie = C_mn·ω_ie − C_mn·(ω_ie×)·φ, so
//   z = −Â_g·δb_g − Â_g·δd_g − Â_g·W(ω̂)·vec(δM_g) + C_mn·(ω_ie×)·φ + n,
// W(x) the 3×9 of δM·x (m_jacobian). σ: the white noise of a mean over the interval (the caller's,
// from the gyro's density and the standstill's measured spread).
//
// With the heading unknown (the levelling standstill of a GNSS-only start: roll and pitch from the
// specific force, yaw a placeholder), only the Earth rate's down component is known in MEMS axes:
// for C_nm = R_z(ψ)·C_lvl, Ĉ_mn·(0, 0, ω_D) does not depend on ψ, the horizontal part
// C_mn·(Ω cos L, 0, 0) turns with it. That part is then noise of its own, zero mean over a heading
// uniform round the circle with variance (Ω cos L)²/2 per horizontal axis (also independent of ψ in
// MEMS axes), and the attitude columns are left out (linearised at a placeholder heading they would
// be false information; the tilt's share, Ω·φ, is below 1e-3 °/h per mrad):
//   z = Â_g·(ȳ − b̂_g − d̂_g) − Ĉ_mn·(0, 0, ω_D),   R = σ²·I + Ĉ_mn·diag(h², h², 0)·Ĉ_nm,  h² = (Ω cos L)²/2.
#include "calibration/inmotion/inmotion_filter.hpp"
#include "calibration/inmotion/observation.hpp"

namespace calbench::inmotion {

Observation zupt_observation(const ObsContext& c, double sigma) {
  Observation o;
  o.H.setZero(3, c.n_states);
  o.z = c.mems->v;
  o.H.block<3, 3>(0, c.vel) = Mat3::Identity();
  o.R = Mat3::Identity() * (sigma * sigma);
  return o;
}

Observation zero_rate_observation(const ObsContext& c, const Nominal& n, const Vec3& y_mean, double sigma, bool heading_known) {
  Observation o;
  o.H.setZero(3, c.n_states);
  const Mat3 A = (Mat3::Identity() + n.mat3(c.gyro_M)).inverse();
  const Vec3 w_hat = A * (y_mean - n.vec3(c.gyro_bias) - n.vec3(c.gyro_drift));
  const Mat3 C_mn = c.mems->C_nb().transpose();
  const Vec3 w_ie = ins::earth_rate_ned_at(c.mems->lat);
  o.R = Mat3::Identity() * (sigma * sigma);
  if (heading_known) {
    o.z = w_hat - C_mn * w_ie;
    o.H.block<3, 3>(0, c.att) = C_mn * ins::skew(w_ie);
  } else {
    o.z = w_hat - C_mn * Vec3(0, 0, w_ie(2));
    const double h2 = 0.5 * w_ie(0) * w_ie(0);
    o.R += C_mn * Vec3(h2, h2, 0).asDiagonal() * C_mn.transpose();
  }
  if (c.gyro_bias >= 0) o.H.block<3, 3>(0, c.gyro_bias) = -A;
  if (c.gyro_drift >= 0) o.H.block<3, 3>(0, c.gyro_drift) = -A;
  if (c.gyro_M >= 0) o.H.block<3, 9>(0, c.gyro_M) = -A * m_jacobian(w_hat);
  return o;
}

}  // namespace calbench::inmotion
