// Physics discovery on a drive recording (issue 7, docs/diagnosis.md "Drives"): the MEMS output
// predicted from the reference trajectory (calibration/diagnosis/drive_data.hpp) is compared with
// what the MEMS measured, per ~1 s block; the residual is located (per axis, per motion class,
// correlation with the conditions of the drive), named from the catalogue by evidence and fitted.
//
// Statistical model per sensor axis a (gyro x..accel z), z = measured − (I+M)·predicted − b − carried:
//   z = Δb_a + [ΔM_a·predicted | mounting δ] + Σ_terms regressor·θ + drift + short-range noise
// * Δb: the bias of a drive is re-estimated always (turn-on repeatability), and it drifts: the
//   data-sheet first-order Gauss–Markov drift is part of the noise covariance (as on the bench).
// * Without given coefficients M is fitted too (the drive then *is* the "fit first"); with given
//   coefficients M stays fixed and only the mounting rotation δ (3 angles, MEMS axes, shared by
//   both triads) is estimated with the bias: the mounting is installation, not sensor. δ enters
//   linearised, so the base model's δ is first applied exactly (the prediction re-rotated, remount
//   in drive_data.hpp) until it is negligible: a fixed M cannot absorb the 1 − cos θ of a mounting
//   ~1° off the nominal one. Whether the scale itself differs from the given M_ii is then a
//   catalogue candidate (scale_factor), found by evidence like the others and folded into M.
// * Short-range noise: IMU white noise plus the reference's own noise, which enters through the
//   differences of its attitudes and velocities at the ends of each interval (adjacent blocks
//   anti-correlated). Its autocovariance up to 3 intervals is estimated from the data (high-pass
//   residuals at the reference interval), floored by the IMU's sample-to-sample white noise.
// Candidates are added greedily by Δχ² with a BIC penalty (k·ln N) and a held-out check (fit on
// even 20 s windows, predict odd ones and vice versa); correlated_drift is a noise-side candidate
// (detected on a grid of σ ×2…×32, τ 60/300/1200 s, then σ, τ by the restricted likelihood), as
// on the bench.
#pragma once
#include <string>
#include <vector>

#include "calibration/diagnosis/diagnose.hpp"
#include "calibration/diagnosis/drive_data.hpp"

namespace calbench {

struct DriveDiagnoseOptions {
  NoiseSpec noise = adis16488a_noise();  // data-sheet drift prior
  bool fixed_scale = false;              // coefficients given: M fixed, mounting δ estimated
  double min_delta_chi2 = 40;
  // Another candidate that, in a finding's place, fits within this Δχ² (and itself explains
  // min_delta_chi2) is reported as not told apart from it (DiagAlternative).
  double ambiguity_chi2 = 10;
  double ambiguity_correlation = 0.99;  // as DiagnoseOptions::ambiguity_correlation
  double penalty_per_param = 0;
  int max_findings = 6;
};

// Mean residual per motion class and axis (before/after), in units of its own σ (z-score).
struct DriveSegmentStat {
  std::string motion;
  int blocks = 0;
  double seconds = 0;
  double mean_before[6] = {0, 0, 0, 0, 0, 0}, mean_after[6] = {0, 0, 0, 0, 0, 0};
  double z_before[6] = {0, 0, 0, 0, 0, 0}, z_after[6] = {0, 0, 0, 0, 0, 0};
};

struct DriveDiagnoseResult {
  // findings, unexplained (worst_steps = worst 20 s windows), per-axis stats before/after,
  // correlations_before, improved b/M and terms, drift model, per-parent residuals.
  DiagnoseResult core;
  std::vector<ConditionCorrelation> correlations_after[6];
  std::vector<DriveSegmentStat> segments;
  Vec3 mounting_delta = Vec3::Zero(), mounting_sigma = Vec3::Zero();  // MEMS axes, rad (fixed_scale)
  double block_noise_sigma[6] = {0, 0, 0, 0, 0, 0};  // short-range noise of a ~1 s block (SI)
  double gamma[6][4] = {};                           // its sub-level autocovariance, lags 0..3
  double white_scale[6] = {1, 1, 1, 1, 1, 1};        // IMU white part scaled down (vibration), see .cpp
  std::vector<double> parent_t;                      // block times (for plots)
  // Per finding: noise level of its systematic RMS figure (binned by the term's contribution);
  // rms_after below it cannot be told from zero.
  std::vector<double> rms_floor;
  // Per finding: its RMS figures are of three-block means (the reference's telescoping error
  // averaged down), not of blocks.
  std::vector<char> rms_lowpass;
  std::vector<int> shown_on;  // per finding: axis (gyro x..accel z) its RMS figures are given for
  // Issue 36, the remainder's condition test on each axis with no finding and not unexplained by its
  // χ² (tested = false otherwise): the motion condition whose block values best explain the final
  // residual by GLS under the noise model, its Δχ² (χ²₁) and Pearson r. Δχ² ≥ kConditionTestLevel
  // makes the axis unexplained; below it the figure says how far the axis was from that.
  struct ConditionTest {
    bool tested = false;
    std::string condition;
    double dchi2 = 0, r = 0;
  };
  ConditionTest condition_test[6];
  // 19.1: the χ²₁ quantile of a family-wise false-alarm rate of 10⁻³ per recording over its
  // 6 axes × 13 conditions (α = 1.3·10⁻⁵ each).
  static constexpr double kConditionTestLevel = 19.1;
};

// `current`: coefficients to test (b, M) and the extra terms they already carry.
DriveDiagnoseResult diagnose_drive(const DriveDiagData& data, const SensorErrors& current, const EffectTerms& carried,
                                   const DriveDiagnoseOptions& opt);

// Conditions of a drive block for correlations: "speed", "w_x".."w_z", "f_x".."f_z" (MEMS axes),
// "|w|", "|f|", "ang_accel", "turn_rate", "along_accel", "time", "temperature".
std::vector<std::string> drive_condition_names(bool with_temperature);
double drive_condition_value(const DriveDiagData& d, int parent, const std::string& name);

}  // namespace calbench
