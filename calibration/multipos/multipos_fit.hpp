// Multi-position calibration without a rate table (issue 37): a unit turned by hand or on a simple
// fixture through static poses whose orientations are unknown. Only the magnitude of gravity (and,
// for units that resolve it, the Earth rate) is known.
//
//   1. Static intervals are found in the data (static_detect.cpp, issue 55): a window is static when
//      the sample variance of every accelerometer and gyro axis is below margin·σ²·χ²_{n−1}(1−α)/(n−1),
//      with σ the white noise per sample learned from the recording itself — from its opening still
//      interval when it has one, else from its quietest windows — and α = 1e-4 per window and axis.
//      A device class's noise is a cross-check reported beside it, never the gate (docs/multipos.md).
//   2. Accelerometer (Skog & Händel 2006; Tedaldi, Pretto & Menegatti, ICRA 2014): bias and M from
//      ‖(I+M)⁻¹(f̄_k − b)‖ = g over the static poses k. The gravity magnitude does not see a rotation
//      of the frame, so three entries of M are fixed by the frame's definition: x along the
//      accelerometer's x axis, y in its x–y plane ((I+M) lower triangular: M01 = M02 = M12 = 0).
//   3. Gyros: bias from the statics, then bias and M (12 parameters) by integrating each rotation
//      between two consecutive static poses with the corrected rates and matching the gravity
//      direction the calibrated accelerometers measure at its end.
// Coefficients in the spec's convention measured = (I + M)·true + b, SI. No I/O.
#pragma once
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/sensor_model.hpp"

namespace calbench::multipos {

struct MultiposInput {
  std::vector<double> t;      // s, increasing
  std::vector<Vec3> gyro;     // rad/s
  std::vector<Vec3> accel;    // m/s²
  double rate_hz = 0;         // nominal sample rate
  double gravity = 9.80665;   // local gravity magnitude, m/s²
  std::optional<double> lat_rad;  // site latitude, for the Earth rate
  // The device class's white noise densities (rad/s/√Hz, m/s²/√Hz); 0 = unknown (measured only).
  double gyro_density = 0, accel_density = 0;
  // The class's in-run gyro bias stability (rad/s; 0 = no class: kWideGyroBiasStability): how far a
  // still unit's mean rate may stray from the statics' median bias.
  double gyro_bias_stability = 0;
  // The class's accelerometer bias stability (m/s²; 0 = unknown): the gravity direction measured at
  // either end of a rotation carries its tilt, σ/g per axis, in the rotations' weights.
  double accel_bias_stability = 0;
};

// A unit of no known class (issue 55): priors wide enough for any MEMS part, ten times the consumer
// class's assumed in-run stability (bench/imu_classes/icm42688p.toml: 10 °/h, 0.1 mg, 100 s).
constexpr double kWideGyroBiasStability = 100.0 * 3.14159265358979323846 / 180.0 / 3600.0;  // rad/s
constexpr double kWideAccelBiasStability = 1e-3 * 9.80665;                                  // m/s²
constexpr double kWideBiasTau = 100.0;                                                      // s

struct MultiposOptions {
  double window_s = 0.5;        // variance window of the static detector
  double min_static_s = 0.75;   // shortest static interval used as a pose (a 1-s pose counts)
  double alpha = 1e-4;          // false-alarm rate of the static test per window and axis
  double margin = 2.0;          // the test's variance limit over the χ² bound of white noise
  double quiet_fraction = 0.1;  // the noise from the quietest windows: this fraction must be still
  double min_opening_s = 2.0;   // an opening still interval this long sets the noise
  bool earth_rate = false;      // remove the vertical Earth rate from the static gyro means
  std::vector<int> exclude_poses;      // poses left out of the accelerometer fit (leave-one-out)
  std::vector<int> exclude_rotations;  // rotations left out of the gyro fit
  std::size_t min_poses = 9;           // the observability rule (multipos_fit.cpp, docs/multipos.md)
  std::size_t min_rotations = 6;
};

struct StaticInterval {
  std::size_t i0 = 0, i1 = 0;  // samples [i0, i1): every sample a still window covers (f_mean's)
  std::size_t c0 = 0, c1 = 0;  // the still windows' centres [c0, c1), at least half a window from any
                               // motion: the gyro mean's samples (a turn's slow tail biases a rate)
  double t0 = 0, t1 = 0;
  Vec3 f_mean = Vec3::Zero(), w_mean = Vec3::Zero();  // raw means (f over [i0, i1), ω over [c0, c1))
  Vec3 f_std = Vec3::Zero(), w_std = Vec3::Zero();    // sample standard deviations
  double g_residual_raw = 0;   // ‖f̄‖ − g before the fit, m/s²
  double g_residual = 0;       // ‖corrected f̄‖ − g after the fit, m/s²
  bool used = true;            // false when excluded
};

struct RotationUse {
  int from = 0, to = 0;        // pose indices
  std::size_t i0 = 0, i1 = 0;  // integrated samples [i0, i1): the turn and up to a window into either pose
  double t0 = 0, t1 = 0;       // integration span, s
  Vec3 angle_raw = Vec3::Zero();  // rotation vector integrated from the raw rates, rad
  double residual_rad = 0;     // angle between predicted and measured gravity direction after the fit
  bool used = true;
};

struct NoiseLevel {
  double class_sigma = 0;     // per sample, from the class density (0 = no class)
  double used_sigma = 0;      // per sample, the largest axis's, learned from the recording: the
                              // static test's and the fit's (the class's is a cross-check only)
  bool differs = false;       // measured and class differ by more than 2× (a note, not a gate)
  std::string source;         // "opening still interval 0.0–49.9 s" or "quietest 10 % of the 0.5-s windows"
  double quiet_sigma = 0;     // the quietest windows' level (the cross-check of the opening interval's)
};

struct MultiposFit {
  SensorErrors coeffs;                   // σ included; gauge-fixed accel entries have σ 0
  std::vector<StaticInterval> statics;
  std::vector<RotationUse> rotations;
  NoiseLevel gyro_noise, accel_noise;
  double threshold_factor = 0;           // margin·χ²_{n−1}(1−α)/(n−1) of the static test
  std::size_t distinct_directions = 0;   // gravity directions of the used poses, within 10° counted once
  std::vector<double> too_short_s;       // still intervals shorter than a pose (their lengths, s)
  std::size_t window_samples = 0;
  double accel_chi2_dof = 0, gyro_chi2_dof = 0;
  double gyro_chi2_dof_class = 0;         // the rotations under white noise and the class's bias wander
  int accel_dof = 0, gyro_dof = 0;
  double g_spread_raw = 0, g_spread = 0;  // RMS of ‖f̄‖ − g over the used poses, before/after
  double g_loo_rms = 0;                   // the same, each pose left out of the fit that judges it
  double rotation_rms_rad = 0;            // RMS of the gravity-direction error over used rotations
  int accel_iterations = 0, gyro_iterations = 0;
  std::vector<std::string> notes;         // what a reader should know (noise differs, Earth rate …)
};

// A recording that cannot determine the coefficients: what is missing and which poses to add.
struct MultiposRefusal : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Static detection alone (step 1), for reports and tests.
std::vector<StaticInterval> detect_statics(const MultiposInput& in, const MultiposOptions& opt,
                                           NoiseLevel* gyro_noise = nullptr, NoiseLevel* accel_noise = nullptr,
                                           double* threshold_factor = nullptr, std::size_t* window = nullptr,
                                           std::vector<double>* too_short_s = nullptr);

// The whole fit. Throws MultiposRefusal when the poses or rotations do not determine the
// coefficients, std::invalid_argument on malformed input.
MultiposFit fit_multipos(const MultiposInput& in, const MultiposOptions& opt);

// Gravity direction after a rotation: integrates the corrected rates over samples [i0, i1) and
// returns the body-frame unit vector a fixed up-direction `up_start` becomes (for held-out scoring).
Vec3 rotate_up(const MultiposInput& in, const TriadErrors& gyro, std::size_t i0, std::size_t i1, const Vec3& up_start);

}  // namespace calbench::multipos
