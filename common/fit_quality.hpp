// How well a bench fit fits its data (issue 35 item 5): the whitened χ²/dof of every triad axis and
// the mean residual of every plan step (a systematic residual: what the model leaves in a step).
// Computed by the fit (calibration/qc/bench_fit_quality.hpp), written into coefficients.json as
// "fit_quality" by the coefficients codec, stored with the set, checked by the approval
// (db/approval_quality.hpp) and plotted by the device report. SI units (rad/s, m/s²).
#pragma once
#include <string>
#include <vector>

#include "common/sensor_model.hpp"

namespace calbench {

// The kinds of plan step, as the fit names them: "static" (a static position) and "rate" (a rate step).
inline constexpr const char* kStepStatic = "static";
inline constexpr const char* kStepRate = "rate";

struct StepMeanResidual {
  int step = -1;
  std::string kind;             // kStepStatic | kStepRate
  Vec3 gyro = Vec3::Zero();     // mean residual after the fit (rad/s)
  Vec3 accel = Vec3::Zero();    // (m/s²)
};

struct BenchFitQuality {
  Vec3 gyro_chi2_dof = Vec3::Zero();   // whitened Σr²/dof per axis (≈1 when the model fits)
  Vec3 accel_chi2_dof = Vec3::Zero();
  std::vector<StepMeanResidual> steps;
};

// The largest systematic residual of one triad over the steps of one kind.
struct LargestResidual {
  std::string kind;
  int steps = 0;       // steps of this kind
  double value = 0;    // largest |mean residual| (rad/s or m/s²)
  int step = -1;       // where it is
  int axis = 0;        // 0..2 = x, y, z
};
// Per kind (static, rate: those present, in that order), for "gyro" or "accel".
std::vector<LargestResidual> largest_residuals(const BenchFitQuality& q, bool gyro);

}  // namespace calbench
