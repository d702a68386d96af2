#include "calibration/diagnosis/drive_innovations.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "calibration/diagnosis/drive_diagnose.hpp"

namespace calbench {

namespace {
constexpr double kChi2_3_95 = 7.814727903251178;

double corr(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = x.size();
  if (n < 3) return 0.0;
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < n; ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= n;
  my /= n;
  double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
  }
  return sxx > 0 && syy > 0 ? sxy / std::sqrt(sxx * syy) : 0.0;
}
}  // namespace

InnovationStats innovation_stats(const std::vector<InnovationSample>& x, const DriveDiagData* data, double window_s,
                                 int n_worst, int n_correlations) {
  InnovationStats s;
  std::vector<double> comp[3], nis_all;
  double nis_used = 0;
  long within = 0;
  for (const InnovationSample& e : x) {
    if (!std::isfinite(e.nis)) continue;
    ++s.epochs;
    nis_all.push_back(e.nis / 3.0);
    if (e.status == 1) ++s.rejected;
    else {
      if (e.status == 2) ++s.forced;
      else {
        ++s.used;
        nis_used += e.nis;
        if (e.nis <= kChi2_3_95) ++within;
      }
    }
    for (int i = 0; i < 3; ++i) comp[i].push_back(e.S(i, i) > 0 ? e.nu(i) / std::sqrt(e.S(i, i)) : 0.0);
  }
  if (s.epochs == 0) return s;
  s.nis_per_dof = s.used ? nis_used / (3.0 * static_cast<double>(s.used)) : 0.0;
  s.fraction_within_95 = s.used ? static_cast<double>(within) / static_cast<double>(s.used) : 0.0;
  {
    std::vector<double> v = nis_all;
    std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
    s.median_nis_per_dof = v[v.size() / 2];
  }
  s.ljung_box_p_min = 1;
  for (int i = 0; i < 3; ++i) {
    double q = 0, p = 1;
    ljung_box(comp[i], 10, q, p);
    s.ljung_box_p[i] = p;
    s.ljung_box_p_min = std::min(s.ljung_box_p_min, p);
    const std::vector<double>& c = comp[i];
    std::vector<double> a(c.begin() + 1, c.end()), b(c.begin(), c.end() - 1);
    s.lag1_autocorr[i] = corr(a, b);
  }

  // Worst windows by mean NIS/dof (all epochs: a gated stretch is the worst place).
  std::map<long, std::pair<double, int>> win;
  for (const InnovationSample& e : x) {
    if (!std::isfinite(e.nis)) continue;
    auto& w = win[static_cast<long>(std::floor(e.t / window_s))];
    w.first += e.nis / 3.0;
    ++w.second;
  }
  for (const auto& [k, w] : win)
    s.worst_windows.push_back({k * window_s, (k + 1) * window_s, w.first / w.second, w.second});
  std::sort(s.worst_windows.begin(), s.worst_windows.end(),
            [](const auto& a, const auto& b) { return a.nis_per_dof > b.nis_per_dof; });
  if (static_cast<int>(s.worst_windows.size()) > n_worst) s.worst_windows.resize(static_cast<std::size_t>(n_worst));

  // Correlation with the drive conditions over the diagnosis blocks.
  if (data && !data->parents.empty()) {
    const int NP = static_cast<int>(data->parents.size());
    std::vector<double> sum(NP, 0.0);
    std::vector<int> cnt(NP, 0);
    std::vector<double> starts(NP);
    for (int k = 0; k < NP; ++k) starts[k] = data->parents[k].t_mid - 0.5 * data->parents[k].duration;
    for (const InnovationSample& e : x) {
      if (!std::isfinite(e.nis)) continue;
      const auto it = std::upper_bound(starts.begin(), starts.end(), e.t);
      if (it == starts.begin()) continue;
      const int k = static_cast<int>(it - starts.begin()) - 1;
      if (e.t > data->parents[k].t_mid + 0.5 * data->parents[k].duration + 1e-9) continue;
      sum[k] += std::sqrt(std::max(0.0, e.nis) / 3.0);
      ++cnt[k];
    }
    std::vector<int> ks;
    std::vector<double> y;
    for (int k = 0; k < NP; ++k)
      if (cnt[k] > 0) {
        ks.push_back(k);
        y.push_back(sum[k] / cnt[k]);
      }
    s.correlation_blocks = static_cast<int>(ks.size());
    if (ks.size() >= 10) {
      for (const std::string& name : drive_condition_names(data->has_temperature)) {
        std::vector<double> c;
        for (int k : ks) c.push_back(drive_condition_value(*data, k, name));
        s.correlations.push_back({name, corr(c, y)});
        const bool is_signed = name.size() == 3 && name[1] == '_';
        if (is_signed || name == "turn_rate" || name == "along_accel") {
          for (double& v : c) v = std::abs(v);
          s.correlations.push_back({"|" + name + "|", corr(c, y)});
        }
      }
      std::sort(s.correlations.begin(), s.correlations.end(),
                [](const auto& a, const auto& b) { return std::abs(a.r) > std::abs(b.r); });
      if (n_correlations >= 0 && static_cast<int>(s.correlations.size()) > n_correlations)
        s.correlations.resize(static_cast<std::size_t>(n_correlations));
    }
  }
  return s;
}

double innovation_overdispersion(const InnovationStats& s) {
  double rho = 0;
  for (double r : s.lag1_autocorr) rho = std::max(rho, std::min(r, 0.95));
  return std::max(1.0, s.nis_per_dof) * std::max(1.0, (1 + rho) / (1 - rho));
}

ProfileFit profile_quadratic(int p, double h, const std::function<double(const Eigen::VectorXd&)>& deviance_at) {
  ProfileFit out;
  Eigen::VectorXd c = Eigen::VectorXd::Zero(p);
  Eigen::VectorXd step = Eigen::VectorXd::Constant(p, h);
  for (int it = 0; it < 4; ++it) {
    auto at = [&](int i, double si, int j, double sj) {
      Eigen::VectorXd t = c;
      if (i >= 0) t(i) += si * step(i);
      if (j >= 0) t(j) += sj * step(j);
      return deviance_at(t);
    };
    const double d0 = at(-1, 0, -1, 0);
    Eigen::VectorXd g(p), dp(p);
    Eigen::MatrixXd H(p, p);
    for (int i = 0; i < p; ++i) {
      dp(i) = at(i, 1, -1, 0);
      const double dm = at(i, -1, -1, 0);
      g(i) = (dp(i) - dm) / (2 * step(i));
      H(i, i) = (dp(i) + dm - 2 * d0) / (step(i) * step(i));
    }
    for (int i = 0; i < p; ++i)
      for (int j = i + 1; j < p; ++j) H(i, j) = H(j, i) = (at(i, 1, j, 1) - dp(i) - dp(j) + d0) / (step(i) * step(j));
    const Eigen::LLT<Eigen::MatrixXd> llt(H);
    if (llt.info() != Eigen::Success) return out;
    const Eigen::VectorXd move = -llt.solve(g);
    out.sigma = (2 * llt.solve(Eigen::MatrixXd::Identity(p, p))).diagonal().cwiseSqrt();
    out.theta = c + move;
    out.ok = true;
    // The filter is not exactly linear in θ (its gain and adaptive noise follow the data): Newton
    // steps, the quadratic taken again around θ̂ with steps of its σ, until the move is below σ/10.
    if ((move.array().abs() < 0.1 * out.sigma.array()).all()) break;
    c = out.theta;
    step = out.sigma.cwiseMax(Eigen::VectorXd::Constant(p, 1e-3 * h));
  }
  return out;
}

namespace {
// One epoch's νᵀS⁻¹ν + ln det S; false where the NIS is not finite or S not positive definite.
bool deviance_term(const InnovationSample& e, double& term) {
  if (!std::isfinite(e.nis)) return false;
  const double det = e.S.determinant();
  if (!(det > 0)) return false;
  term = e.nis + std::log(det);
  return true;
}
}  // namespace

double innovation_deviance(const std::vector<InnovationSample>& x) {
  double d = 0, term = 0;
  for (const InnovationSample& e : x)
    if (deviance_term(e, term)) d += term;
  return d;
}

std::pair<double, double> paired_deviance(const std::vector<InnovationSample>& a, const std::vector<InnovationSample>& b,
                                          long* shared) {
  std::pair<double, double> d{0, 0};
  long n = 0;
  std::size_t j = 0;
  for (const InnovationSample& x : a) {
    while (j < b.size() && b[j].t < x.t - 1e-6) ++j;
    if (j == b.size()) break;
    if (std::abs(b[j].t - x.t) > 1e-6) continue;
    double ta = 0, tb = 0;
    if (deviance_term(x, ta) && deviance_term(b[j], tb)) {
      d.first += ta;
      d.second += tb;
      ++n;
    }
    ++j;
  }
  if (shared) *shared = n;
  return d;
}

HypothesisSearchResult hypothesis_search(const std::vector<int>& nparams, long rows, const GreedyPolicy& policy,
                                         const std::function<double(const std::vector<int>&)>& deviance) {
  HypothesisSearchResult out;
  std::map<std::vector<int>, double> cache;
  auto eval = [&](std::vector<int> m) {
    std::sort(m.begin(), m.end());
    const auto it = cache.find(m);
    if (it != cache.end()) return it->second;
    ++out.evaluations;
    return cache[m] = deviance(m);
  };
  const int n = static_cast<int>(nparams.size());
  auto in_model = [&](int c) { return std::find(out.model.begin(), out.model.end(), c) != out.model.end(); };
  double cur = out.base_deviance = eval({});
  while (static_cast<int>(out.model.size()) < std::min(n, policy.max_findings)) {
    HypothesisStep best;
    best.candidate = -1;
    for (int c = 0; c < n; ++c) {
      if (in_model(c)) continue;
      std::vector<int> m = out.model;
      m.push_back(c);
      const double dchi2 = cur - eval(m);
      if (out.model.empty()) out.first_round_dchi2.push_back(dchi2);
      const double dbic = dchi2 - greedy_term_penalty(nparams[c], static_cast<int>(rows), policy.penalty_per_param);
      if (dchi2 >= policy.min_delta_chi2 && dbic > 0 && (best.candidate < 0 || dchi2 > best.dchi2)) {
        best.candidate = c;
        best.dchi2 = dchi2;
        best.dbic = dbic;
      }
    }
    if (out.model.empty() && out.first_round_dchi2.size() < nparams.size()) out.first_round_dchi2.resize(nparams.size(), 0.0);
    if (best.candidate < 0) break;
    out.model.push_back(best.candidate);
    out.steps.push_back(best);
    cur -= best.dchi2;
  }
  // Backward check in the final model.
  for (bool changed = true; changed && !out.model.empty();) {
    changed = false;
    for (std::size_t k = 0; k < out.model.size(); ++k) {
      std::vector<int> without = out.model;
      without.erase(without.begin() + static_cast<long>(k));
      out.steps[k].dchi2_final = eval(without) - cur;
    }
    for (std::size_t k = 0; k < out.model.size(); ++k)
      if (out.steps[k].dchi2_final < policy.min_delta_chi2) {
        out.withdrawn.push_back(out.steps[k]);
        cur += out.steps[k].dchi2_final;
        out.model.erase(out.model.begin() + static_cast<long>(k));
        out.steps.erase(out.steps.begin() + static_cast<long>(k));
        changed = true;
        break;
      }
  }
  out.final_deviance = cur;
  return out;
}

}  // namespace calbench
