#include "calibration/inmotion/state_layout.hpp"

namespace calbench::inmotion {

const std::array<std::string, 6>& total_drift_names() {
  static const std::array<std::string, 6> names = {"gyro_total_x_dph",  "gyro_total_y_dph",  "gyro_total_z_dph",
                                                   "accel_total_x_mg", "accel_total_y_mg", "accel_total_z_mg"};
  return names;
}

}  // namespace calbench::inmotion
