// Standstill detection from the IMU data, for the zero-velocity and zero-rate updates
// (obs_zupt.cpp) and to keep the non-holonomic constraint (obs_nhc.cpp) off while standing.
//
// Rule (docs/in-motion.md, "Vehicle constraints"): over the last `window_s` of samples, the spread
// of every gyro axis and of every accelerometer axis (sample variance) is at most `factor` times
// what the sensor's white noise alone makes of one sample, q²/Δt + lsb²/12 (q: white-noise density
// of the NoiseSpec, Δt: the mean sample interval; an increment over Δt carries a white-noise
// variance q²/Δt of its rate, the quantisation lsb²/12). At rest that ratio is 1 on average with a
// relative spread √(2/(n−1)) over n samples (0.14 at 100 samples): a factor of 3 misses a true
// standstill of a quiet unit essentially never, and leaves room for the anti-alias filter,
// quantisation beyond the model and an idling engine's vibration. A moving vehicle excites far
// more than that — except on a perfectly smooth straight road at constant speed, which the IMU
// alone cannot tell from a standstill: the filter adds a speed condition (the INS's and the fixes').
#pragma once
#include <cmath>
#include <deque>

#include "common/noise_spec.hpp"
#include "common/sensor_model.hpp"

namespace calbench::inmotion {

class StandstillDetector {
 public:
  explicit StandstillDetector(double window_s = 1.0) : window_s_(window_s) {}
  // One sample: rate (rad/s) and specific force (m/s²) of the data over the dt ending at t.
  void add(double t, const Vec3& w, const Vec3& f, double dt);
  // Whether the last window is quiet by the rule above (false until a full window is held).
  // gyro_ratio/accel_ratio: the largest axis's spread over its white-noise variance.
  bool quiet(const NoiseSpec& n, double factor, double* gyro_ratio = nullptr, double* accel_ratio = nullptr) const;
  // Time of the first sample of the window held (the start of a standstill found now).
  double window_start() const { return s_.empty() ? 0.0 : s_.front().t - s_.front().dt; }

 private:
  struct Sample {
    double t, dt;
    Vec3 w, f;
  };
  double window_s_;
  std::deque<Sample> s_;
};

// 1σ per axis of the mean rate (or specific force) of a triad over T seconds of a standstill: the
// white noise the rule above allows (its factor) and the quantisation of one sample.
inline double standstill_mean_sigma(const TriadNoise& q, double factor, double T) {
  return std::sqrt(factor * q.white_density * q.white_density / T + q.lsb * q.lsb / 12.0);
}

}  // namespace calbench::inmotion
