// The IMU's attitude on the two-axis table from the bench reference alone (the table-tilt term of
// the effect registry needs it per 0.05 s sub-block; the diagnosis uses it too).
#pragma once
#include "common/sensor_model.hpp"

namespace calbench {

// Attitude of the IMU in a static position from the reference (TRIAD on gravity and Earth rate):
// false if not static.
bool static_attitude(const Vec3& w, const Vec3& f, Mat3& C_b_l);

// Attitude of the IMU on the two-axis table from the reference of a static or a rotating
// sub-block: down from the specific force; north from the Earth rate. While the inner axis spins
// (about a fixture direction k: an IMU axis, or a face diagonal on the 45° wedge), the table
// geometry keeps north perpendicular to k (the outer axis points north, the inner axis is
// perpendicular to it), so north ∝ k × down with the sign of the Earth rate along it, or, with k
// vertical, the Earth rate perpendicular to k. False if neither works (no gravity, or a rate not
// about a fixture direction).
bool bench_attitude(const Vec3& w, const Vec3& f, Mat3& C_b_l);

}  // namespace calbench
