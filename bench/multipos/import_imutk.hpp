// calbench import imu-tk: IMU-TK's text files (one per triad, rows `t x y z`) into a multipos
// recording (../shared/spec/recording-format.md, kind "multipos"). Values are taken as SI and time
// in seconds unless a counts conversion and time unit are given; the conversion is recorded in
// meta.json `source_counts`, not re-applied by readers.
#pragma once
#include <optional>
#include <string>

#include "bench/multipos/multipos_import.hpp"
#include "common/sensor_model.hpp"

namespace calbench {

struct CountsConversion {
  Vec3 offset = Vec3::Zero();     // counts at zero input
  Vec3 scale = Vec3::Ones();      // SI per count (rad/s or m/s²)
  bool given = false;             // false: the files are SI already
};

struct ImportImuTkArgs : MultiposTarget {
  std::string acc, gyro;
  CountsConversion acc_counts, gyro_counts;
  std::string time_unit = "s";
};

struct ImportImuTkSummary {
  std::size_t rows = 0;
  double rate_hz = 0;
};

// InputError naming file, line and column on anything malformed; nothing is written then.
ImportImuTkSummary import_imu_tk(const ImportImuTkArgs& a);

}  // namespace calbench
