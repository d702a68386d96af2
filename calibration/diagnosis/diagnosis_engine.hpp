// The linear problem both diagnoses share (bench: diagnose.cpp, drive: drive_diagnose.cpp): one
// sensor axis' data under one noise model, whitened by the Cholesky factor of its parent-block
// covariance, kept as normal-equation pieces (Gram G, Xᵀz, zᵀz); the Jacobi-scaled fit of a model
// over several such datasets with its χ² and the restricted-likelihood term; the drift the noise
// model sees in a residual. The two data sources only build z, X and the covariance R.
//
// A model's parameters reach a dataset's columns through a ColumnMap of (column, parameter)
// pairs: the bench keeps per-axis local columns, the drive global ones. The sums run in the
// order the two diagnoses always ran them (the outputs are compared within 1e-12).
#pragma once
#include <algorithm>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "calibration/diagnosis/diag_data.hpp"
#include "calibration/diagnosis/greedy_search.hpp"
#include "calibration/gauss_markov_window.hpp"

namespace calbench::diag {

constexpr int kAxes = 6;  // a = sensor·3 + axis (gyro x..accel z)

// One axis' whitened data. The drive uses the parent level only (n_low rows); the bench adds the
// sub-block deviations from their parent's mean (n_high rows) to G, g, zz and keeps the
// parent-level part apart in Gl, gl, zzl.
struct LinearDataset {
  int axis = 0, subset = kSubsetAll;
  std::vector<int> parents;  // parent indices
  Eigen::MatrixXd L;         // Cholesky factor of the parent covariance
  Eigen::MatrixXd G;         // Gram of the whitened columns
  Eigen::VectorXd g;         // whitened columnsᵀ · whitened z
  double zz = 0;
  Eigen::MatrixXd Gl;        // bench: parent-level part of G, g, zz
  Eigen::VectorXd gl;
  double zzl = 0;
  int n_low = 0, n_high = 0;
  double logdet = 0;         // ln det R
  double drift_sigma = 0, drift_tau = 1;
};

// (column of a dataset, index of the parameter in the fit's theta) for one model on one axis.
using ColumnMap = std::vector<std::pair<int, int>>;

struct FitOut {
  Eigen::VectorXd theta;
  Eigen::MatrixXd cov;
  double chi2 = 0;
  double chi2_axis[kAxes] = {};
  std::vector<int> offset;  // bench: per model term, start in theta
  double logdet_info = 0;   // ln det(Xᵀ R⁻¹ X (+ priors)): the restricted-likelihood (REML) term
};

// First-order Gauss–Markov drift covariance of two parent blocks' means.
inline double drift_covariance(const ParentBlock& pk, const ParentBlock& pl, double ds, double tau) {
  return ds * ds * gm_window_correlation(pk.t_mid, pk.duration, pl.t_mid, pl.duration, tau);
}

// Parameter p of term t at 1, every other term zero (t0_c: the carried reference temperature):
// its predicted output is the term's regressor column.
inline EffectTerms unit_term(const Term& t, int p, double t0_c) {
  EffectTerms unit;
  unit.t0_c = t0_c;
  t.add_param(unit, p, 1.0);
  return unit;
}

// The catalogue search's policy from a diagnosis' options (bench or drive). A drift larger than
// the data sheet says (correlated_drift) competes with the linear terms in every round: a
// wandering bias would otherwise be half-explained by spurious linear terms.
template <class Options>
GreedyPolicy search_policy(const Options& opt) {
  GreedyPolicy policy;
  policy.min_delta_chi2 = opt.min_delta_chi2;
  policy.penalty_per_param = opt.penalty_per_param;
  policy.max_findings = opt.max_findings;
  policy.drift_competes = true;
  return policy;
}

// The data-sheet drift (first-order Gauss–Markov σ, τ) per triad (0 gyro, 1 accel).
struct DriftPrior {
  double sigma[2], tau[2];
};
inline DriftPrior drift_prior(const NoiseSpec& n) {
  return {{n.gyro.drift_sigma, n.accel.drift_sigma}, {n.gyro.drift_tau_s, n.accel.drift_tau_s}};
}

// An empty dataset of `axis` (held-out `subset`) under the drift (ds, tau), holding the parents
// 0..n_parents−1 that keep(p) admits; whiten() fills it.
template <class Keep>
LinearDataset subset_dataset(int axis, int subset, double ds, double tau, int n_parents, Keep keep) {
  LinearDataset S;
  S.axis = axis;
  S.subset = subset;
  S.drift_sigma = ds;
  S.drift_tau = tau;
  for (int p = 0; p < n_parents; ++p)
    if (keep(p)) S.parents.push_back(p);
  return S;
}

// Whiten parent-level z and X by the Cholesky factor of R into S (L, G, g, zz, logdet, n_low).
// A covariance that is not positive definite gets its diagonal raised by 5 % up to `retries`
// times (the drive's estimated banded noise can be borderline; the bench's never is).
void whiten(LinearDataset& S, Eigen::MatrixXd R, const Eigen::VectorXd& z, const Eigen::MatrixXd& X, int retries);

// χ² of parameters theta on a dataset: zz − 2θᵀg + θᵀGθ over the mapped columns.
inline double quadratic_chi2(const Eigen::MatrixXd& G, const Eigen::VectorXd& g, double zz, const ColumnMap& cm,
                             const Eigen::VectorXd& theta) {
  double chi2 = zz;
  for (const auto& [c, p] : cm) {
    chi2 -= 2 * theta(p) * g(c);
    for (const auto& [c2, p2] : cm) chi2 += theta(p) * G(c, c2) * theta(p2);
  }
  return chi2;
}

// Add a dataset's normal equations into A, b through the column map.
inline void accumulate_normal(Eigen::MatrixXd& A, Eigen::VectorXd& b, const LinearDataset& S, const ColumnMap& cm) {
  for (const auto& [c, p] : cm) {
    b(p) += S.g(c);
    for (const auto& [c2, p2] : cm) A(p, p2) += S.G(c, c2);
  }
}

// Each global index mapped to itself (χ² of a global theta).
inline ColumnMap global_map(const std::vector<int>& idx) {
  ColumnMap cm;
  for (int p : idx) cm.push_back({p, p});
  return cm;
}

// The fit of a model over global parameters `idx` (of P in all; the drive's and the multipos
// diagnosis' layout): the datasets' normal equations, weak zero-mean priors on every parameter from
// n_base on (σ = prior_sigma[index − n_base]; ≤ 0: none) so that one the data cannot see stays at
// zero instead of trading off against the bias, solve_scaled; θ and its covariance global (zeros
// outside the model), χ² per axis.
FitOut fit_global(const std::vector<int>& idx, int P, int n_base, const std::vector<double>& prior_sigma,
                  const std::vector<const LinearDataset*>& sets);

// The catalogue search's problem (greedy_search.hpp) over a design of global parameters (the
// drive's, the multipos poses'): Design has `terms`, `term_off` (global index of each term's first
// parameter) and `touched` (per term, the axes with a column), and model_params(D, terms) (found by
// argument-dependent lookup) gives a model's global indices. A term's penalty counts the rows of
// the axes it touches, correlated_drift's the rows; the data source adds build() and fit().
template <class Design>
struct GlobalProblem {
  using Dataset = LinearDataset;
  using Fit = FitOut;
  const Design& D;
  int n_terms() const { return static_cast<int>(D.terms.size()); }
  const Term& term(int t) const { return D.terms[t]; }
  double chi2(const Dataset& S, const std::vector<int>& m, const Fit& f) const {
    return quadratic_chi2(S.G, S.g, S.zz, global_map(model_params(D, m)), f.theta);
  }
  bool touches(int t, int a) const { return std::find(D.touched[t].begin(), D.touched[t].end(), a) != D.touched[t].end(); }
  int rows(const Dataset& S) const { return S.n_low; }
  int drift_rows(const Dataset& S) const { return S.n_low; }
  int param_index(const Fit& /*f*/, std::size_t /*k*/, int t) const { return D.term_off[t]; }
};

// Solve A θ = b with Jacobi scaling and a tiny ridge (parameters a subset cannot see stay at 0):
// θ, its covariance A⁻¹ and ln det A into out.
void solve_scaled(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, double ridge, Eigen::VectorXd& theta,
                  Eigen::MatrixXd& cov, double& logdet_info);

// The drift as the noise model sees it in a parent-level residual rP: the smoothed (conditional
// mean) first-order Gauss–Markov part, E[drift | r] = K_drift · Σ⁻¹ · r.
Eigen::VectorXd smoothed_drift(const std::vector<ParentBlock>& parents, const LinearDataset& S,
                               const Eigen::VectorXd& rP);

}  // namespace calbench::diag
