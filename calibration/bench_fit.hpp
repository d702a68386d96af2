// Bench calibration (paper section II, eqs 1–5): gyro drift, skews and scale factors;
// accelerometer bias, skews and scale factors — by generalised least squares over the whole
// recording ("lsq", eq 5 generalised) or by the paper's sequential modification of the EKF
// ("ekf"), both on the same observation model and the same noise model:
//
//   z = measured − reference = b + M·reference + d(t) + e_step + v
//
// per triad and axis i:  z_i = b_i + Σ_j M_ij·ref_j + d_i + e_i + v_i   (H row of eq 4, generalised
// with the scale factor M_ii). d is the in-run drift (first-order Gauss–Markov, data-sheet σ and τ:
// prior knowledge of the device class, not of the unit), e is the bench's own error during a step
// (rate accuracy, axis wobble, position accuracy: constant within a step, independent between
// steps), v is white noise whose level is measured from the scatter inside each block.
// The reported σ of the bias is therefore the uncertainty of the *constant* (turn-on) part.
#pragma once
#include <string>
#include <vector>

#include "calibration/bench_blocks.hpp"
#include "calibration/bench_plan.hpp"
#include "common/noise_spec.hpp"

namespace calbench {

enum class BenchMethod { lsq, ekf };
enum class BenchModel { paper, full };

struct BenchFitOptions {
  BenchMethod method = BenchMethod::lsq;
  BenchModel model = BenchModel::full;
  NoiseSpec noise = adis16488a_noise();  // drift prior (data-sheet class)
  TableSpec table;                        // bench errors (from the plan, or defaults)
};

// Parameter layout per triad axis i: [b_i, M_i0, M_i1, M_i2].
inline constexpr int kAxisParams = 4;
inline constexpr int kParBias = 0;
inline constexpr int kParM0 = 1;

enum class TriadId { gyro = 0, accel = 1 };

struct Unobservable {
  std::string triad;   // "gyro" | "accel"
  std::string param;   // e.g. "M[2][0]" or "bias[1]"
  std::string reason;
};

struct StepResidual {
  int step = -1;
  bool rotating = false;        // |w| > 1 °/s
  int samples = 0;
  double duration_s = 0;
  double rate_norm = 0;          // |w| (rad/s)
  Vec3 f_mean = Vec3::Zero();
  Vec3 gyro_mean = Vec3::Zero(); // mean residual after the fit (rad/s)
  Vec3 gyro_rms = Vec3::Zero();  // RMS of block-mean residuals (rad/s)
  Vec3 accel_mean = Vec3::Zero();
  Vec3 accel_rms = Vec3::Zero();
};

struct BenchFitResult {
  SensorErrors estimate;                  // σ = +inf for coefficients not estimated
  std::vector<Unobservable> unobservable; // coefficients the data cannot determine (reported as 0, σ unknown)
  std::vector<std::string> not_estimated; // fixed at 0 by the model choice (--model paper)
  std::vector<StepResidual> steps;
  Vec3 gyro_white_density = Vec3::Zero();   // measured white-noise density (rad/s/√Hz)
  Vec3 accel_white_density = Vec3::Zero();  // (m/s²/√Hz)
  Vec3 gyro_chi2_dof = Vec3::Zero();        // whitened residual Σr²/dof per axis (≈1 when the model fits)
  Vec3 accel_chi2_dof = Vec3::Zero();
  int blocks = 0;
  double data_s = 0;
};

BenchFitResult fit_bench(const std::vector<BenchBlock>& blocks, const BenchFitOptions& opt);

// ---- internals shared by the two methods (bench_fit_common.cpp) ----
namespace bench_fit_detail {

struct AxisProblem {
  TriadId triad;
  int axis;
  std::array<bool, kAxisParams> estimated{};  // which of [b, M_i0, M_i1, M_i2] are free
  double white_var = 0;                       // per-sample white variance
  double drift_sigma = 0, drift_tau = 1;
};

// z and H row for block k.
double observation(const BenchBlock& b, TriadId triad, int axis);
Eigen::Matrix<double, 1, kAxisParams> design_row(const BenchBlock& b, TriadId triad);
// σ of the bench's own error for this block/axis (constant within a step).
double bench_error_sigma(const BenchBlock& b, TriadId triad, int axis, const TableSpec& table);
// Decide which parameters are free (model choice + observability) for every triad axis.
std::vector<AxisProblem> setup_problems(const std::vector<BenchBlock>& blocks, const BenchFitOptions& opt,
                                        BenchFitResult& result);

}  // namespace bench_fit_detail
}  // namespace calbench
