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
#include "calibration/identification/shaping_filter.hpp"
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
// Each writes its rows of F (any layout: the offsets of the blocks are fixed, the state may be longer).
using FRef = Eigen::Ref<Eigen::MatrixXd>;
void nav_block(const NavBlockInputs& in, FRef F);
// The sensor blocks' columns, each block's own (called by its declaration, state_blocks.cpp), as
// the mean over the interval of the accumulated sums:
//   φ̇ ∋ −C δω = +C A (δb + δd + δM ω)      (gyro bias and in-run drift at `col`, M at `col`)
//   δv̇ ∋ C δf = −C A (δb + δd + δM f)       (accelerometer likewise)
void gyro_bias_jacobian(const FAccumulator& acc, int col, FRef F);
void gyro_M_jacobian(const FAccumulator& acc, int col, FRef F);
void accel_bias_jacobian(const FAccumulator& acc, int col, FRef F);
void accel_M_jacobian(const FAccumulator& acc, int col, FRef F);
// Shaping filter of a first-order in-run drift (eq 22): δḋ = −α·δd + σ√(2α)·ξ, the block at off.
void drift_jacobian(const Vec3& alpha, int off, FRef F);
// Exponential-cosine shaping filter of one axis (eqs 35–36, drift_expcos.cpp): the 2×2 A of
// `f` on the states (aux, drift) = (x[0], x[1]); the drift seen by the navigation equations is
// x[1] (H = [0 1]), so its Jacobian into the attitude/velocity rows is the drift block's column,
// which the drift block fills. Only in the augmented layout.
void expcos_drift_block(const identification::ShapingFilter& f, int aux, int drift, FRef F);
// Its discrete process noise over a step (exact: Qd of shaping_filter.hpp discretise()) into Q.
void expcos_drift_noise(const identification::DiscreteShapingFilter& d, int aux, int drift, FRef Q);

}  // namespace calbench::inmotion
