// The bench's data source for the diagnosis engine (diagnosis_engine.hpp): the design (z and the
// regressor columns per sub-block, per-axis local columns [b, M_i0..M_i2 | terms touching the
// axis]), its two-level datasets (~1 s parents by GLS with white + drift + bench-error covariance;
// sub-block deviations from their parent's mean, white only) and the residuals of a fit.
#pragma once
#include <vector>

#include "calibration/diagnosis/diagnose.hpp"
#include "calibration/diagnosis/diagnosis_engine.hpp"

namespace calbench::bench_diag {

using diag::kAxes;
constexpr int kBase = 4;  // b, M_i0, M_i1, M_i2

// Everything precomputed once: raw observations and regressor columns per sub-block.
struct Design {
  std::vector<Term> terms;
  std::vector<int> term_param_offset;  // into the global parameter vector after the 24 base params
  int n_term_params = 0;
  // per axis: columns (base 4, then every term param that touches the axis)
  std::vector<int> col_of[kAxes];  // col_of[a][t] = first local column of term t on axis a, −1 if none
  int ncols[kAxes] = {};
  std::vector<Eigen::VectorXd> z;  // per axis: raw z per sub-block (measured − ref − carried)
  std::vector<Eigen::MatrixXd> X;  // per axis: Nsub × ncols raw columns
  double white_var[kAxes] = {};
  std::vector<NotExcited> not_excited;  // candidates dropped: this recording cannot excite them
};

using Dataset = diag::LinearDataset;
using FitOut = diag::FitOut;
using Model = std::vector<int>;  // indices into Design::terms

Design build_design(const DiagData& d, const EffectTerms& carried);
Dataset build_dataset(const DiagData& d, const Design& D, int a, int subset, double ds, double tau,
                      const DiagnoseOptions& opt);
// Local (column, global parameter) pairs of a model on axis a.
diag::ColumnMap column_map(const Design& D, const Model& m, int a, std::vector<int>& offset);
int model_params(const Design& D, const Model& m);
FitOut fit_model(const Design& D, const Model& m, const std::vector<const Dataset*>& sets);
// Residual per sub-block of axis a for parameters theta of model m.
Eigen::VectorXd residual(const Design& D, const Model& m, int a, const Eigen::VectorXd& theta);
// Residual of the given coefficients (b, M) on axis a.
Eigen::VectorXd residual_coeffs(const Design& D, const SensorErrors& e, int a);
// Parent-block means of a sub-block residual series on one axis.
Eigen::VectorXd parent_means(const DiagData& d, const Dataset& S, const Eigen::VectorXd& r);

}  // namespace calbench::bench_diag
