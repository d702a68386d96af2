#include "calibration/ins/strapdown.hpp"

#include <cmath>

namespace calbench::ins {

void Strapdown::reset(const NavState& s) {
  s_ = s;
  s_.q_nb.normalize();
  have_prev_ = false;
  prev_dth_.setZero();
  prev_dv_.setZero();
  dv_n_last_.setZero();
  dlat_last_ = dh_last_ = 0;
  earth_ = local_earth(s_.lat, s_.h, s_.v);
  cache_lat_ = s_.lat;
  cache_h_ = s_.h;
  tan_lat_ = std::tan(s_.lat);
}

void Strapdown::update(const Vec3& dth, const Vec3& dv, double dt) {
  if (!(dt > 0)) return;
  const Vec3 pdth = have_prev_ ? prev_dth_ : Vec3::Zero();
  const Vec3 pdv = have_prev_ ? prev_dv_ : Vec3::Zero();

  // Earth quantities at the extrapolated midpoint of the step.
  const Vec3 v_mid = s_.v + 0.5 * dv_n_last_;
  // Gravity, radii and Earth rate change slowly: refresh them when the midpoint has moved by more
  // than ~0.5 m horizontally or 0.05 m vertically (gravity gradient 3e-6 s⁻²); the transport
  // rate depends on velocity and is recomputed every step.
  const double lat_m = s_.lat + 0.5 * dlat_last_, h_m = s_.h + 0.5 * dh_last_;
  if (std::abs(lat_m - cache_lat_) > 8e-8 || std::abs(h_m - cache_h_) > 0.05) {
    earth_ = local_earth(lat_m, h_m, v_mid);
    cache_lat_ = lat_m;
    cache_h_ = h_m;
    tan_lat_ = std::tan(lat_m);
  }
  {
    const double rn = earth_.r.RN + h_m, rm = earth_.r.RM + h_m;
    earth_.w_en = Vec3(v_mid(1) / rn, -v_mid(0) / rm, -v_mid(1) * tan_lat_ / rn);
  }
  const Vec3 zeta = (earth_.w_ie + earth_.w_en) * dt;

  // Velocity: rotation and sculling compensation, then NED-frame rotation, gravity, Coriolis.
  const Vec3 dv_f = dv + 0.5 * dth.cross(dv) + (pdth.cross(dv) + pdv.cross(dth)) / 12.0;
  const Mat3 C0 = s_.C_nb();
  const Vec3 dv_fn = (Mat3::Identity() - 0.5 * skew(zeta)) * (C0 * dv_f);
  const Vec3 dv_g = (earth_.g - (2.0 * earth_.w_ie + earth_.w_en).cross(v_mid)) * dt;
  const Vec3 v0 = s_.v;
  s_.v = v0 + dv_fn + dv_g;
  dv_n_last_ = s_.v - v0;

  // Position: trapezoidal.
  const Vec3 va = 0.5 * (v0 + s_.v);
  const double h0 = s_.h, lat0 = s_.lat;
  s_.h = h0 - va(2) * dt;
  const double h_mid = 0.5 * (h0 + s_.h);
  const Radii r0 = earth_.r;
  s_.lat = lat0 + va(0) / (r0.RM + h_mid) * dt;
  const double lat_mid = 0.5 * (lat0 + s_.lat);
  s_.lon += va(1) / ((r0.RN + h_mid) * std::cos(lat_mid)) * dt;
  dlat_last_ = s_.lat - lat0;
  dh_last_ = s_.h - h0;

  // Attitude: two-sample coning, NED-frame rotation.
  const Vec3 phi = dth + pdth.cross(dth) / 12.0;
  s_.q_nb = quat_from_rotvec(-zeta) * s_.q_nb * quat_from_rotvec(phi);
  s_.q_nb.normalize();
  s_.t += dt;

  f_body_ = dv_f / dt;
  f_ned_ = dv_fn / dt;
  w_body_ = dth / dt;
  prev_dth_ = dth;
  prev_dv_ = dv;
  have_prev_ = true;
}

}  // namespace calbench::ins
