// Shaping filters of the identified sensor-drift models (paper section IV): the linear systems
//   ẋ(t) = A x(t) + G ξ(t),   drift(t) = H x(t),   E[ξ(t) ξ(s)] = δ(t − s)  (unit-intensity white noise)
// whose output has the identified correlation function, and their exact discretisation for a step
// dt, x_{k+1} = Φ x_k + w_k, E[w wᵀ] = Qd. The in-motion EKF carries x as augmented states:
//
//   - exponential (eq 17 → eq 22/23): one state, the drift itself.
//       A = −α,  G = σ√(2α),  H = 1,  Φ = e^{−α dt},  Qd = σ²(1 − e^{−2α dt}).
//   - exponential-cosine (eq 32 → eqs 34–36, the paper's vector-matrix form): two states
//       x = [Δμ, Δμ̃]ᵀ,  A = [[−2α, −b²], [1, 0]],  G = [(b − 2α)σ√(2α), σ√(2α)]ᵀ,  b² = α² + β².
//     NOTE: of these two states it is x[1] = Δμ̃ whose transfer function from ξ is eq 34,
//     W(p) = σ√(2α)(p + b)/(p² + 2αp + b²), and hence whose correlation function is eq 32:
//     (sI − A)⁻¹G has second row σ√(2α)(s + b)/(s² + 2αs + b²), first row σ√(2α)((b−2α)s − b²)/(…).
//     The paper's text calls x[0] "the total sensor error"; that labelling does not match its own
//     eq 34. We keep the paper's A and G and set H = [0 1], so H·x is the drift with correlation
//     σ² e^{−α|τ|} cos βτ (checked in tests/unit/calibration/identify_shaping_filter_test.cpp).
//
// Usage in an EKF (augmented block of size n starting at some offset o):
//   F[o:o+n, o:o+n] = A (continuous) or Φ (discrete);  Q[o:o+n, o:o+n] += G Gᵀ (continuous, per
//   unit time) or Qd (discrete, per step);  the sensor error seen by the navigation equations is
//   H·x (so its Jacobian w.r.t. the block is H);  the initial covariance is P∞ (stationary).
// Matrices are fixed 2×2 / 2×1 / 1×2; for the exponential model only the leading 1×1 part is used
// (the rest is zero) and n = 1.
#pragma once
#include <Eigen/Core>

namespace calbench::identification {

enum class DriftModelKind { exponential, exp_cosine };
const char* drift_model_name(DriftModelKind k);  // "exponential" | "exp_cosine"

// Parameters of the correlation function K(τ) = σ² e^{−α|τ|} cos βτ (β = 0 for exponential).
struct DriftModel {
  DriftModelKind kind = DriftModelKind::exponential;
  double sigma = 0;  // σ, units of the signal
  double alpha = 0;  // α = 1/T, 1/s
  double beta = 0;   // β, rad/s (0 for exponential)
  double correlation(double tau) const;  // K(τ)
};

struct ShapingFilter {
  DriftModelKind kind = DriftModelKind::exponential;
  int n = 1;                                       // number of states (1 or 2)
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();     // continuous dynamics
  Eigen::Vector2d G = Eigen::Vector2d::Zero();     // noise input (unit-intensity white ξ)
  Eigen::RowVector2d H = Eigen::RowVector2d::Zero();  // drift = H x
  Eigen::Matrix2d P_inf = Eigen::Matrix2d::Zero();    // stationary covariance: A P + P Aᵀ + G Gᵀ = 0
};

struct DiscreteShapingFilter {
  int n = 1;
  double dt = 0;
  Eigen::Matrix2d Phi = Eigen::Matrix2d::Zero();  // e^{A dt}
  Eigen::Matrix2d Qd = Eigen::Matrix2d::Zero();   // ∫₀^dt e^{Aτ} G Gᵀ e^{Aᵀτ} dτ
};

// Eq 22 (exponential) or eqs 35–36 (exp-cosine). Throws std::invalid_argument for σ ≤ 0, α ≤ 0
// or β < 0.
ShapingFilter shaping_filter(const DriftModel& m);
// Exact discretisation (Van Loan), valid for any dt > 0.
DiscreteShapingFilter discretise(const ShapingFilter& f, double dt);

}  // namespace calbench::identification
