// Stochastic error levels of an IMU, as a data sheet states them, converted to SI.
// Used by the simulators (to make noise) and, as prior knowledge, by the estimators.
#pragma once
#include "common/units.hpp"

namespace calbench {

struct TriadNoise {
  double white_density = 0;   // white noise density: rad/s/√Hz (gyro ARW) or m/s²/√Hz (accel VRW)
  double drift_sigma = 0;     // in-run bias drift, first-order Gauss–Markov σ (rad/s or m/s²)
  double drift_tau_s = 300;   // its correlation time
  double lsb = 0;             // output quantisation step of the 32-bit register (rad/s or m/s²)
  double range = 0;           // full-scale (rad/s or m/s²)
};

struct NoiseSpec {
  TriadNoise gyro;
  TriadNoise accel;
  double output_rate_hz = 2460.0;
};

// ADIS16488A data-sheet class: ARW 0.26 °/√h, in-run bias stability 5.1 °/h, VRW 0.029 m/s/√h,
// accelerometer in-run bias stability 0.1 mg, ±450 °/s, ±18 g, 32-bit LSB = 0.02/2¹⁶ °/s and
// 0.8/2¹⁶ mg. The in-run bias drift is modelled as a first-order Gauss–Markov process with σ equal
// to the stated bias stability and a correlation time of 300 s.
inline NoiseSpec adis16488a_noise() {
  using namespace units;
  NoiseSpec n;
  n.gyro.white_density = 0.26 * kDeg / kSqrtHour;
  n.gyro.drift_sigma = 5.1 * kDegPerHour;
  n.gyro.drift_tau_s = 300.0;
  n.gyro.lsb = 0.02 / 65536.0 * kDeg;
  n.gyro.range = 450.0 * kDeg;
  n.accel.white_density = 0.029 / kSqrtHour;
  n.accel.drift_sigma = 0.1 * kMilliG;
  n.accel.drift_tau_s = 300.0;
  n.accel.lsb = 0.8e-3 / 65536.0 * kG0;
  n.accel.range = 18.0 * kG0;
  n.output_rate_hz = 2460.0;
  return n;
}

}  // namespace calbench
