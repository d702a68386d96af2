// `calbench simulate drive`: run the drive simulator on a route file and write a recording
// (kind "drive") with the truth next to it.
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace calbench {

struct SimulateDriveArgs {
  std::string route, truth, out, serial;
  std::uint64_t seed = 1;
  bool force = false;
  double until_s = 0;  // 0 = whole route
  // Catalogue effects to inject (docs/diagnosis.md): --inject EFFECT:key=value,... and/or an
  // --effects JSON file (a TRUTH.json carrying the keys is injected too).
  std::vector<std::string> inject;
  std::string effects;
  // --noise NOISE.json: the simulated unit's in-run drift instead of the data sheet's (first-order
  // Gauss–Markov per sensor): {"gyro": {"drift_sigma_deg_h": 20, "drift_tau_s": 60},
  // "accel": {"drift_sigma_mg": 0.1, "drift_tau_s": 300}}; every key optional; kept in truth.json.
  std::string noise;
  // --device-class: the simulated unit's class (a class file, or the name or alias of a built-in
  // class): its white noise, drift, ranges and LSB, and for --truth random its spread; meta.json
  // device.model names it. "" = ADIS16488A (the built-in default, unchanged).
  std::string device_class;
  // Several MEMS units on the vehicle (issue 21): N > 1 writes a multi-unit drive (units.json, the
  // reference once, one recording folder per unit; docs/recording-units.md), unit k with the errors
  // and mounting drawn from seed + k, turned 90°·k in yaw and 0.15 m round the route's lever arm.
  int units = 1;
  // The logger and receiver of sim_logger.hpp: reads per second of a logger polling the IMU (0:
  // the sensor's own instants), and fix velocities formed from the positions.
  double logger_read_hz = 0;
  bool gnss_velocity_from_positions = false;
};

struct SimulateDriveSummary {
  std::size_t imu_rows = 0, ref_rows = 0, gnss_rows = 0;  // imu_rows: per unit
  double duration_s = 0;
};

SimulateDriveSummary simulate_drive_recording(const SimulateDriveArgs& a);

}  // namespace calbench
