// The physics catalogue of `calbench diagnose` (docs/diagnosis.md): error terms beyond the spec's
// measured = (I + M)·true + b. One struct holds the value of every term; the bench simulator
// injects them (truth side) and the diagnosis/predictors apply them (model side). All SI.
// Everything else about an effect (units, JSON, physics hooks, sentences, where its values sit in
// EffectTerms::values) is its spec in effect_registry.hpp.
//
// Sensor-side terms (added to the output of a triad, evaluated at the true input x = ω or f):
//   temperature_bias    b_T,i·(T − T0)                       gyro rad/s/K, accel m/s²/K
//   temperature_scale   s_T,i·(T − T0)·x_i                   1/K
//   temperature_rate    r_T,i·dT/dt  (thermal lag: gradient-driven bias during warm-up and ramps)
//                                                            gyro rad/s per K/s, accel m/s² per K/s
//   g_sensitivity       G·f   (gyro only, 3×3)               rad/s per m/s²
//   scale_nonlinearity  k_i·x_i·|x_i|                        1/(rad/s), 1/(m/s²)
//   scale_asymmetry     a_i·|x_i|  (scale M_ii + a_i for x_i > 0, M_ii − a_i for x_i < 0)
//   scale_factor        s_i·x_i: the scale differs from the coefficients' M_ii (changed since the
//                       calibration, or set at other rates); a drive with given coefficients
//                       finds it, IMPROVED.json folds it into M_ii                   dimensionless
//   lever_arm           accel: ω×(ω×r) + ω̇×r                 r in m, IMU axes
// Reference-side terms (the bench is not what its nominal model says):
//   time_offset         IMU sample stamped t saw the truth at t − τ:  Δx ≈ −τ·ẋ          s
//   misalignment        table base tilted by ψ = (ψN, ψE, 0) (rad, level frame):
//                       Δf = −C_bLᵀ (ψ × C_bL f)
//   table_wobble        inner-axis angle error δ(θ) = a·sin θ + c·cos θ (rad):
//                       true angle θ + δ(θ), true rate θ̇·(1 + δ'(θ))
//   correlated_drift    bias drift beyond the data-sheet prior (first-order Gauss–Markov σ, τ)
#pragma once
#include <array>
#include <cmath>
#include <limits>

#include "common/sensor_model.hpp"

namespace calbench {

// The values of every effect, laid out by the registry (effect_registry.hpp: effect_param and the
// typed views effect_triad, effect_vector, effect_matrix); no effect has a member of its own, so
// adding one does not touch this struct (the static check in effect_registry.cpp keeps `values`
// large enough).
struct EffectTerms {
  double t0_c = 25.0;  // reference temperature of the temperature terms
  std::array<double, 192> values{};

  bool any() const;
  bool any_sensor_side() const;
};

// Conditions of one instant (or the mean over a short block) on the bench.
struct EffectContext {
  Vec3 w = Vec3::Zero(), f = Vec3::Zero();        // true (or reference) rate and specific force
  Vec3 dw = Vec3::Zero(), df = Vec3::Zero();      // their time derivatives
  double temp_c = 25.0;
  double dtemp_k_s = 0.0;  // dT/dt (K/s)
  // The bench reference (reference-side terms only): the inner-axis angle (rad; NaN unknown), its
  // rate (rad/s), and in a static position the inner axis in IMU axes (zero: unknown).
  double angle = std::numeric_limits<double>::quiet_NaN();
  double angle_rate = 0.0;
  Vec3 inner_axis = Vec3::Zero();
};

// Sensor-side extra output (added to (I+M)·x + b): gyro and accel, summed over the registry's
// effects (effect_registry.cpp).
void sensor_side_terms(const EffectTerms& e, const EffectContext& c, Vec3& dgyro, Vec3& daccel);

// Lever-arm specific force at the IMU relative to the rotation centre: ω×(ω×r) + ω̇×r.
Vec3 lever_arm_force(const Vec3& r, const Vec3& w, const Vec3& dw);

// Encoder/wobble angle error δ(θ) and its derivative dδ/dθ.
inline double wobble_angle(const Eigen::Vector2d& ac, double theta) {
  return ac(0) * std::sin(theta) + ac(1) * std::cos(theta);
}
inline double wobble_slope(const Eigen::Vector2d& ac, double theta) {
  return ac(0) * std::cos(theta) - ac(1) * std::sin(theta);
}

// Specific force error of a tilted table base: Δf = −C_bLᵀ (ψ × C_bL f), ψ = (ψN, ψE, 0).
Vec3 table_tilt_force(const Eigen::Vector2d& psi, const Mat3& C_b_l, const Vec3& f_b);

}  // namespace calbench
