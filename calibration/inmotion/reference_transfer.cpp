#include <cmath>

#include "calibration/inmotion/observation.hpp"

namespace calbench::inmotion {

ins::NavState mems_state_from_reference(const RefObs& r, const Mat3& C_mb, const Vec3& lever) {
  const Mat3 C_nb = ins::dcm_from_rpy(r.rpy);
  ins::NavState s;
  s.t = r.t;
  s.lat = r.lat;
  s.lon = r.lon;
  s.h = r.h;
  ins::geodetic_add_ned(s.lat, s.lon, s.h, C_nb * lever);
  s.v = r.v_ned;
  s.q_nb = ins::Quat(C_nb * C_mb);
  return s;
}

RefObs gnss_fix_obs(double t, double lat, double lon, double h, const Vec3* v_ned, double sigma_h, double sigma_v,
                    double sigma_vel) {
  RefObs o;
  o.t = t;
  o.lat = lat;
  o.lon = lon;
  o.h = h;
  o.has_att = false;
  o.sigma_pos = sigma_h > 0 ? sigma_h : 0.0;
  o.sigma_pos_v = sigma_v > 0 ? sigma_v : 0.0;
  // No σ column (NaN): the filter's default; 1e3 m/s or more, or infinite: velocity unknown.
  o.has_vel = v_ned != nullptr && !(sigma_vel >= 1e3);
  if (o.has_vel) {
    o.v_ned = *v_ned;
    o.sigma_vel = sigma_vel > 0 ? sigma_vel : 0.0;
  }
  return o;
}

}  // namespace calbench::inmotion
