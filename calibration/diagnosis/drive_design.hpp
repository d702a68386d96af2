// The drive's data source for the diagnosis engine (diagnosis_engine.hpp): the design (block
// means of z and of the regressor columns over global parameters [6 biases | 18 ΔM or 3 mounting
// angles | terms]), the short-range noise estimated from the data, the parent-level datasets
// (banded short-range noise + first-order Gauss–Markov drift) and the fit with weak priors.
#pragma once
#include <algorithm>
#include <vector>

#include "calibration/diagnosis/diagnosis_engine.hpp"
#include "calibration/diagnosis/drive_diagnose.hpp"

namespace calbench::drive_diag {

using diag::kAxes;
constexpr int kLags = 3;

// Weighted mean of x over element i and up to h neighbours on each side within i's contiguous
// run (adjacent(l): elements l − 1 and l are contiguous); summed centre first, then backwards,
// then forwards.
template <class T, class X, class Wt, class Adj>
T run_window_mean(int N, int i, int h, X x, Wt wt, Adj adjacent) {
  T s = x(i) * wt(i);
  double sw = wt(i);
  for (int l = i - 1; l >= std::max(0, i - h) && adjacent(l + 1); --l) {
    s += x(l) * wt(l);
    sw += wt(l);
  }
  for (int l = i + 1; l < std::min(N, i + h + 1) && adjacent(l); ++l) {
    s += x(l) * wt(l);
    sw += wt(l);
  }
  return s / sw;
}

// Global parameters: 6 biases, then 18 ΔM (M free) or 3 mounting angles (M fixed), then the
// candidate terms' parameters.
struct Design {
  bool fixed = false;
  int n_base = 0;
  std::vector<Term> terms;
  std::vector<int> term_off;  // global index of each term's first parameter
  int P = 0;
  std::vector<Eigen::VectorXd> z;  // per axis, per sub
  std::vector<Eigen::VectorXd> zp;  // per axis, per parent
  std::vector<Eigen::MatrixXd> Xp;  // per axis: Nparent × P
  std::vector<std::vector<int>> touched;  // per term: axes with a non-zero column
  std::vector<char> contig;  // sub j follows sub j−1 without a gap
  // Short-range noise per axis: sub-level autocovariance (lags 0..3), and the parent-level
  // banded covariance (variance, covariance with the next parent).
  double gamma[kAxes][kLags + 1] = {};
  double endpoint_var[kAxes] = {};
  double white_scale[kAxes] = {1, 1, 1, 1, 1, 1};
  std::vector<double> prior_sigma;  // per term parameter
  std::vector<double> pvar[kAxes], pcov[kAxes];
};

using Dataset = diag::LinearDataset;
using FitOut = diag::FitOut;  // theta, cov: global, zeros outside the model

Design build_design(const DriveDiagData& d, const SensorErrors& cur, const EffectTerms& carried, bool fixed);
Dataset build_dataset(const DriveDiagData& d, const Design& D, int a, int subset, double ds, double tau);
// Global parameter indices of a model: the base, then the terms' parameters.
std::vector<int> model_params(const Design& D, const std::vector<int>& terms);
using diag::global_map;  // each global index mapped to itself (χ² of a global theta)
FitOut fit_model(const Design& D, const std::vector<int>& terms, const std::vector<const Dataset*>& sets);
// Parent-level residual of axis a for global parameters theta.
inline Eigen::VectorXd residual(const Design& D, int a, const Eigen::VectorXd& theta) { return D.zp[a] - D.Xp[a] * theta; }

}  // namespace calbench::drive_diag
