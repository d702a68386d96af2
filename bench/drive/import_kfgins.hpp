// `calbench import kf-gins`: the KF-GINS text formats (whitespace-separated columns) into the
// recording interchange format (kind "drive"):
//   IMU file:  t_s, Δθx, Δθy, Δθz (rad), Δvx, Δvy, Δvz (m/s)  — increments, IMU = body axes
//   truth.nav: week, t_s, lat_deg, lon_deg, h_m, vn, ve, vd (m/s), roll, pitch, yaw (deg)
//   GNSS .pos: t_s, lat_deg, lon_deg, h_m, σn, σe, σd (m)
// Column positions: kfgins_columns.hpp (shared with the writer, export_kfgins.hpp).
// Extra columns are ignored. Every defect is an InputError with file, line and column.
#pragma once
#include <string>

#include "common/sensor_model.hpp"

namespace calbench {

struct ImportKfGinsArgs {
  std::string imu, truth, gnss, out, model = "unknown", serial = "kf-gins";
  double rate_hz = 0;  // 0: from the median sample interval
  Vec3 mounting_rpy_deg = Vec3::Zero();
  Vec3 lever_arm_m = Vec3::Zero();
  // The interchange writer always has sigma columns; KF-GINS truth files carry none, so the
  // reference's accuracy is stated here (defaults: a post-processed navigation-grade reference).
  double ref_sigma_pos_m = 0.05, ref_sigma_vel_m_s = 0.01, ref_sigma_att_deg = 0.01;
  bool force = false;
};

struct ImportSummary {
  std::size_t imu_rows = 0, ref_rows = 0, gnss_rows = 0;
  double rate_hz = 0;
};

ImportSummary import_kf_gins(const ImportKfGinsArgs& a);

}  // namespace calbench
