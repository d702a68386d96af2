// The in-motion filter's unobservable rotation, and its covariance kept honest (docs/in-motion.md,
// "The triads' common rotation").
//
// What in-motion data cannot see. The sensor model measured = (I + M)·true + b refers both triads
// to the MEMS case frame m. Call m' the case frame turned by a small rotation ε (v_m' = (I − ε×)·v_m):
// the same unit, motion and observations are described exactly as well by
//   M'_g = (I + M_g)·(I + ε×) − I,  M'_a = (I + M_a)·(I + ε×) − I    (a common rotation of both triads)
//   C_nm' = C_nm·(I + ε×)                                             (the MEMS attitude)
//   C_m'b = C_mb·(I + ε×)                                             (the mounting)
// with biases, drifts, lever arms (reference body axes) and the navigation unchanged. Position,
// velocity, the reference body's attitude, the NHC, zero velocity and zero rate, the course and the
// antenna blocks all read the reference body frame or the sensor's output, so none of them tells ε;
// only the priors do (the bench's M, the mounting's, the levelled tilt's). In the error state
// ("estimate minus truth") the direction is, per component ε_k (column k of N, layout size × 3),
//   δM_g = (I + M̂_g)·(e_k×),  δM_a = (I + M̂_a)·(e_k×),  φ = −Ĉ_nm·e_k,  δμ = −Ĉ_mb·e_k,  0 elsewhere.
// Every observation's H·N is 0 at the point it is linearised at (asserted for eqs 13–15, the NHC,
// zero velocity and zero rate in tests/unit/calibration/inmotion_jacobian_test.cpp; the course
// update's row by hand), and the propagation does not add information along N (measured).
//
// Where the EKF still gains it: N moves with the estimate (its attitude part −Ĉ_nm·e_k turns with
// every heading correction), while the feedback leaves P as it was, so information P held about
// other directions is read as information about ε (the mechanism of the EKF inconsistency in
// SLAM and visual-inertial odometry: Huang, Mourikis & Roumeliotis, "Observability-based rules for
// designing consistent EKF SLAM estimators", IJRR 29(5), 2010). Measured on a consumer-class GNSS-only
// drive: the conditional σ of ε fell from 0.52° to 0.18° within a minute of motion, and the
// coefficients of M's antisymmetric part missed the truth by up to 8σ.
//
// The remedy, in the spirit of their observability-constrained EKF: at each feedback (and when the
// levelling or the restart at the first heading set the attitude) the conditional covariance of ε
// moves with its direction,
//   P ← P − N⁻·S·N⁻ᵀ + N⁺·S·N⁺ᵀ,  S = (N⁻ᵀ·P⁻¹·N⁻)⁻¹,
// N⁻ and N⁺ the direction before and after the feedback. P − N⁻·S·N⁻ᵀ is P conditioned on ε (positive
// semidefinite), so P stays a covariance, and N⁺ᵀP⁻¹N⁺ = N⁻ᵀP⁻¹N⁻: the information along the
// unobservable direction is what it was, and in the end what the priors gave.
#pragma once
#include <Eigen/Dense>

#include "calibration/inmotion/state_blocks.hpp"

namespace calbench::inmotion {

struct Nominal;

// N at the nominal state n (the MEMS attitude read from n.nav), or an empty matrix when the layout
// lacks one of the attitude, gyro M, accelerometer M and mounting blocks (without the mounting the
// reference body frame pins the case frame through the lever arm and the attitude observations).
Eigen::MatrixXd unobservable_rotation(const StateLayout& s, const Nominal& n);

// P ← P − N⁻·S·N⁻ᵀ + N⁺·S·N⁺ᵀ (above); P symmetric on return. Nothing when N⁻ is empty or P does not
// give a finite, positive definite S. Returns the conditional σ of ε (3 components, rad) it kept,
// or a zero vector when it did nothing.
Eigen::Vector3d carry_unobservable_rotation(Eigen::MatrixXd& P, const Eigen::MatrixXd& N_before, const Eigen::MatrixXd& N_after);

// The conditional covariance S = (NᵀP⁻¹N)⁻¹ of ε in P, over the states of nonzero variance (an exact
// zero on P's diagonal is a zero row and column); false (S untouched) when N is empty, reaches a
// state of zero variance, or P there or NᵀP⁻¹N is not positive definite.
bool unobservable_rotation_covariance(const Eigen::MatrixXd& P, const Eigen::MatrixXd& N, Eigen::Matrix3d& S);

// After a change of P that is not a Bayesian update (the gate's forced widening of the navigation
// block, D·P·D, which would otherwise make information along N out of nothing): P ← P − N·S(P)·Nᵀ +
// N·S·Nᵀ, the conditional covariance of ε set back to S (the one before the change). Nothing when
// S(P) cannot be formed.
void restore_unobservable_rotation(Eigen::MatrixXd& P, const Eigen::MatrixXd& N, const Eigen::Matrix3d& S);

// The conditional σ of ε (rad, per component) in P: the square roots of the diagonal of
// (NᵀP⁻¹N)⁻¹; a zero vector when N is empty.
Eigen::Vector3d unobservable_rotation_sigma(const Eigen::MatrixXd& P, const Eigen::MatrixXd& N);

}  // namespace calbench::inmotion
