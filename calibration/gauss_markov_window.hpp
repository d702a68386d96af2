// Covariance of the time averages of a stationary first-order Gauss–Markov process over two
// windows. The estimators and the diagnosis model the in-run drift of block means (a block is the
// mean of many samples over [c − d/2, c + d/2]); taking the process at the block centre instead
// overstates the variance of a block mean and understates the correlation of neighbouring ones,
// by amounts that matter as soon as the drift is large against the white noise of a block (a drift
// of 16× the data-sheet σ with τ = 60 s was taken for one of 32× with τ = 300 s).
//
// With K(u) = σ² e^{−|u|/τ} and means over [a₁, b₁] and [a₂, b₂] (lengths d₁, d₂):
//   Cov = σ²/(d₁d₂) ∫∫ e^{−|s−t|/τ} ds dt
//       = σ²/(d₁d₂) [H(b₂−a₁) + H(a₂−b₁) − H(b₂−b₁) − H(a₂−a₁)],  H(u) = τ²(e^{−|u|/τ} + |u|/τ − 1);
//   disjoint windows, centres Δ apart:  σ² e^{−|Δ|/τ} · S(d₁/2τ) · S(d₂/2τ),  S(x) = sinh(x)/x;
//   the same window (x = d/τ):          σ² · 2(x − 1 + e^{−x})/x².
// A window of length 0 is a point value, so the point model is the d → 0 limit.
#pragma once
#include <cmath>
#include <vector>

#include <Eigen/Dense>

namespace calbench {

// Correlation (Cov/σ²) of the means over [c1 − d1/2, c1 + d1/2] and [c2 − d2/2, c2 + d2/2] of a
// stationary first-order Gauss–Markov process with correlation time tau (> 0). d1, d2 ≥ 0.
double gm_window_correlation(double c1, double d1, double c2, double d2, double tau);

// The drift the noise model attributes to a residual, given v = Σ⁻¹·r (Σ the whole block
// covariance): E[drift | r] = σ²·ρ·v, ρ the window-mean correlation of the blocks (centre,
// duration) as above. The GLS smoother of the bench and the drive diagnosis.
Eigen::VectorXd gm_window_smoothed(const std::vector<double>& centre, const std::vector<double>& duration,
                                   double sigma, double tau, const Eigen::VectorXd& v);

// Random-walk density K = σ·√(2/τ) (unit/√s) of a first-order Gauss–Markov process: its spectrum
// above 1/τ is K²/ω², which is what a record only a few τ long determines.
inline double gm_random_walk_density(double sigma, double tau) { return sigma * std::sqrt(2.0 / tau); }

}  // namespace calbench
