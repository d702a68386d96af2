// The simulated MEMS IMU: turns true angular rate and specific force into what the device
// outputs, with the spec's deterministic model measured = (I + M)·true + b, a first-order
// Gauss–Markov in-run drift of the bias, white noise, saturation and 32-bit output quantisation.
// The drift is discretised exactly, so its level does not depend on the sample rate.
#pragma once
#include <random>

#include "common/noise_spec.hpp"
#include "common/sensor_model.hpp"

namespace calbench {

class ImuErrorSimulator {
 public:
  ImuErrorSimulator(const SensorErrors& truth, const NoiseSpec& noise, std::uint64_t seed);

  struct Output {
    Vec3 gyro;   // rad/s
    Vec3 accel;  // m/s²
    bool saturated = false;
  };
  // One output sample at time t (seconds, increasing) for the true inputs at that time.
  Output sample(double t, const Vec3& w_true, const Vec3& f_true);

  const Vec3& gyro_drift() const { return gyro_drift_; }    // current drift (truth side only)
  const Vec3& accel_drift() const { return accel_drift_; }
  const SensorErrors& truth() const { return truth_; }
  void set_truth(const SensorErrors& truth) { truth_ = truth; }

 private:
  void advance_drift(double dt);
  SensorErrors truth_;
  NoiseSpec noise_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> n01_{0.0, 1.0};
  Vec3 gyro_drift_, accel_drift_;
  double t_last_ = 0;
  bool started_ = false;
};

// Spread (1σ) of an uncalibrated part of a device class, as its data sheet states it (SI):
// turn-on bias, scale error (diagonal of M) and skew (off-diagonal).
struct UnitSpread {
  double gyro_bias = 0, accel_bias = 0;    // rad/s, m/s²
  double gyro_scale = 0, gyro_skew = 0;    // dimensionless
  double accel_scale = 0, accel_skew = 0;
};

// Draw a unit of a device class (bench/imu_classes/*.toml, [spread]).
SensorErrors draw_random_unit(std::uint64_t seed, const UnitSpread& spread);
// Draw a realistic ADIS16488A-class unit: turn-on biases, scale errors and skews of data-sheet
// magnitude (gyro bias ~0.2 °/s, accel bias ~16 mg, scale ~0.5 %, skews ~0.05 %) — the built-in
// default of the simulators; bench/imu_classes/adis16488a.toml holds the same figures (a unit test
// pins them equal).
SensorErrors draw_random_unit(std::uint64_t seed);

}  // namespace calbench
