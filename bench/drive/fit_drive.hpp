// `calbench fit drive`: the in-motion calibration of a drive recording (calibration/inmotion),
// producing RESULT.json (contract in docs/in-motion.md) and optionally the estimate series.
#pragma once
#include <array>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "bench/drive/drive_stream.hpp"
#include "bench/drive/outage_qc.hpp"
#include "bench/io/coefficients_json.hpp"
#include "calibration/inmotion/inmotion_filter.hpp"
#include "common/drive_result.hpp"

namespace calbench {

struct FitDriveArgs {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::string dir, coeffs, out, obs = "pos,vel,att", series, window;
  // The aiding source: "reference" (reference.csv), "gnss" (gnss.csv: position, velocity where
  // given; no attitude), or "" = reference.csv when the recording has one, else gnss.csv.
  std::string aiding;
  bool obs_given = true;      // false: --obs not given (GNSS aiding then uses pos,vel)
  std::string drift_models;   // MODELS.json (identify --out) or a coefficients.json with drift_models
  bool smooth = false;
  // The device class (bench/imu_classes, docs/in-motion.md "Device classes"): a class file, or the
  // name or alias of a built-in class; "" = from meta.json device.model (unknown: bad input).
  std::string device_class;
  // The approval preview's thresholds file (as `db approve --thresholds`); "" = the built-in
  // defaults of the recording's device class (meta.json device.model).
  std::string thresholds;
  // Measure the white noise on the recording's standstills and use it where it differs from the
  // class by more than 2x (docs/in-motion.md, "White noise measured on standstills").
  bool measure_noise = true;
  // > 0: the forward-pass series also gets a row at the first IMU sample every series_every_s
  // seconds (the navigation solution between fixes, e.g. through a GNSS outage); 0: rows at the
  // epochs the filter used only.
  double series_every_s = 0;
  double obs_rate_hz = 10, cov_dt = 0.1;
  // Vehicle constraints (--obs …,nhc,zupt): at most constraint_rate_hz updates a second; their σ
  // (0: InMotionConfig's defaults, 0.1 m/s NHC, 0.01 m/s ZUPT).
  double constraint_rate_hz = 10, nhc_sigma = 0, zupt_sigma = 0;
  std::string covariance = "structured";  // structured, joseph or dense (InMotionConfig::covariance)
  // Adaptive process noise (calibration/inmotion/adaptive_noise.hpp): "on", "off", or "auto" = on
  // with GNSS aiding, off against a reference INS (whose inconsistencies are findings for diagnose).
  std::string adaptive = "auto";
  // The logger's sample timing (identification/sample_timing.hpp) and the GNSS velocity's latency
  // (identification/gnss_velocity_latency.hpp): "auto" = measured from the recording, "off", or ms.
  std::string sample_time = "auto", gnss_vel_latency = "auto";
  // The triads' common rotation (calibration/inmotion/gauge.hpp): "hold" (default) or "ekf".
  std::string unobservable_rotation = "hold";
  double prior_gyro_bias_dps = 0, prior_accel_bias_mg = 0;  // > 0: override the bias priors
  // Antenna blocks (--estimate lever,time; docs/in-motion.md "Lever arm and time offset"): "" none,
  // else a comma list of lever (the lever arm, prior σ lever_arm_sigma m per axis) and time (the
  // IMU–GNSS time offset, prior σ time_offset_sigma s).
  std::string estimate;
  double lever_arm_sigma = 0.1, time_offset_sigma = 0.02;
  // Stability allowances (how far a parameter may move between the input set's calibration and
  // the drive, 1σ; calibration/inmotion/priors.hpp); NaN: the device class's default.
  struct Allowances {
    double gyro_bias_dph = kNaN, accel_bias_mg = kNaN, gyro_scale_ppm = kNaN, gyro_skew_ppm = kNaN,
           accel_scale_ppm = kNaN, accel_skew_ppm = kNaN, mount_deg = kNaN;
  } allowance;
  double sigma_pos = 0, sigma_vel = 0, sigma_att_deg = 0;  // 0: from reference.csv or defaults
  bool qc = true;             // out-of-sample ΔS after the window, when data remain
  double qc_horizon_s = 600;
  // In memory instead of --coeffs (a.coeffs then only names it): the set and its extra keys.
  std::optional<CoefficientSet> coeffs_set;
  // A mounting carried by the input (an earlier in-motion RESULT.json): roll, pitch, yaw and 1σ, deg.
  std::optional<std::pair<Vec3, Vec3>> coeffs_mounting_deg;
  std::string coeffs_recording_sha256;  // of the drive a RESULT.json input was fitted on
  // Called after every reference epoch the filter took, per observation type (0 pos, 1 vel, 2 att).
  std::function<void(int type, const inmotion::InnovationRecord&)> on_innovation;
  // Outage QC of a GNSS-aided fit (docs/in-motion.md, "Outage QC"): RESULT.json qc.outages.
  OutageOptions outages;
  // Called after every reference epoch the filter handled (took: used), e.g. to record its state.
  std::function<void(const inmotion::InMotionFilter&, const inmotion::RefObs&, bool took)> on_epoch;
  bool write_out = true;      // false: return RESULT.json without writing a.out
  // A multi-unit drive: the reference parsed once for every unit (fit and QC read no reference.csv).
  std::shared_ptr<const SharedReference> shared_reference;
};

// The --allowance-* options, one row each: the option, its field in FitDriveArgs::Allowances (in
// the display unit), the StabilityAllowance member it overrides (SI), SI per display unit, the key
// of RESULT.json priors.allowance, and what it is. The CLI, the fit and RESULT.json read this table.
struct AllowanceOption {
  const char* option;
  double FitDriveArgs::Allowances::*given;
  double inmotion::StabilityAllowance::*field;
  double unit;
  const char* json_key;
  const char* what;
};
const std::array<AllowanceOption, 7>& allowance_options();

// Runs the fit, writes args.out (and args.series), returns RESULT.json (common/drive_result.hpp, its codec). Catalogue keys of the
// coefficients (docs/diagnosis.md) are compensated on the IMU samples before the filter
// (calibration/effects/effect_compensation.hpp); RESULT.json "effects" says which were applied and
// which ignored, and its "coefficients" carry them. Without such keys nothing changes.
DriveResult fit_drive(const FitDriveArgs& a);

}  // namespace calbench
