// `calbench export kf-gins`: a drive recording into the text files of KF-GINS (i2Nav-WHU's
// EKF-based loosely coupled GNSS/INS, run as an external program), the reverse of
// `import kf-gins` (import_kfgins.hpp; columns: kfgins_columns.hpp). Written into FOLDER:
//   imu.txt       IMU increments in KF-GINS's IMU frame, forward-right-down. calbench's reference
//                 body frame is forward-right-down too, so the MEMS axes are turned into it through
//                 the recording's nominal mounting (meta.json mounting.rpy_deg, C_mb); the mounting's
//                 residual misalignment is left to KF-GINS's attitude (it has no mounting state).
//   gnss.pos      the fixes of gnss.csv (antenna), σ north = σ east = sigma_h_m, σ down = sigma_v_m
//   truth.nav     reference.csv as it is (reference body origin; attitude of the body frame), week 0
//   kf-gins.yaml  a starter configuration: initial state at --start from the reference (else the
//                 first fix), initial gyro bias from an opening standstill when one is named, IMU noise and initial sensor-error spread of the data-sheet class,
//                 antenna lever arm = −(meta.json lever arm) in the IMU frame, outputpath = FOLDER.
// The data files carry no comment line (KF-GINS's reader takes every line as numbers).
// Times are the recording's clock (KF-GINS takes them as seconds of week: it refuses times beyond
// 604800 s). Written into a staging folder and renamed into place (atomic).
#pragma once
#include <string>

#include "common/sensor_model.hpp"

namespace calbench {

struct ExportKfGinsArgs {
  std::string dir, out;
  double start_s = -1;  // < 0: the first reference epoch (else fix) at or after the first IMU sample
  // > 0: the first standstill_s seconds after the start are a standstill: KF-GINS's initial gyro
  // bias is their mean rate less the Earth rate (in the IMU frame at the initial attitude), its σ
  // the white noise over the window combined with the in-run instability. 0: bias 0, σ the
  // raw-data prior.
  double standstill_s = 0;
  bool force = false;
};

struct ExportSummary {
  std::size_t imu_rows = 0, gnss_rows = 0, truth_rows = 0;
  double start_s = 0;
  Vec3 gyro_bias_dph = Vec3::Zero();  // initial gyro bias written (standstill_s > 0)
  bool init_from_reference = false;
};

ExportSummary export_kf_gins(const ExportKfGinsArgs& a);

}  // namespace calbench
