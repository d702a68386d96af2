// Continuous-time error dynamics of the in-motion filter, δẋ = F·δx + G·ξ (paper eq 11), with each
// estimated block's Jacobian in its own function. The sensor model is the spec's
//   y = (I + M)·true + b + d + noise   (d: in-run drift, shaping-filter state)
// and the navigation uses the corrected ŵ = A·(y − b̂ − d̂), A = (I + M̂)⁻¹, so that
//   δω_ib^b = ŵ − ω = −A·(δb + δd + δM·ω),   likewise δf^b for the accelerometer.
//
// Because F depends on the IMU signals, which arrive at up to 2460 Hz, the sensor-dependent
// blocks are integrated sample by sample into an accumulator (cheap: 3×3 and 3×9 sums) and the
// covariance is propagated only every few tens of milliseconds with Φ = I + F̄T + (F̄T)²/2, where
// F̄ is the mean of F over the interval T.
#pragma once
#include "calibration/inmotion/state_layout.hpp"
#include "calibration/ins/nav_math.hpp"

namespace calbench::inmotion {

// ∂(δM·x)/∂vec(δM) for row-major vec: a 3×9 matrix with xᵀ in row i at columns 3i..3i+2.
Eigen::Matrix<double, 3, 9> m_jacobian(const Vec3& x);

// Sums over IMU samples of the sensor-dependent F blocks, times dt.
struct FAccumulator {
  double T = 0;
  Mat3 att_bg = Mat3::Zero();                                 // ∫ C_nb·A_g dt        (φ ← δb_g, δd_g)
  Eigen::Matrix<double, 3, 9> att_mg = Eigen::Matrix<double, 3, 9>::Zero();  // ∫ C_nb A_g W(ω) dt
  Mat3 vel_ba = Mat3::Zero();                                 // ∫ C_nb·A_a dt        (δv ← δb_a, δd_a)
  Eigen::Matrix<double, 3, 9> vel_ma = Eigen::Matrix<double, 3, 9>::Zero();  // ∫ C_nb A_a W(f) dt
  Vec3 f_n = Vec3::Zero();                                    // ∫ f^n dt
  void add(const Mat3& C_nb, const Mat3& A_g, const Mat3& A_a, const Vec3& w_b, const Vec3& f_b, double dt);
  void clear() { *this = FAccumulator{}; }
};

// Navigation block (position, velocity, attitude) at the current nominal state.
struct NavBlockInputs {
  double lat = 0, h = 0;
  Vec3 v_ned = Vec3::Zero();
  Vec3 f_n = Vec3::Zero();  // mean specific force over the interval
  ins::LocalEarth earth;
};
void nav_block(const NavBlockInputs& in, StateMat& F);
// Gyro: drift, in-run drift and M into the attitude rows (mean over the interval).
void gyro_blocks(const FAccumulator& acc, StateMat& F);
// Accelerometer: bias, in-run drift and M into the velocity rows.
void accel_blocks(const FAccumulator& acc, StateMat& F);
// Shaping filters of the in-run drifts (eq 22): δḋ = −α·δd + σ√(2α)·ξ.
void drift_blocks(const Vec3& alpha_g, const Vec3& alpha_a, StateMat& F);

}  // namespace calbench::inmotion
