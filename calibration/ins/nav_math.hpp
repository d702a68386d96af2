// Navigation-frame mathematics shared by the strapdown INS, the drive simulator and the in-motion
// filter: WGS-84 radii of curvature and rates in the local north-east-down (NED) frame, attitude
// conversions, and small-angle/rotation-vector helpers. Angles in radians, SI throughout.
#pragma once
#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "common/sensor_model.hpp"

namespace calbench::ins {

using Quat = Eigen::Quaterniond;

// WGS-84 meridian (RM) and prime-vertical (RN) radii of curvature at geodetic latitude.
struct Radii {
  double RM = 0, RN = 0;
};
Radii wgs84_radii(double lat_rad);

// The Earth-related quantities a NED mechanization needs at a point moving with velocity v_ned.
struct LocalEarth {
  Radii r;
  Vec3 w_ie;  // Earth rate in NED, rad/s
  Vec3 w_en;  // transport rate in NED, rad/s
  Vec3 g;     // WGS-84 normal gravity in NED (GeographicLib::NormalGravity), m/s², down positive
};
LocalEarth local_earth(double lat_rad, double h_m, const Vec3& v_ned);
// Earth rotation in NED at a latitude, rad/s.
Vec3 earth_rate_ned_at(double lat_rad);

// C = Rz(yaw)·Ry(pitch)·Rx(roll): body (forward-right-down) → NED, or MEMS → reference body
// for the mounting (spec: recording-format.md).
Mat3 dcm_from_rpy(const Vec3& rpy_rad);
// Inverse of dcm_from_rpy (roll, pitch, yaw), yaw in (−π, π].
Vec3 rpy_from_dcm(const Mat3& C);
// J = ∂rpy/∂δ of rpy_from_dcm((I + δ×)·C) at δ = 0 (a small rotation applied on the left, in the
// axes C maps into), by central differences; angle differences wrapped to (−π, π].
Mat3 rpy_jacobian_left(const Mat3& C);
// Skew-symmetric matrix: skew(a)·b = a × b.
Mat3 skew(const Vec3& a);
// Quaternion of the rotation vector phi (exact, with small-angle series near zero).
Quat quat_from_rotvec(const Vec3& phi);
// Rotation vector of a rotation matrix (log map).
Vec3 rotvec_from_dcm(const Mat3& C);

// Geodetic position difference a − b expressed in metres north, east, down at b.
Vec3 geodetic_diff_ned(double lat_a, double lon_a, double h_a, double lat_b, double lon_b, double h_b);
// Move a geodetic position by a small NED displacement (metres).
void geodetic_add_ned(double& lat, double& lon, double& h, const Vec3& d_ned);

}  // namespace calbench::ins
