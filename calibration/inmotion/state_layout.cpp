#include "calibration/inmotion/state_layout.hpp"

namespace calbench::inmotion {

const std::array<std::string, kStates>& state_names() {
  static const std::array<std::string, kStates> names = [] {
    std::array<std::string, kStates> n;
    const char* ax = "xyz";
    const char* ned[3] = {"n", "e", "d"};
    for (int i = 0; i < 3; ++i) {
      n[kPos + i] = i == 0 ? "lat_deg" : i == 1 ? "lon_deg" : "h_m";  // MEMS IMU position
      n[kVel + i] = std::string("vel_") + ned[i] + "_m_s";
      n[kAtt + i] = i == 0 ? "roll_deg" : i == 1 ? "pitch_deg" : "yaw_deg";
      n[kBg + i] = std::string("gyro_bias_") + ax[i] + "_dph";
      n[kBa + i] = std::string("accel_bias_") + ax[i] + "_mg";
      n[kMount + i] = i == 0 ? "mount_roll_deg" : i == 1 ? "mount_pitch_deg" : "mount_yaw_deg";
      n[kDg + i] = std::string("gyro_drift_") + ax[i] + "_dph";
      n[kDa + i] = std::string("accel_drift_") + ax[i] + "_mg";
      for (int j = 0; j < 3; ++j) {
        n[kMg + 3 * i + j] = std::string("gyro_M_") + ax[i] + ax[j] + "_ppm";
        n[kMa + 3 * i + j] = std::string("accel_M_") + ax[i] + ax[j] + "_ppm";
      }
    }
    return n;
  }();
  return names;
}

const std::array<std::string, kStatesAug - kStates>& aux_state_names() {
  static const std::array<std::string, kStatesAug - kStates> names = {
      "gyro_drift_aux_x_dph_s", "gyro_drift_aux_y_dph_s", "gyro_drift_aux_z_dph_s",
      "accel_drift_aux_x_mg_s", "accel_drift_aux_y_mg_s", "accel_drift_aux_z_mg_s"};
  return names;
}

const std::array<std::string, 6>& total_drift_names() {
  static const std::array<std::string, 6> names = {"gyro_total_x_dph",  "gyro_total_y_dph",  "gyro_total_z_dph",
                                                   "accel_total_x_mg", "accel_total_y_mg", "accel_total_z_mg"};
  return names;
}

}  // namespace calbench::inmotion
