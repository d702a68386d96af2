#include "calibration/effects/effect_terms.hpp"

#include <cmath>

#include "calibration/effects/effect_registry.hpp"

namespace calbench {

bool EffectTerms::any_sensor_side() const {
  for (const EffectSpec& s : effect_specs())
    if ((s.axis_output || s.sensor_output) && effect_present(s, *this)) return true;
  return false;
}

bool EffectTerms::any() const {
  for (const EffectSpec& s : effect_specs())
    if (effect_present(s, *this)) return true;
  return false;
}

Vec3 lever_arm_force(const Vec3& r, const Vec3& w, const Vec3& dw) { return w.cross(w.cross(r)) + dw.cross(r); }

Vec3 table_tilt_force(const Eigen::Vector2d& psi, const Mat3& C_b_l, const Vec3& f_b) {
  const Vec3 p(psi(0), psi(1), 0.0);
  return -(C_b_l.transpose() * p.cross(C_b_l * f_b));
}

}  // namespace calbench
