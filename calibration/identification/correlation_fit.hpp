// Identification of the drift-model parameters from the statistical correlation function K̂
// (paper section IV, eqs 24–38), and the nonlinear least-squares fits beside them.
//
// The paper's log-linear estimates ("paper"):
//   exponential (eqs 28, 29, 31): σ² = K̂(0), r̂_j = K̂(j)/σ², α = −Σ ln r̂_j / Σ τ_j over the
//     "limited sample" where K̂ > 0: the leading run of lags j = 0 … J with K̂(j) > 0 (no further
//     than the maximum lag).
//   exponential-cosine (eq 38 and the formula after it): σ² = K̂(0), β = 0.5π/τ_β with τ_β the
//     first zero of K̂ (linear interpolation between lags), α = Σ_{j≥1} (ln cos βτ_j − ln r̂_j) / Σ τ_j
//     over the same leading positive run (there τ_j < τ_β, so cos βτ_j > 0). Needs a sign change.
//
// Nonlinear least squares ("nls"): eq 24 and eq 37 with σ² free as well,
//   min Σ_j [K̂(j) − σ² e^{−α τ_j} cos βτ_j]²   over lags j = first_lag … max_lag (Levenberg–Marquardt).
// By default lag 0 is left out (first_lag = 1): white measurement noise adds its variance to K̂(0)
// only, and would otherwise be mistaken for drift variance; white_var = K̂(0) − σ² reports it.
//
// Standard errors. Neighbouring lags of K̂ are strongly correlated, so the textbook
// s²(JᵀJ)⁻¹ (reported as se_*_iid) understates the uncertainty. The reported se_* use Bartlett's
// large-sample covariance of K̂ for a Gaussian process,
//   cov(K̂(j), K̂(k)) ≈ (1/N) Σ_m [K(m)K(m+k−j) + K(m+k)K(m−j)],
// evaluated with the fitted model (and K̂(0) at lag 0, which carries any white noise), in the
// sandwich Cov(θ) = (JᵀJ)⁻¹ Jᵀ Σ J (JᵀJ)⁻¹ of the unweighted least-squares estimator. They are
// 1-σ, first-order (delta-method) errors of the estimate from this record; they do not include
// the O(T/T_record) bias of K̂ from removing the mean.
//
// Structure choice. Both structures are fitted over the same lags; AIC and BIC use the residual
// sum of squares (n lags, p = 2 or 3 parameters). Because the lags are correlated, n overstates
// the information and BIC alone would favour the extra parameter on noise; the exp-cosine model is
// chosen only when (a) its BIC is lower by more than `bic_margin`, and (b) β is significant,
// β/se_β > `beta_z` with the honest (Bartlett) se_β, (c) the fitted curve has a negative lobe
// deeper than `lobe_z` Bartlett standard deviations of K̂ at that lag (the sign change is
// significant, not estimation noise), and (d) the fit converged. The sign change of
// K̂ (the paper's criterion) is reported beside it.
#pragma once
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "calibration/identification/shaping_filter.hpp"

namespace calbench::identification {

struct PaperExponential {
  bool valid = false;      // false if K̂(1) ≤ 0 (nothing to fit) or α ≤ 0
  double sigma = 0, alpha = 0;
  std::size_t lags_used = 0;  // J: lags 0 … J were summed
};

struct PaperExpCosine {
  bool valid = false;      // false if K̂ has no zero within the lags, or α ≤ 0
  double sigma = 0, alpha = 0, beta = 0;
  double tau_beta = 0;     // first zero of K̂, s
  std::size_t lags_used = 0;
};

PaperExponential paper_exponential(std::span<const double> K, double dt, std::size_t max_lag);
PaperExpCosine paper_exp_cosine(std::span<const double> K, double dt, std::size_t max_lag);

struct NlsFit {
  DriftModelKind kind = DriftModelKind::exponential;
  bool converged = false;
  bool usable = false;     // set by identify(): converged, finite errors, 1e-3/T_record < α < 1e3/dt
  int iterations = 0;
  double sigma = 0, alpha = 0, beta = 0;
  double se_sigma = 0, se_alpha = 0, se_beta = 0;              // Bartlett sandwich (see above)
  double se_sigma_iid = 0, se_alpha_iid = 0, se_beta_iid = 0;  // s²(JᵀJ)⁻¹, for comparison
  double rss = 0;          // Σ residual², units of K̂²
  std::size_t lags = 0;    // number of lags fitted
  double aic = 0, bic = 0;
  double white_var = 0;    // K̂(0) − σ² (≥ 0 when white noise is present), units of K̂
  double min_model = 0;    // most negative value of the fitted K within the lags (0 if none)
  double min_model_se = 0; // Bartlett 1-σ of K̂ at that lag
  DriftModel model() const { return {kind, sigma, alpha, beta}; }
};

// Fit over lags first_lag … max_lag of K (K from autocovariance(), n_samples the record length).
NlsFit fit_exponential(std::span<const double> K, double dt, std::size_t n_samples,
                       std::size_t first_lag, std::size_t max_lag);
NlsFit fit_exp_cosine(std::span<const double> K, double dt, std::size_t n_samples,
                      std::size_t first_lag, std::size_t max_lag, double beta_start_hint = 0,
                      const NlsFit* exponential_fit = nullptr);

struct IdentifyOptions {
  double max_lag_s = 0;      // 0: automatic (see identify())
  std::size_t first_lag = 1; // 0 to include K̂(0) in the NLS fit
  double bic_margin = 10.0;
  double beta_z = 3.0;
  double lobe_z = 3.0;
};

struct Identification {
  std::size_t n_samples = 0;
  double dt = 0;
  double mean = 0;                 // m_x
  std::vector<double> K;           // K̂(0 … max_lag)
  std::size_t max_lag = 0;
  bool sign_change = false;        // K̂ < 0 somewhere within the lags
  double first_zero_s = 0;         // τ_β (0 if none)
  PaperExponential paper_exp;
  PaperExpCosine paper_cos;
  NlsFit exp, cos;
  DriftModelKind chosen = DriftModelKind::exponential;
  std::string reason;              // why the structure was chosen, human readable
  const NlsFit& best() const { return chosen == DriftModelKind::exponential ? exp : cos; }
};

// Everything above for one series at a constant step dt. Automatic maximum lag: T₀ = the first
// lag where K̂ falls below K̂(1)/e; L = max(3 T₀, 2.5 τ_β) (τ_β only if K̂ crosses zero before
// 3 T₀, i.e. where an exponential could not), at most N/5, at least 10 lags. (Far lags of K̂ are
// mostly estimation noise; for a first-order process 2–3 T gives the smallest error of T̂.) Throws std::invalid_argument if N < 20, the
// series is constant, or not finite.
Identification identify(std::span<const double> x, double dt, const IdentifyOptions& opt = {});

}  // namespace calbench::identification
