// Residual statistics both diagnoses report per sensor axis: whiteness of the whitened residual
// (χ²/dof and Ljung–Box), the axis still far from its noise model (unexplained) with its worst
// windows, and the correlated_drift finding's figures. ljung_box and correlated_drift_finding are
// declared in diagnose.hpp (public); the data-source-specific systematic RMS stays with each side
// (bench: per step and table angle; drive: grouped blocks against the banded short-range noise).
#pragma once
#include <map>
#include <utility>
#include <vector>

#include "calibration/diagnosis/diagnose.hpp"
#include "calibration/diagnosis/diagnosis_engine.hpp"

namespace calbench::diag {

// Whitened parent-level residual of rP under S's noise model; fills st.chi2_dof (dof: rows less
// the model's parameters per axis) and the Ljung–Box whiteness. Returns the whitened residual.
Eigen::VectorXd whiteness(const LinearDataset& S, const Eigen::VectorXd& rP, int nparams, AxisStats& st);

// Windows (steps on the bench, 20 s windows on drives) by |mean residual| in units of its σ:
// per window Σ residual and its weight; sigma the noise of a unit weight. The worst three.
std::vector<int> worst_windows(const std::map<int, std::pair<double, double>>& sums, double sigma);

// The unexplained entry of axis a (its statistics after, the strongest four correlations).
DiagUnexplained unexplained_axis(int a, const AxisStats& after, std::vector<ConditionCorrelation> correlations);
// Is sensor axis a (0–5) already spoken for: a finding reported on it (or on all of its triad), or
// unexplained? The issue-36 remainder reports (drift against stability, the drive's condition test)
// are made only on the other axes.
bool axis_reported(const DiagnoseResult& r, int a);

}  // namespace calbench::diag
