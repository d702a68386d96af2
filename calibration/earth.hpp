// Earth model at a site: WGS-84 normal gravity (GeographicLib) and Earth rotation in NED.
#pragma once
#include "calibration/bench_plan.hpp"
#include "common/sensor_model.hpp"

namespace calbench {

// Normal gravity vector (gravitation + centrifugal) in NED at geodetic latitude/height, m/s².
Vec3 normal_gravity_ned(double lat_rad, double h_m);
// Earth rotation vector in NED at latitude: [Ω cos φ, 0, −Ω sin φ].
Vec3 earth_rate_ned(double lat_rad);

// What a static bench site contributes: gravity and Earth rate in NED.
struct SiteEarth {
  Vec3 g_ned;      // gravity (m/s², down positive)
  Vec3 w_ie_ned;   // Earth rate (rad/s)
  explicit SiteEarth(const Site& site);
};

}  // namespace calbench
