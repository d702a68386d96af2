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
#include "calibration/inmotion/state_blocks.hpp"
#include "calibration/inmotion/state_layout.hpp"
#include "calibration/ins/nav_math.hpp"

namespace calbench::inmotion {

// ∂(δM·x)/∂vec(δM) for row-major vec: a 3×9 matrix with xᵀ in row i at columns 3i..3i+2.
Eigen::Matrix<double, 3, 9> m_jacobian(const Vec3& x);

// The sensors of the sensor model: index of a sensor's entries in SensorCorrection and ImuSample.
enum Sensor { kGyro = 0, kAccel = 1 };

// The correction of the raw increments, y → ŵ (InMotionFilter::imu()), built by the sensor-error
// blocks from their nominal values (BlockSpec::compensate, in layout order; sensor_correction() in
// state_blocks.hpp): per sensor
//   corrected = A·(raw − offset·dt),   offset = the sum of the additive blocks' values (b̂ + d̂),
//   A = (I + M̂)⁻¹ (identity without an M block).
// The offset starts at −0, the neutral element of the sum (−0 + x = x for every x, also ±0), so the
// blocks' values are summed exactly as b̂ + d̂.
struct SensorCorrection {
  Vec3 offset[2] = {Vec3::Constant(-0.0), Vec3::Constant(-0.0)};
  Mat3 A[2] = {Mat3::Identity(), Mat3::Identity()};
  Vec3 apply(int sensor, const Vec3& raw, double dt) const { return A[sensor] * (raw - offset[sensor] * dt); }
};

// One IMU interval as the transition sees it: the attitude at its start C_nb, the corrected rate
// w_b and specific force f_b (body), dt, and per sensor CA = C_nb·A·dt, the map of that sensor's
// error (δb, δd, δM·x) into the navigation equations over the interval.
struct ImuSample {
  Mat3 C_nb;
  Vec3 x[2];  // corrected output per sensor: w_b (gyro), f_b (accelerometer)
  double dt;
  Mat3 CA[2];
};

// Sums over IMU samples of the sensor-dependent F entries, times dt: the blocks' own
// (BlockSpec::accumulate, each into its columns of `sum`, three rows: the navigation rows it feeds),
// and the navigation block's input, the specific force in NED.
struct FAccumulator {
  double T = 0;
  Vec3 f_n = Vec3::Zero();                 // ∫ f^n dt
  // Sampling-time noise (identification/sample_timing.hpp), when track_jumps: Σ over the interval's
  // steps of (C·Δm)(C·Δm)ᵀ, Δm the change of the step's mean rate from the previous step's, for the
  // gyro (jump_w) and the accelerometer (jump_f), NED. The last step's means outlive clear().
  bool track_jumps = false;
  Mat3 jump_w = Mat3::Zero(), jump_f = Mat3::Zero();
  Vec3 m_w = Vec3::Zero(), m_f = Vec3::Zero();
  bool have_m = false;
  Eigen::Matrix<double, 3, Eigen::Dynamic> sum;  // 3 × the layout's size (zero columns: a block without accumulate)
  // Sized (and zeroed) for a layout of n states.
  void resize(int n);
  // One IMU interval: every active block's accumulate hook, in layout order.
  void add(const StateLayout& L, const Mat3& C_nb, const SensorCorrection& c, const Vec3& w_b, const Vec3& f_b, double dt);
  void clear();
};

// Navigation block (position, velocity, attitude) at the current nominal state.
struct NavBlockInputs {
  double lat = 0, h = 0;
  Vec3 v_ned = Vec3::Zero();
  Vec3 f_n = Vec3::Zero();  // mean specific force over the interval
  ins::LocalEarth earth;
};
// Each writes its rows of F at the offsets the layout gave its blocks.
using FRef = Eigen::Ref<Eigen::MatrixXd>;
void nav_block(const NavBlockInputs& in, int pos, int vel, int att, FRef F);
// A sensor-error block's columns of F (called by its declaration, state_blocks.cpp), the mean over
// the interval of what the block accumulated:
//   φ̇ ∋ −C δω = +C A (δb + δd + δM ω)      (gyro: attitude rows)
//   δv̇ ∋ C δf = −C A (δb + δd + δM f)       (accelerometer: velocity rows)
void sensor_jacobian(const FAccumulator& acc, int sensor, int rows, int col, int size, FRef F);
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
