// Physics discovery on a multi-position recording (issue 37 item 4, docs/diagnosis.md
// "Multi-position recordings"): the static poses' residuals after `fit multipos` feed the same
// catalogue search (greedy_search.hpp) as the bench and the drive.
//
// What a static pose k observes, with the fitted coefficients C = I + M, b and the pose's unknown
// orientation (only gravity's magnitude g is known):
//   * accelerometers — one number, the gravity-magnitude residual
//       z_k = ‖C⁻¹(f̄_k − b)‖ − g ≈ v_kᵀ (Δb + ΔC·f_k + X_k θ),   v_k = C⁻ᵀ û_k,  f_k = g·û_k,
//     û_k the direction of the corrected mean force (the pose's tilt is the nuisance; the two
//     directions across gravity carry no information about the sensor). ΔC is lower triangular
//     (the frame's gauge, as in the fit);
//   * gyros — three numbers, the mean rate less the bias, z_k = w̄_k − b_g ≈ Δb_g + X_k θ: a still
//     unit's true rate is the Earth rate, whose vertical part Ω sin φ·û_k is removed when the site's
//     latitude is known and whose horizontal part (heading unknown) is noise of variance
//     (Ω cos φ)²(1 − û_a²)/2 per axis (Ω²/3 without a latitude).
// X_k θ are the catalogue terms' outputs at (ω = 0, f = f_k): what static poses excite —
// accelerometer scale nonlinearity (K2, K3, asymmetry), cross-coupling, the gyros' g and g²
// sensitivity; a term with no column on any pose is no candidate. Noise per pose: the white noise
// of the fit's static test (σ²/n, projected by v_k for the magnitude) plus the class's first-order
// Gauss–Markov drift between poses (correlated_drift is the noise-side candidate, as elsewhere).
// The held-out check fits even poses and predicts odd ones and vice versa. The rotations between
// poses are not used here (their gyro terms need the rate during the turn, which these residuals
// do not resolve): gyro scale and its nonlinearity stay with `fit multipos`.
#pragma once
#include <vector>

#include "calibration/diagnosis/diagnose.hpp"
#include "calibration/multipos/multipos_fit.hpp"

namespace calbench {

struct MultiposDiagnoseResult {
  // findings, unexplained, withdrawn, improved b/M and terms; before/after per axis (accel x, y, z
  // all carry the one gravity-magnitude dataset's statistics); residual per pose (gyro x..z, and
  // the magnitude residual under accel x).
  DiagnoseResult core;
  std::vector<int> poses;          // indices into fit.statics of the poses used
  std::vector<double> pose_t;      // their mid times, s
  double g_rms_before = 0, g_rms_after = 0;  // RMS of the magnitude residual, m/s²
  double gyro_rms_before[3] = {0, 0, 0}, gyro_rms_after[3] = {0, 0, 0};  // RMS of the static rate residual
  bool earth_vertical_removed = false;  // the site's latitude was known
};

// The base model's fit of the static poses under the full noise model (white noise, the class's
// drift between poses, the Earth rate): χ²/dof of the gravity-magnitude residuals (N − 9 dof) and
// of each gyro's static rate (N − 1). fit_multipos' own χ²/dof weighs white noise only, so a unit
// whose bias wanders as its data sheet allows shows several there; these are ≈ 1 for such a unit.
// What `fit multipos` records for the approval ("accel_chi2_dof_class").
struct MultiposNoiseCheck {
  double accel_chi2_dof = 0;
  int accel_dof = 0;
  double gyro_chi2_dof[3] = {0, 0, 0};
  int gyro_dof = 0;
};
MultiposNoiseCheck multipos_noise_check(const multipos::MultiposInput& in, const multipos::MultiposFit& fit,
                                        const SensorErrors& current, const NoiseSpec& noise);

// `fit`: fit_multipos on `in` (its statics and noise levels); `current`: the coefficients tested
// (fit.coeffs, or a given set); opt.noise: the class's drift prior. std::runtime_error when fewer
// than 9 poses are used.
MultiposDiagnoseResult diagnose_multipos(const multipos::MultiposInput& in, const multipos::MultiposFit& fit,
                                         const SensorErrors& current, const DiagnoseOptions& opt);

}  // namespace calbench
