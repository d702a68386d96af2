#include "calibration/ins/nav_math.hpp"

#include <GeographicLib/Constants.hpp>
#include <cmath>

#include "calibration/earth.hpp"
#include "common/units.hpp"

namespace calbench::ins {

Radii wgs84_radii(double lat_rad) {
  const double a = GeographicLib::Constants::WGS84_a();
  const double f = GeographicLib::Constants::WGS84_f();
  const double e2 = f * (2.0 - f);
  const double s = std::sin(lat_rad);
  const double w = 1.0 - e2 * s * s;
  const double sw = std::sqrt(w);
  Radii r;
  r.RN = a / sw;
  r.RM = a * (1.0 - e2) / (w * sw);
  return r;
}

LocalEarth local_earth(double lat_rad, double h_m, const Vec3& v) {
  LocalEarth e;
  e.r = wgs84_radii(lat_rad);
  e.w_ie = earth_rate_ned(lat_rad);
  const double rn = e.r.RN + h_m, rm = e.r.RM + h_m;
  e.w_en = Vec3(v(1) / rn, -v(0) / rm, -v(1) * std::tan(lat_rad) / rn);
  e.g = normal_gravity_ned(lat_rad, h_m);
  return e;
}

Vec3 earth_rate_ned_at(double lat_rad) { return earth_rate_ned(lat_rad); }

Mat3 dcm_from_rpy(const Vec3& rpy) {
  return (Eigen::AngleAxisd(rpy(2), Vec3::UnitZ()) * Eigen::AngleAxisd(rpy(1), Vec3::UnitY()) *
          Eigen::AngleAxisd(rpy(0), Vec3::UnitX()))
      .toRotationMatrix();
}

Vec3 rpy_from_dcm(const Mat3& C) {
  const double pitch = std::asin(std::clamp(-C(2, 0), -1.0, 1.0));
  const double roll = std::atan2(C(2, 1), C(2, 2));
  const double yaw = std::atan2(C(1, 0), C(0, 0));
  return Vec3(roll, pitch, yaw);
}

Mat3 skew(const Vec3& a) {
  Mat3 S;
  S << 0, -a(2), a(1), a(2), 0, -a(0), -a(1), a(0), 0;
  return S;
}

Quat quat_from_rotvec(const Vec3& phi) {
  const double n2 = phi.squaredNorm();
  double c, s;  // cos(|φ|/2), sin(|φ|/2)/|φ|
  if (n2 < 1e-12) {
    c = 1.0 - n2 / 8.0;
    s = 0.5 - n2 / 48.0;
  } else {
    const double n = std::sqrt(n2);
    c = std::cos(0.5 * n);
    s = std::sin(0.5 * n) / n;
  }
  return Quat(c, s * phi(0), s * phi(1), s * phi(2));
}

Vec3 rotvec_from_dcm(const Mat3& C) {
  const Eigen::AngleAxisd aa(C);
  return aa.angle() * aa.axis();
}

Vec3 geodetic_diff_ned(double lat_a, double lon_a, double h_a, double lat_b, double lon_b, double h_b) {
  const Radii r = wgs84_radii(lat_b);
  double dlon = lon_a - lon_b;
  if (dlon > units::kPi) dlon -= 2 * units::kPi;
  if (dlon < -units::kPi) dlon += 2 * units::kPi;
  return Vec3((lat_a - lat_b) * (r.RM + h_b), dlon * (r.RN + h_b) * std::cos(lat_b), -(h_a - h_b));
}

void geodetic_add_ned(double& lat, double& lon, double& h, const Vec3& d) {
  const Radii r = wgs84_radii(lat);
  const double lat0 = lat;
  lat += d(0) / (r.RM + h);
  lon += d(1) / ((r.RN + h) * std::cos(lat0));
  h -= d(2);
}

}  // namespace calbench::ins

namespace calbench::ins {
Mat3 rpy_jacobian_left(const Mat3& C) {
  Mat3 J;
  const double h = 1e-7;
  for (int k = 0; k < 3; ++k) {
    Vec3 e = Vec3::Zero();
    e(k) = h;
    Vec3 d = rpy_from_dcm(quat_from_rotvec(e).toRotationMatrix() * C) - rpy_from_dcm(quat_from_rotvec(-e).toRotationMatrix() * C);
    for (int i = 0; i < 3; ++i) d(i) = std::remainder(d(i), 2 * units::kPi);
    J.col(k) = d / (2 * h);
  }
  return J;
}
}  // namespace calbench::ins
