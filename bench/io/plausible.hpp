// Plausibility bounds of a recording (issue 35): input that is finite but absurd (a lever arm of
// 1e15 m, a time stamp of 1.8e308 s, an angular rate of 1e30 rad/s) is bad input, refused where it
// is read naming the file, line and field (exit 2), not left to break a filter numerically. The
// bounds are far beyond any IMU, vehicle or bench; docs/recording-csv.md states them. One place:
// the table readers (time), ImuReader (intervals and values) and read_meta (meta.json) use these.
#pragma once
#include <cmath>
#include <string>

#include "bench/io/message_text.hpp"
#include "bench/io/table_source.hpp"

namespace calbench::plausible {

inline constexpr double kMaxAbsTime_s = 1e10;         // time stamps: 317 years (Unix or GPS seconds fit)
inline constexpr double kMaxImuInterval_s = 3600;     // between consecutive IMU rows
inline constexpr double kMaxAngularRate_rad_s = 1e4;  // |ω| per axis (IMUs saturate below 100 rad/s)
inline constexpr double kMaxSpecificForce_m_s2 = 1e5; // |f| per axis (about 10,000 g)
inline constexpr double kMaxImuRate_Hz = 1e6;         // meta.json imu_rate_hz
inline constexpr double kMaxLeverArm_m = 100;         // |lever_arm_m|, meta.json mounting
inline constexpr double kMaxMountingAngle_deg = 360;  // each of mounting.rpy_deg
inline constexpr double kMaxAbsHeight_m = 1e5;        // site.h_m

// The time of a table's row (in its time column), after the row before it (has_last): within
// ±kMaxAbsTime_s, strictly increasing. The one check of time order of every table reader.
inline void check_row_time(const TableSource& s, const std::string& column, double t, bool has_last, double last) {
  if (!(std::abs(t) <= kMaxAbsTime_s))
    s.fail_at(column, "time " + number_text(t) + " s is not plausible (at most " + number_text(kMaxAbsTime_s) + " s)");
  if (has_last) {
    if (t == last) s.fail_at(column, "duplicated time " + number_text(t));
    if (t < last) s.fail_at(column, "time goes backwards");
  }
}

}  // namespace calbench::plausible
