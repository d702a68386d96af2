#include "calibration/effects/effect_compensation.hpp"

#include <cmath>

#include "calibration/effects/effect_registry.hpp"

namespace calbench {

EffectUse drive_effect_use(const EffectTerms& e, bool has_temperature) {
  // Output terms first, then the time-stamp corrections; the noise-model terms are the filter's
  // drift prior (fit drive lists them itself).
  EffectUse u;
  std::vector<std::string> stamps;
  for (const EffectSpec& s : effect_specs()) {
    if (!effect_present(s, e)) continue;
    switch (s.compensation) {
      case DriveCompensation::output: u.applied.push_back(s.key); break;
      case DriveCompensation::time_stamp: stamps.push_back(s.key); break;
      case DriveCompensation::with_temperature:
        if (has_temperature) u.applied.push_back(s.key);
        else u.ignored.push_back({s.key, s.drive_ignored_reason});
        break;
      case DriveCompensation::ignored: u.ignored.push_back({s.key, s.drive_ignored_reason}); break;
      case DriveCompensation::noise_model: break;
    }
  }
  u.applied.insert(u.applied.end(), stamps.begin(), stamps.end());
  return u;
}

ImuEffectCompensator::ImuEffectCompensator(const EffectTerms& e, const SensorErrors& set)
    : e_(e), cg_(set.gyro), ca_(set.accel) {
  // Terms a stream cannot apply (temperature_rate needs dT/dt; drive_effect_use says so) are zeroed.
  for (const EffectSpec& s : effect_specs())
    if (s.compensation == DriveCompensation::ignored && (s.axis_output || s.sensor_output)) effect_clear(s, e_);
  active_ = e_.any_sensor_side();
}

double ImuEffectCompensator::time_offset_s() const { return time_stamp_offset(e_); }
double ImuEffectCompensator::corrected_time(double t) const { return truth_time(e_, t); }

void ImuEffectCompensator::output_terms(const Vec3& w, const Vec3& f, const Vec3& dw, double temp_c, Vec3& dg,
                                        Vec3& da) const {
  EffectContext c;
  c.w = w;
  c.f = f;
  c.dw = dw;
  c.temp_c = std::isfinite(temp_c) ? temp_c : e_.t0_c;  // no temperature: temperature terms are zero
  c.dtemp_k_s = 0;
  sensor_side_terms(e_, c, dg, da);
}

void ImuEffectCompensator::rates(Vec3& w, Vec3& f, double dt, double temp_c) {
  if (!active_) return;
  if (std::isfinite(temp_c)) ++n_temp_;
  Vec3 xw = cg_(w), xf = ca_(f);
  Vec3 dg = Vec3::Zero(), da = Vec3::Zero();
  const bool first = !have_prev_;
  for (int it = 0; it < 2; ++it) {
    const Vec3 dw = first || !(dt > 0) ? Vec3::Zero() : Vec3((xw - w_prev_) / dt);
    output_terms(xw, xf, dw, temp_c, dg, da);
    xw = cg_(w - dg);
    xf = ca_(f - da);
  }
  w_prev_ = xw;
  have_prev_ = true;
  w -= dg;
  f -= da;
}

void ImuEffectCompensator::increments(Vec3& dtheta, Vec3& dv, double dt, double temp_c) {
  if (!active_ || !(dt > 0)) return;
  Vec3 w = dtheta / dt, f = dv / dt;
  rates(w, f, dt, temp_c);
  dtheta = w * dt;
  dv = f * dt;
}

}  // namespace calbench
