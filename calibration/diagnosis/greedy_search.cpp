#include "calibration/diagnosis/greedy_search.hpp"

#include <algorithm>
#include <cmath>

namespace calbench {

double greedy_term_penalty(int nparams, int rows, double penalty_per_param) {
  return nparams * (std::log(std::max(rows, 2)) + penalty_per_param);
}

double greedy_drift_penalty(int rows, double penalty_per_param) {
  return 2 * (std::log(static_cast<double>(rows)) + penalty_per_param);
}

const std::vector<double>& greedy_drift_multipliers() {
  static const std::vector<double> m = {2.0, 4.0, 8.0, 16.0, 32.0};
  return m;
}

const std::vector<double>& greedy_drift_taus() {
  static const std::vector<double> t = {60.0, 300.0, 1200.0};
  return t;
}

DiagFinding greedy_term_finding(const Term& t, const GreedyStep& step, int first, const Eigen::VectorXd& theta,
                                const Eigen::MatrixXd& cov, const EffectTerms& carried) {
  DiagFinding f;
  f.term = t;
  for (int p = 0; p < t.nparams(); ++p) {
    const int idx = first + p;
    f.value.push_back(theta(idx) + t.get_param(carried, p));
    f.sigma.push_back(std::sqrt(std::max(cov(idx, idx), 0.0)));
  }
  f.unit = term_unit(t);
  f.delta_chi2 = step.dchi2;
  f.delta_bic = step.dbic;
  f.heldout_delta_chi2 = step.dheld;
  f.report_sensor = t.sensor;
  f.report_axis = t.axis;
  return f;
}

void greedy_add_term(const Term& t, int first, const Eigen::VectorXd& theta, const Eigen::MatrixXd& cov,
                     EffectTerms& value, EffectTerms& sigma) {
  for (int p = 0; p < t.nparams(); ++p) {
    const int idx = first + p;
    t.add_param(value, p, theta(idx));
    t.add_param(sigma, p, std::sqrt(std::max(cov(idx, idx), 0.0)));
  }
}

}  // namespace calbench
