// Verdicts that look at the fit (issue 35 item 5): the approval's checks of the fit's quality,
// beside the coefficient and QC thresholds of db/approval.hpp (which holds them in its Thresholds
// and runs them in check_verdict(), the one verdict of `db approve`, the device report and the
// preview that `fit drive` ends with).
//  - multipos (a bench-source set fitted without a rate table, `fit multipos`): the accelerometer's
//    and the gyros' χ²/dof of that fit, by the same max_chi2_dof limits;
//  - bench: the whitened χ²/dof of each triad axis, and per kind of plan step (static positions,
//    rate steps) the largest systematic residual (the mean residual of a step), from the set's
//    coefficients.json "fit_quality" (common/fit_quality.hpp, written by `fit bench`);
//  - in-motion: the time-average NIS of each observation (position, velocity, attitude, nhc, zupt,
//    zero_rate) per degree of freedom, inside a band, from the run's "consistency";
//  - combined: the set against its parent, coefficient by coefficient: a move larger than
//    k·√(σ_parent² + allowance²) (allowance: the device class's stability allowance), and a σ that
//    grew beyond a factor of the parent's.
// Thresholds file keys (docs/database.md, "Approval thresholds"):
//   "bench":    {"max_chi2_dof": {"gyro": 3, "accel": 3},
//                "max_systematic_residual": {"static": {"gyro_dph": 60, "accel_mg": 1},
//                                            "rate": {"gyro_dph": 60, "accel_mg": 1}},
//                "require_fit_quality": false}
//   "inmotion": {"mean_nis_per_dof": {"default": [0.1, 2], "attitude": [0.1, 3], ...}}
//   "combined": {"max_move_sigmas": 1, "max_sigma_growth": 3}
#pragma once
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "calibration/inmotion/priors.hpp"
#include "common/drive_result.hpp"
#include "common/fit_quality.hpp"
#include "db/store.hpp"

namespace calbench::db {

struct FitQualityLimits {
  // bench, per triad: χ²/dof of every axis, and per step kind the largest |mean residual| (SI)
  double max_chi2_dof_gyro = 3, max_chi2_dof_accel = 3;
  std::map<std::string, double> max_residual_gyro, max_residual_accel;  // by kStepStatic / kStepRate
  bool require_fit_quality = false;  // a bench set without "fit_quality" is refused when true
  // in-motion: mean NIS / expected (dof), per observation; "default" for the others
  std::map<std::string, std::pair<double, double>> nis_band;
  // combined against its parent
  double max_move_sigmas = 1;   // k of k·√(σ_parent² + allowance²)
  double max_sigma_growth = 3;  // σ_set ≤ factor · σ_parent
  // The device classes' stability allowances by normalized model name (calibration/imu_class.hpp),
  // filled from the classes by the caller (bench/approval_thresholds.hpp); a model without one is
  // compared with an allowance of 0, and the reason says so.
  std::map<std::string, inmotion::StabilityAllowance> allowances;
};
FitQualityLimits default_fit_quality_limits();

// A key of the thresholds file this part reads ("bench", "inmotion", "combined"): parsed into `q`
// (InputError naming the file and the key on anything malformed or unknown) and true; false for
// any other key.
bool parse_fit_quality_key(const std::string& key, const nlohmann::json& v, const std::string& file, FitQualityLimits& q);
std::vector<std::string> describe_fit_quality(const FitQualityLimits& q);

// What the checks look at, read from the store (fit_evidence) or given by `fit drive` (its result).
struct FitEvidence {
  std::optional<BenchFitQuality> bench;                      // the set's coefficients.json fit_quality
  std::optional<std::map<std::string, NisConsistency>> nis;  // the in-motion run's consistency
  std::optional<CoefficientSetRecord> parent;                // the set a combined set refines
  // A set fitted from a multipos recording (payload "multipos"): χ²/dof of the gravity-magnitude
  // residuals under the class's white noise and drift ("accel_chi2_dof_class") and of the rotations'
  // gravity-direction residuals ("gyro_chi2_dof"), judged by the bench limits max_chi2_dof.
  std::optional<std::pair<double, double>> multipos_chi2;    // accel, gyro
  // The in-motion run's adaptive noise scale at the end of its fit (RESULT.json adaptive_noise):
  // above inmotion::AdaptiveNoise::kFailScale the filter followed the fixes with the IMU's noise
  // scaled away, and the set is refused whatever its NIS (issue 53).
  std::optional<AdaptiveNoiseSummary> adaptive;
  std::vector<std::string> problems;                         // evidence that could not be read (refuses)
};
FitEvidence fit_evidence(Store& store, const CoefficientSetRecord& set);

// Why the fit's quality refuses `set` (empty when it does not), in display units.
std::vector<std::string> fit_quality_reasons(const CoefficientSetRecord& set, const FitEvidence& ev,
                                             const FitQualityLimits& q);

}  // namespace calbench::db
