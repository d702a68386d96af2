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

}  // namespace calbench::inmotion
