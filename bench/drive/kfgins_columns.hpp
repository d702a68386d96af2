// The KF-GINS text formats (i2Nav-WHU/KF-GINS, README section 2.2), stated once for the reader
// (`import kf-gins`, import_kfgins.*) and the writer (`export kf-gins`, export_kfgins.*):
// whitespace-separated columns, one epoch a line.
//   IMU file:   t_s, Δθ x y z (rad), Δv x y z (m/s): increments over the interval ending at t, in
//               KF-GINS's IMU frame (forward-right-down)
//   GNSS .pos:  t_s, lat (deg), lon (deg), h (m), σ north, east, down (m)
//   navigation: week, t_s, lat (deg), lon (deg), h (m), vn, ve, vd (m/s), roll, pitch, yaw (deg)
//               (truth.nav, and KF-GINS's own result KF_GINS_Navresult.nav)
#pragma once
#include <cstddef>

namespace calbench::kfgins {

namespace imu_col {
inline constexpr std::size_t t = 0, dtheta = 1, dvel = 4, count = 7;
}
namespace gnss_col {
inline constexpr std::size_t t = 0, lat = 1, lon = 2, h = 3, sigma_n = 4, sigma_e = 5, sigma_d = 6, count = 7;
}
namespace nav_col {
inline constexpr std::size_t week = 0, t = 1, lat = 2, lon = 3, h = 4, vel = 5, rpy = 8, count = 11;
}

// Significant digits every exported number carries: the shortest count that gives a double back
// exactly, so that export → import reproduces the values (tests/cli/drive_export_kfgins.sh).
inline constexpr int kDigits = 17;

}  // namespace calbench::kfgins
