#include "calibration/effects/effect_compensation.hpp"

#include <cmath>

namespace calbench {

namespace {
bool nz3(const Vec3& v) { return !v.isZero(0); }
}  // namespace

EffectUse drive_effect_use(const EffectTerms& e, bool has_temperature) {
  EffectUse u;
  auto triad_any = [&](Vec3 TriadEffectTerms::*m) { return nz3(e.gyro.*m) || nz3(e.accel.*m); };
  for (const auto& [key, member] : {std::pair{"temperature_bias", &TriadEffectTerms::temp_bias},
                                    std::pair{"temperature_scale", &TriadEffectTerms::temp_scale}}) {
    if (!triad_any(member)) continue;
    if (has_temperature) u.applied.push_back(key);
    else u.ignored.push_back({key, "imu.csv has no temperature column"});
  }
  if (triad_any(&TriadEffectTerms::temp_rate))
    u.ignored.push_back({"temperature_rate", "needs dT/dt, which the drive estimator does not derive"});
  if (!e.g_sensitivity.isZero(0)) u.applied.push_back("g_sensitivity");
  if (triad_any(&TriadEffectTerms::nonlinearity)) u.applied.push_back("scale_nonlinearity");
  if (triad_any(&TriadEffectTerms::asymmetry)) u.applied.push_back("scale_asymmetry");
  if (triad_any(&TriadEffectTerms::scale)) u.applied.push_back("scale_factor");
  if (nz3(e.lever_arm_m)) u.applied.push_back("lever_arm");
  if (e.time_offset_s != 0) u.applied.push_back("time_offset");
  if (!e.table_tilt_rad.isZero(0)) u.ignored.push_back({"misalignment", "a rate-table term (bench only)"});
  if (!e.wobble_rad.isZero(0)) u.ignored.push_back({"table_wobble", "a rate-table term (bench only)"});
  return u;
}

ImuEffectCompensator::ImuEffectCompensator(const EffectTerms& e, const SensorErrors& set)
    : e_(e), cg_(set.gyro), ca_(set.accel) {
  // temperature_rate needs dT/dt: not applied on a stream (drive_effect_use says so).
  e_.gyro.temp_rate.setZero();
  e_.accel.temp_rate.setZero();
  active_ = e_.any_sensor_side();
}

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
