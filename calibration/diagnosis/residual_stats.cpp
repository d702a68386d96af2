#include "calibration/diagnosis/residual_stats.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace calbench {

void ljung_box(const std::vector<double>& x, int lags, double& q, double& p) {
  const std::size_t n = x.size();
  q = 0;
  p = 1;
  if (n < 4 || lags < 1) return;
  const double m = std::accumulate(x.begin(), x.end(), 0.0) / n;
  double c0 = 0;
  for (double v : x) c0 += (v - m) * (v - m);
  if (c0 <= 0) return;
  for (int k = 1; k <= lags && k < static_cast<int>(n); ++k) {
    double ck = 0;
    for (std::size_t t = k; t < n; ++t) ck += (x[t] - m) * (x[t - k] - m);
    const double rho = ck / c0;
    q += rho * rho / (n - k);
  }
  q *= n * (n + 2.0);
  p = chi2_upper_p(q, lags);
}

double chi2_upper_p(double q, double dof) {
  // Wilson–Hilferty: (q/k)^(1/3) is nearly normal with mean 1 − 2/(9k) and variance 2/(9k).
  const double z = (std::cbrt(std::max(q, 0.0) / dof) - (1 - 2 / (9 * dof))) / std::sqrt(2 / (9 * dof));
  return 0.5 * std::erfc(z / std::sqrt(2.0));
}

DiagFinding correlated_drift_finding(int triad, double sigma, double tau_s, const DriftInterval& interval,
                                     double delta_chi2, double delta_bic, const AxisStats (&before)[6],
                                     const AxisStats (&after)[6]) {
  DiagFinding f;
  f.term = Term{noise_effect_spec().id, triad, -1};
  f.value = {sigma};
  f.sigma = {0.5 * (interval.sigma_hi - interval.sigma_lo)};
  f.noise_tau_s = tau_s;
  f.noise_interval = interval;
  f.unit = term_unit(f.term);
  f.report_sensor = triad;
  f.report_axis = -1;
  f.delta_chi2 = delta_chi2;
  f.delta_bic = delta_bic;
  f.condition = "time";
  double rb = 0, ra = 0;
  for (int a = triad * 3; a < triad * 3 + 3; ++a) {
    rb += std::pow(before[a].systematic_rms, 2);
    ra += std::pow(after[a].systematic_rms, 2);
  }
  f.rms_before = std::sqrt(rb / 3);
  f.rms_after = std::sqrt(ra / 3);
  return f;
}

namespace diag {

Eigen::VectorXd whiteness(const LinearDataset& S, const Eigen::VectorXd& rP, int nparams, AxisStats& st) {
  const int N = static_cast<int>(S.parents.size());
  Eigen::VectorXd rw = S.L.triangularView<Eigen::Lower>().solve(rP);
  st.chi2_dof = rw.squaredNorm() / std::max(1, N - nparams / kAxes);
  std::vector<double> rv(rw.data(), rw.data() + rw.size());
  ljung_box(rv, std::min(10, std::max(1, N / 5)), st.ljung_box_q, st.ljung_box_p);
  return rw;
}

std::vector<int> worst_windows(const std::map<int, std::pair<double, double>>& sums, double sigma) {
  std::vector<std::pair<double, int>> score;
  for (const auto& [w, x] : sums) score.push_back({std::abs(x.first / x.second) * std::sqrt(x.second) / sigma, w});
  std::sort(score.rbegin(), score.rend());
  std::vector<int> worst;
  for (std::size_t k = 0; k < score.size() && k < 3; ++k) worst.push_back(score[k].second);
  return worst;
}

bool axis_reported(const DiagnoseResult& r, int a) {
  for (const auto& f : r.findings)
    if (f.report_sensor == a / 3 && (f.report_axis < 0 || f.report_axis == a % 3)) return true;
  for (const auto& u : r.unexplained)
    if (u.sensor * 3 + u.axis == a) return true;
  return false;
}

DiagUnexplained unexplained_axis(int a, const AxisStats& s, std::vector<ConditionCorrelation> correlations) {
  DiagUnexplained u;
  u.sensor = a / 3;
  u.axis = a % 3;
  u.chi2_dof = s.chi2_dof;
  u.high_chi2_dof = s.high_chi2_dof;
  u.ljung_box_p = s.ljung_box_p;
  u.systematic_rms = s.systematic_rms;
  u.step_p = s.step_p;
  u.step_family = s.step_family;
  u.correlations = std::move(correlations);
  if (u.correlations.size() > 4) u.correlations.resize(4);
  return u;
}

}  // namespace diag
}  // namespace calbench
