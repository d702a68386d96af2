// The simulated test drive of the in-motion filter tests (inmotion_test_drive.hpp).
#include "inmotion_test_drive.hpp"

#include "common/imu_error_sim.hpp"
#include "common/units.hpp"

namespace calbench::inmotion_test {

using namespace drivesim;
using units::kDeg;

Route lap_route(double lat_deg, double lon_deg, double h_m, double heading_deg, int laps) {
  Route r;
  r.lat = lat_deg * kDeg;
  r.lon = lon_deg * kDeg;
  r.h = h_m;
  r.heading = heading_deg * kDeg;
  auto add = [&](SegmentKind k, double a = 0, double b = 0) {
    Segment s;
    s.kind = k;
    switch (k) {
      case SegmentKind::accelerate: s.to_speed = a; s.duration_s = b; break;
      case SegmentKind::turn: s.angle = a * kDeg; s.radius = b; break;
      case SegmentKind::climb: s.grade = a * kDeg; s.duration_s = b; break;
      case SegmentKind::lane_change: s.width = a; s.duration_s = b; break;
      default: s.duration_s = a;
    }
    r.segments.push_back(s);
  };
  add(SegmentKind::stop, 20);
  for (int lap = 0; lap < laps; ++lap) {
    add(SegmentKind::accelerate, 12, 8);
    add(SegmentKind::turn, 90, 25);
    add(SegmentKind::climb, 5, 15);
    add(SegmentKind::lane_change, 3.5, 4);
    add(SegmentKind::turn, -180, 30);
    add(SegmentKind::accelerate, 20, 8);
    add(SegmentKind::climb, -4, 15);
    add(SegmentKind::turn, 135, 60);
    add(SegmentKind::lane_change, -3.5, 4);
    add(SegmentKind::stop, 8);
    add(SegmentKind::accelerate, 10, 6);
    add(SegmentKind::turn, -225, 20);
    add(SegmentKind::cruise, 10);
    add(SegmentKind::stop, 8);
  }
  return r;
}

Vec3 nominal_mounting_rpy() { return Vec3(0, 0, 90 * kDeg); }
Mat3 nominal_mounting() { return ins::dcm_from_rpy(nominal_mounting_rpy()); }

DriveSimConfig drive_config(const Route& route, std::uint64_t seed, double imu_rate_hz, const Vec3& misalignment_deg,
                            const Vec3& lever_arm_m) {
  DriveSimConfig cfg;
  cfg.route = route;
  cfg.mems = draw_random_unit(seed);
  cfg.imu_rate_hz = imu_rate_hz;
  cfg.reference.rate_hz = 50;
  cfg.gnss.rate_hz = 0;
  cfg.mounting_rpy = nominal_mounting_rpy() + misalignment_deg * kDeg;
  cfg.lever_arm = lever_arm_m;
  cfg.seed = seed;
  return cfg;
}

inmotion::RefObs ref_obs(const SimRef& r) {
  return {r.t, r.lat, r.lon, r.h, r.v_ned, r.rpy, r.sigma_pos, r.sigma_vel, r.sigma_att};
}

}  // namespace calbench::inmotion_test
