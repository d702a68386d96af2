// Overlapping Allan deviation of a rate series (gyro rad/s, accelerometer m/s², or any signal) at
// octave-spaced cluster times τ = m·dt, m = 1, 2, 4, …, with 68.3 % confidence intervals, and a
// fit of the IEEE Std 952 / 1293 noise terms. Definitions (y = rate samples, θ = Σ y dt):
//   AVAR(τ) = 1/(2τ²(M − 2m)) Σ_{k=0}^{M−2m−1} (θ_{k+2m} − 2θ_{k+m} + θ_k)²,  M = N + 1 angle points.
// Noise terms, each with the AVAR it produces (two-sided rate PSD S(f) in brackets):
// (units for a rate signal y; for a gyro y is rad/s, for an accelerometer m/s²)
//   Q  quantisation            σ² = 3Q²/τ²        Q in y·s (rad, m/s)
//   N  angle/velocity random walk (white rate noise)  σ² = N²/τ   N in y·√s (rad/√s, m/s/√s);
//      N² is the two-sided white PSD S of y; the one-sided density is √2·N
//   B  bias instability (flicker rate)  σ² = (2 ln 2/π) B²  B in y   [S(f) = B²/(2π f)]
//   K  rate random walk         σ² = K²τ/3         K in y/√s (rad/s/√s)  [S(f) = K²/(2πf)²]
//   R  rate ramp (drift)        σ² = R²τ²/2        R in y/s
//   GM first-order Gauss–Markov of variance σ_gm², correlation time T:
//      σ² = (σ_gm² T²/τ²)(2τ/T − 3 + 4e^{−τ/T} − e^{−2τ/T})  (RRW-like for τ ≪ T, white for τ ≫ T).
// Confidence intervals: χ² with equivalent degrees of freedom of the overlapping estimator for the
// noise type the local slope of the curve indicates (NIST SP 1065 table 5: white PM, white FM,
// flicker FM, random-walk FM), quantiles by the Wilson–Hilferty approximation.
#pragma once
#include <cstddef>
#include <span>
#include <vector>

namespace calbench::identification {

struct AllanPoint {
  std::size_t m = 0;   // cluster size (samples)
  double tau = 0;      // s
  double adev = 0;     // σ(τ), signal units
  double lo = 0, hi = 0;  // 68.3 % confidence interval of σ(τ)
  double edf = 0;      // equivalent degrees of freedom used
};

// Octave-spaced τ from dt up to (N − 1)/2 samples… but at most max_m (0: no limit). Needs N ≥ 8.
std::vector<AllanPoint> allan_deviation(std::span<const double> y, double dt, std::size_t max_m = 0);

struct AllanTerm {
  bool present = false;  // false: the fit set it to zero (non-negative least squares)
  double value = 0;      // SI (see above)
  double se = 0;         // 1-σ from the weighted fit (0 when not present)
};

struct AllanFit {
  AllanTerm Q, N, B, K, R;  // five-term power-law model
  double chi2 = 0;          // Σ edf/2 · (model/avar − 1)² over the points, for the five-term model
  // Alternative: Q, N, Gauss–Markov (σ_gm, T), K, R — the GM term replacing B.
  bool gm_present = false;
  double gm_sigma = 0, gm_T = 0;
  double gm_chi2 = 0;       // same measure as chi2, for the GM alternative
  AllanTerm gm_N, gm_K;     // white and RRW levels of the GM alternative
  std::size_t points = 0;
  // The usual read-off: minimum of the curve and B = σ_min/√(2 ln 2/π) = σ_min/0.664.
  double adev_min = 0, tau_min = 0, B_from_min = 0;
  double N_at_1s = 0;       // σ(τ) at τ = 1 s of the fitted N line (= N)
};

// Weighted non-negative least squares on AVAR, χ² = Σ edf/2 · (model/avar − 1)², over every
// point with edf ≥ 1.
AllanFit fit_allan(const std::vector<AllanPoint>& pts);

// Allan variance of each term at τ (for plotting and tests).
double avar_quantisation(double Q, double tau);
double avar_white(double N, double tau);
double avar_bias_instability(double B);
double avar_rate_random_walk(double K, double tau);
double avar_rate_ramp(double R, double tau);
double avar_gauss_markov(double sigma, double T, double tau);

}  // namespace calbench::identification
