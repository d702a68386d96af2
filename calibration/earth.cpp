#include "calibration/earth.hpp"

#include <GeographicLib/NormalGravity.hpp>
#include <cmath>

#include "common/units.hpp"

namespace calbench {

Vec3 normal_gravity_ned(double lat_rad, double h_m) {
  static const GeographicLib::NormalGravity& wgs = GeographicLib::NormalGravity::WGS84();
  double gy = 0, gz = 0;  // northerly and upward components
  wgs.Gravity(lat_rad / units::kDeg, h_m, gy, gz);
  return Vec3(gy, 0.0, -gz);
}

Vec3 earth_rate_ned(double lat_rad) {
  return Vec3(units::kEarthRate * std::cos(lat_rad), 0.0, -units::kEarthRate * std::sin(lat_rad));
}

SiteEarth::SiteEarth(const Site& site)
    : g_ned(normal_gravity_ned(site.lat_deg * units::kDeg, site.h_m)),
      w_ie_ned(earth_rate_ned(site.lat_deg * units::kDeg)) {}

}  // namespace calbench
