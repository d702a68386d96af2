#include "calibration/effects/effect_terms.hpp"

#include <cmath>

namespace calbench {

namespace {
bool nz(const TriadEffectTerms& t) {
  return !t.temp_bias.isZero(0) || !t.temp_scale.isZero(0) || !t.temp_rate.isZero(0) || !t.nonlinearity.isZero(0) || !t.asymmetry.isZero(0) ||
         !t.scale.isZero(0);
}
}  // namespace

bool EffectTerms::any_sensor_side() const {
  return nz(gyro) || nz(accel) || !g_sensitivity.isZero(0) || !lever_arm_m.isZero(0);
}

bool EffectTerms::any() const {
  return any_sensor_side() || time_offset_s != 0 || !table_tilt_rad.isZero(0) || !wobble_rad.isZero(0) ||
         gyro.drift_sigma > 0 || accel.drift_sigma > 0;
}

void sensor_side_terms(const EffectTerms& e, const EffectContext& c, Vec3& dgyro, Vec3& daccel) {
  const double dT = c.temp_c - e.t0_c;
  auto triad = [&](const TriadEffectTerms& t, const Vec3& x) {
    Vec3 d;
    for (int i = 0; i < 3; ++i)
      d(i) = t.temp_bias(i) * dT + t.temp_scale(i) * dT * x(i) + t.temp_rate(i) * c.dtemp_k_s + t.nonlinearity(i) * x(i) * std::abs(x(i)) +
             t.asymmetry(i) * std::abs(x(i)) + t.scale(i) * x(i);
    return d;
  };
  dgyro = triad(e.gyro, c.w) + e.g_sensitivity * c.f;
  daccel = triad(e.accel, c.f) + lever_arm_force(e.lever_arm_m, c.w, c.dw);
}

Vec3 lever_arm_force(const Vec3& r, const Vec3& w, const Vec3& dw) { return w.cross(w.cross(r)) + dw.cross(r); }

Vec3 table_tilt_force(const Eigen::Vector2d& psi, const Mat3& C_b_l, const Vec3& f_b) {
  const Vec3 p(psi(0), psi(1), 0.0);
  return -(C_b_l.transpose() * p.cross(C_b_l * f_b));
}

}  // namespace calbench
