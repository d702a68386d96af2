// The unit learned from the data (issue 34, item 2): standstills found in the IMU samples of a
// recording, and the white-noise level of each axis measured on them. docs/in-motion.md, "White
// noise measured on standstills", states the rule and its reasoning; in short:
//
// Detection. The samples are cut into consecutive windows of `window_s`. A window is still when,
// on every one of the six axes, the standard deviation of its samples about their mean is at most
// `ratio` times the per-sample white-noise σ of the device class, σ = N/√dt (N the class's ARW or
// VRW, dt the window's mean sample interval). Consecutive still windows make a standstill; one of
// at least `min_duration_s` is used. A window with a time gap (a step over 5× the previous one)
// ends the current standstill.
//
// Measurement. On each standstill and axis, the overlapping Allan deviation at the shortest cluster
// time τ = dt (identification/allan.hpp; σ²(dt) is half the mean square of first differences), so
// that N = σ(dt)·√dt. First differences remove the mean (the bias and gravity) and most of a slow
// motion the detector let through. The levels of several standstills are pooled per axis, each
// weighted by its number of differences: N² = Σ n_k N_k² / Σ n_k.
#pragma once
#include <array>
#include <cstddef>
#include <limits>
#include <vector>

#include "common/noise_spec.hpp"
#include "common/sensor_model.hpp"

namespace calbench::identification {

struct StandstillConfig {
  double window_s = 0.5;        // detection window
  double ratio = 3.0;           // still: sample σ ≤ ratio × class σ on all six axes
  double min_duration_s = 1.0;  // shortest standstill measured
  std::size_t max_samples = 1u << 17;  // samples kept per standstill (the first ones)
};

struct Standstill {
  double t0 = 0, t1 = 0;  // first and last sample time, s
  double dt = 0;          // mean sample interval, s
  // Samples per axis: gyro x, y, z (rad/s), accelerometer x, y, z (m/s²); at most max_samples.
  std::array<std::vector<double>, 6> y;
};

// Fed sample by sample (rates: rad/s, m/s²), in time order.
class StandstillDetector {
 public:
  explicit StandstillDetector(const NoiseSpec& cls, StandstillConfig cfg = {});
  void add(double t, const Vec3& gyro, const Vec3& accel);
  // Closes the last standstill; call once after the last sample.
  void finish();
  const std::vector<Standstill>& standstills() const { return found_; }

 private:
  void close_window();
  void close_standstill();
  NoiseSpec cls_;
  StandstillConfig cfg_;
  double last_t_ = std::numeric_limits<double>::quiet_NaN(), last_step_ = 0;
  std::vector<double> wt_;                   // current window: times
  std::array<std::vector<double>, 6> wy_;    // and samples
  bool open_ = false;                        // a standstill is being extended
  Standstill cur_;
  std::size_t cur_n_ = 0;                    // samples of cur_ (kept or not)
  double cur_dt_sum_ = 0;
  std::vector<Standstill> found_;
};

// White noise per axis: gyro x, y, z (rad/√s), accelerometer x, y, z (m/s/√s).
struct AxisLevels {
  std::array<double, 6> v{};
};

struct StandstillNoise {
  double t0 = 0, t1 = 0, dt = 0;
  std::size_t samples = 0;
  AxisLevels level;
};

struct NoiseMeasurement {
  std::vector<StandstillNoise> standstills;
  bool measured = false;  // at least one standstill
  AxisLevels level;       // pooled (NaN when not measured)
  AxisLevels cls;         // the class's level per axis
  AxisLevels ratio;       // level / cls
  // Per triad (0 gyro, 1 accel): some axis differs from the class by more than `factor` (either
  // way); then `used` is the largest measured level of that triad (the filter's process noise is
  // one density per triad, isotropic in the navigation frame), else the class's.
  std::array<bool, 2> differs{false, false};
  // Per triad: some axis measured exactly zero (a noise-free signal, or noise below the output
  // LSB): not a level the filter can take; the class is kept.
  std::array<bool, 2> zero{false, false};
  std::array<double, 2> used{0, 0};
  double factor = 2.0;
};

NoiseMeasurement measure_white_noise(const std::vector<Standstill>& s, const NoiseSpec& cls, double factor = 2.0);

// `cls` with the white-noise densities the measurement says to use.
NoiseSpec apply_measured_noise(const NoiseSpec& cls, const NoiseMeasurement& m);

}  // namespace calbench::identification
