#include "calibration/inmotion/state_blocks.hpp"

#include "common/units.hpp"

namespace calbench::inmotion {

namespace {
// Series columns: totals (estimate, not error) in display units.
const char* const kPosCols[] = {"lat_deg", "lon_deg", "h_m"};  // MEMS IMU position
const char* const kVelCols[] = {"vel_n_m_s", "vel_e_m_s", "vel_d_m_s"};
const char* const kAttCols[] = {"roll_deg", "pitch_deg", "yaw_deg"};
const char* const kBgCols[] = {"gyro_bias_x_dph", "gyro_bias_y_dph", "gyro_bias_z_dph"};
const char* const kBaCols[] = {"accel_bias_x_mg", "accel_bias_y_mg", "accel_bias_z_mg"};
const char* const kMgCols[] = {"gyro_M_xx_ppm", "gyro_M_xy_ppm", "gyro_M_xz_ppm", "gyro_M_yx_ppm", "gyro_M_yy_ppm",
                               "gyro_M_yz_ppm", "gyro_M_zx_ppm", "gyro_M_zy_ppm", "gyro_M_zz_ppm"};
const char* const kMaCols[] = {"accel_M_xx_ppm", "accel_M_xy_ppm", "accel_M_xz_ppm", "accel_M_yx_ppm", "accel_M_yy_ppm",
                               "accel_M_yz_ppm", "accel_M_zx_ppm", "accel_M_zy_ppm", "accel_M_zz_ppm"};
const char* const kMountCols[] = {"mount_roll_deg", "mount_pitch_deg", "mount_yaw_deg"};
const char* const kDgCols[] = {"gyro_drift_x_dph", "gyro_drift_y_dph", "gyro_drift_z_dph"};
const char* const kDaCols[] = {"accel_drift_x_mg", "accel_drift_y_mg", "accel_drift_z_mg"};
const char* const kDgAuxCols[] = {"gyro_drift_aux_x_dph_s", "gyro_drift_aux_y_dph_s", "gyro_drift_aux_z_dph_s"};
const char* const kDaAuxCols[] = {"accel_drift_aux_x_mg_s", "accel_drift_aux_y_mg_s", "accel_drift_aux_z_mg_s"};

constexpr int sz(Block b) { return size_of(b); }
}  // namespace

const std::array<BlockSpec, static_cast<std::size_t>(Block::count)>& block_specs() {
  using namespace units;
  static const std::array<BlockSpec, static_cast<std::size_t>(Block::count)> specs = {{
      {Block::pos, "position", sz(Block::pos), kPosCols, "m (NED)", "deg, deg, m", 1.0, false, false},
      {Block::vel, "velocity", sz(Block::vel), kVelCols, "m/s (NED)", "m/s", 1.0, false, false},
      {Block::att, "attitude", sz(Block::att), kAttCols, "rad", "deg", kDeg, false, false},
      {Block::bg, "gyro_bias", sz(Block::bg), kBgCols, "rad/s", "deg/h", kDegPerHour, true, false},
      {Block::ba, "accel_bias", sz(Block::ba), kBaCols, "m/s^2", "mg", kMilliG, true, false},
      {Block::Mg, "gyro_M", sz(Block::Mg), kMgCols, "1", "ppm", kPpm, true, false},
      {Block::Ma, "accel_M", sz(Block::Ma), kMaCols, "1", "ppm", kPpm, true, false},
      {Block::mount, "mounting", sz(Block::mount), kMountCols, "rad", "deg", kDeg, false, false},
      {Block::dg, "gyro_drift", sz(Block::dg), kDgCols, "rad/s", "deg/h", kDegPerHour, true, false},
      {Block::da, "accel_drift", sz(Block::da), kDaCols, "m/s^2", "mg", kMilliG, true, false},
      {Block::dg_aux, "gyro_drift_aux", sz(Block::dg_aux), kDgAuxCols, "rad/s^2", "deg/h/s", kDegPerHour, true, true},
      {Block::da_aux, "accel_drift_aux", sz(Block::da_aux), kDaAuxCols, "m/s^3", "mg/s", kMilliG, true, true},
  }};
  return specs;
}

}  // namespace calbench::inmotion
