#include "calibration/qc/inertial_qc.hpp"

namespace calbench::qc {

InertialRun::InertialRun(const SensorErrors& e, const Mat3& C_mb, const Vec3& lever, const inmotion::RefObs& r)
    : g_(e.gyro), a_(e.accel), C_mb_(C_mb), lever_(lever) {
  nav_.reset(inmotion::mems_state_from_reference(r, C_mb_, lever_));
}

InertialRun::InertialRun(const SensorErrors& e, const Mat3& C_mb, const Vec3& lever, const ins::NavState& start)
    : g_(e.gyro), a_(e.accel), C_mb_(C_mb), lever_(lever) {
  nav_.reset(start);
}

void InertialRun::imu(double t, const Vec3& dth, const Vec3& dv, double dt) {
  if (!(dt > 0) || t <= nav_.state().t) return;
  nav_.update(g_.increment(dth, dt), a_.increment(dv, dt), dt);
  nav_.state().t = t;
}

double InertialRun::cpe(const inmotion::RefObs& r) const {
  const ins::NavState& s = nav_.state();
  const Mat3 C_nb = s.C_nb() * C_mb_.transpose();
  double lat = s.lat, lon = s.lon, h = s.h;
  ins::geodetic_add_ned(lat, lon, h, -(C_nb * lever_));
  // Bring the reference to the INS time with its velocity (at most one IMU interval).
  double rl = r.lat, ro = r.lon, rh = r.h;
  ins::geodetic_add_ned(rl, ro, rh, r.v_ned * (s.t - r.t));
  const Vec3 d = ins::geodetic_diff_ned(lat, lon, h, rl, ro, rh);
  return d.head<2>().norm();
}

}  // namespace calbench::qc
