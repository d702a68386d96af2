// `calbench fit drive`: the in-motion calibration of a drive recording (calibration/inmotion),
// producing RESULT.json (contract in docs/in-motion.md) and optionally the estimate series.
#pragma once
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

namespace calbench {

struct FitDriveArgs {
  std::string dir, coeffs, out, obs = "pos,vel,att", series, window;
  std::string drift_models;   // MODELS.json (identify --out) or a coefficients.json with drift_models
  bool smooth = false;
  double obs_rate_hz = 10, cov_dt = 0.1;
  double prior_gyro_bias_dps = 0, prior_accel_bias_mg = 0;  // > 0: override the bias priors
  double sigma_pos = 0, sigma_vel = 0, sigma_att_deg = 0;  // 0: from reference.csv or defaults
  bool qc = true;             // out-of-sample ΔS after the window, when data remain
  double qc_horizon_s = 600;
};

// Runs the fit, writes args.out (and args.series), returns RESULT.json.
nlohmann::json fit_drive(const FitDriveArgs& a);

}  // namespace calbench
