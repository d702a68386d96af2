// A bench calibration plan: what the two-axis table does, step by step.
//
// Table geometry (local level frame L = NED at the bench site):
//   outer axis: horizontal, along north (x_L); outer angle θo rotates about it: C_O→L = Rx(θo)
//   inner axis: the outer gimbal's z (down when θo = 0); inner angle θi: C_P→O = Rz(θi)
//   the IMU sits on the inner platform P in a fixture ("mount"): C_B→P, one of three cube faces,
//   chosen so that the named IMU axis lies along the inner (rate) axis, or one of three faces of a
//   45° wedge that put a face diagonal (e_i + e_j)/√2 of the IMU there ("xy", "yz", "zx"), so that
//   a rate step turns two IMU axes at once (the gyro cross-coupling ω_i·ω_j needs that).
// So C_B→L = Rx(θo)·Rz(θi)·C_B→P. Rate steps spin the inner axis; a rate step about IMU axis k
// needs mount k (the station asks the operator to re-mount the cube when it changes).
#pragma once
#include <string>
#include <vector>

#include "common/sensor_model.hpp"

namespace calbench {

struct Site {
  double lat_deg = 0, lon_deg = 0, h_m = 0;
};

struct TableSpec {
  double max_rate = 0;            // rad/s, inner axis
  double max_accel = 0;           // rad/s², both axes
  double slew_rate = 0;           // rad/s, positioning moves
  double settle_s = 0;            // time after a move before data counts
  double remount_s = 0;           // time the operator needs to re-mount the cube (no data)
  // The bench's own errors (1σ), used by the estimators as measurement noise.
  double rate_accuracy_rel = 0;   // relative rate error (e.g. 1e-6 = 1 ppm)
  double position_accuracy = 0;   // rad, static position error of the platform
  double axis_wobble = 0;         // rad, tilt of the rate axis from nominal while spinning
};

enum class StepKind { static_position, rate };

struct PlanStep {
  StepKind kind = StepKind::static_position;
  std::string label;
  int mount = 2;           // IMU direction along the inner axis: 0..2 = x, y, z; 3..5 = the diagonals xy, yz, zx
  double outer = 0;        // rad: outer angle for the step
  double inner = 0;        // rad: inner angle (static steps; start angle of rate steps)
  double rate = 0;         // rad/s: inner-axis rate (rate steps), right-handed about +IMU axis `mount`
  double dwell_s = 0;      // data time at the step, after settling
  int line = 0;            // line in the plan file, for messages
};

// Temperature of the device during the run (the bench simulator; docs/bench-calibration.md,
// [temperature]). Without it (set = false) the simulator's default applies: self-heating warm-up
// from 25 °C towards 31 °C (τ = 15 min). With it: a chamber follows the piecewise-linear setpoints
// (held before the first and after the last point), the device follows the chamber through a
// first-order lag, and self-heating adds self_heating_k·(1 − e^(−t/τ)).
struct TemperatureProfile {
  bool set = false;
  std::vector<std::pair<double, double>> chamber;  // (t s, °C), t increasing
  double lag_s = 0;                                // device vs chamber time constant
  double self_heating_k = 0, self_heating_tau_s = 900;
  double chamber_at(double t) const;               // setpoint at t
};

// An operator prompt (issue 38): a [[step]] of kind "prompt" in the plan file. The station asks it
// before table step `before_step` (== steps.size(): after the last) and waits for a person's answer
// (docs/devices.md "Operator prompts"); the table steps, their indices and every estimator ignore it.
struct PlanPrompt {
  std::size_t before_step = 0;
  std::string text;        // e.g. "mount the unit in slot 3, then confirm"
  std::string slot;        // the slot it concerns ("" : the whole fixture)
  double timeout_s = 600;  // unanswered this long: the run aborts (table stopped)
  int line = 0;
};

struct BenchPlan {
  std::string name;
  std::string description;
  Site site;               // default site (a recording's meta.json overrides)
  TableSpec table;
  std::vector<PlanStep> steps;
  std::vector<PlanPrompt> prompts;  // by before_step
  TemperatureProfile temperature;
  std::string fixture_file;  // [plan] fixture: the station's multi-unit fixture (path; empty: one unit)
};

// The fixtures: IMU axes x, y, z (cube faces) and the face diagonals xy, yz, zx (45° wedge).
inline constexpr int kMountCount = 6;
// "x", "y", "z", "xy", "yz", "zx".
const char* mount_name(int mount);
// The mount of a name ("+x" is "x"); -1 if there is none.
int mount_from_name(const std::string& name);
// C_B→P of the fixture that puts the IMU direction of `mount` along the platform's z.
Mat3 mount_rotation(int mount);
// That IMU direction, a unit vector in IMU axes (C_B→P's last row).
Vec3 mount_direction(int mount);
// C_B→L for table angles and mount.
Mat3 imu_attitude(double outer, double inner, int mount);
// Table angles (outer, inner) that realise C_B→L with the given mount; false if unreachable
// (the mount axis must be perpendicular to the outer axis, i.e. to north).
bool solve_table_angles(const Mat3& C_b_l, int mount, double& outer, double& inner, double tol = 1e-9);
// Nominal duration of the plan (dwell + settle + moves + remounts), seconds.
double plan_duration_s(const BenchPlan& plan);

}  // namespace calbench
