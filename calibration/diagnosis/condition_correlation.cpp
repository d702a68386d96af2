#include "calibration/diagnosis/condition_correlation.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace calbench {

std::vector<std::string> condition_names() {
  return {"rate", "w_x", "w_y", "w_z", "f_x", "f_y", "f_z", "temperature", "dT/dt", "time", "angle"};
}

double condition_value(const DiagData& d, const SubBlock& s, const std::string& name) {
  if (name == "rate") return s.w.norm();
  if (name == "w_x") return s.w(0);
  if (name == "w_y") return s.w(1);
  if (name == "w_z") return s.w(2);
  if (name == "f_x") return s.f(0);
  if (name == "f_y") return s.f(1);
  if (name == "f_z") return s.f(2);
  if (name == "temperature") return std::isfinite(s.temp_c) ? s.temp_c : 0.0;
  if (name == "dT/dt") return s.parent >= 0 ? d.parents[s.parent].dtemp : 0.0;
  if (name == "time") return s.t_mid;
  if (name == "angle") {
    if (!std::isfinite(s.angle)) return 0.0;
    double u = std::fmod(s.angle * 180.0 / M_PI, 360.0);
    return u < 0 ? u + 360.0 : u;
  }
  return 0.0;
}

std::string condition_axis_label(const std::string& name) {
  static const std::vector<std::pair<std::string, std::string>> units = {
      {"rate", "rad/s"},      {"|w|", "rad/s"},       {"w_x", "rad/s"},        {"w_y", "rad/s"},
      {"w_z", "rad/s"},       {"turn_rate", "rad/s"}, {"f_x", "m/s²"},         {"f_y", "m/s²"},
      {"f_z", "m/s²"},        {"f", "m/s²"},          {"|f|", "m/s²"},         {"along_accel", "m/s²"},
      {"ang_accel", "rad/s²"}, {"speed", "m/s"},      {"temperature", "°C"},   {"dT/dt", "°C/s"},
      {"time", "s"},          {"angle", "°"}};
  for (const auto& [n, u] : units)
    if (n == name) return name + " (" + u + ")";
  return name;
}

std::vector<std::string> drive_condition_names(bool with_temperature) {
  std::vector<std::string> n = {"speed", "w_x", "w_y", "w_z", "f_x", "f_y", "f_z", "|w|", "|f|",
                                "ang_accel", "turn_rate", "along_accel", "time"};
  if (with_temperature) n.push_back("temperature");
  return n;
}

double drive_condition_value(const DriveDiagData& d, int k, const std::string& name) {
  const ParentBlock& p = d.parents[k];
  const DriveParentInfo& i = d.info[k];
  if (name == "speed") return i.speed;
  if (name == "w_x") return p.w(0);
  if (name == "w_y") return p.w(1);
  if (name == "w_z") return p.w(2);
  if (name == "f_x") return p.f(0);
  if (name == "f_y") return p.f(1);
  if (name == "f_z") return p.f(2);
  if (name == "|w|") return p.w.norm();
  if (name == "|f|") return p.f.norm();
  if (name == "ang_accel") return i.ang_accel;
  if (name == "turn_rate") return i.turn_rate;
  if (name == "along_accel") return i.along_accel;
  if (name == "time") return p.t_mid;
  if (name == "temperature") {
    double t = 0, w = 0;
    for (int j = p.first; j < p.first + p.count; ++j)
      if (std::isfinite(d.subs[j].temp_c)) {
        t += d.subs[j].temp_c;
        w += 1;
      }
    return w > 0 ? t / w : 0.0;
  }
  return 0.0;
}

namespace diag {

std::vector<double> parent_block_means(const DiagData& d, const Eigen::VectorXd& r) {
  std::vector<double> rp(d.parents.size());
  for (std::size_t p = 0; p < d.parents.size(); ++p) {
    const ParentBlock& pb = d.parents[p];
    double z = 0;
    for (int j = pb.first; j < pb.first + pb.count; ++j) z += d.subs[j].n * r(j);
    rp[p] = z / pb.n;
  }
  return rp;
}

double pearson(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  if (n < 3) return 0.0;
  const double mx = std::accumulate(x.begin(), x.end(), 0.0) / n, my = std::accumulate(y.begin(), y.end(), 0.0) / n;
  double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sxy += (x[k] - mx) * (y[k] - my);
    sxx += (x[k] - mx) * (x[k] - mx);
    syy += (y[k] - my) * (y[k] - my);
  }
  return (sxx > 0 && syy > 0) ? sxy / std::sqrt(sxx * syy) : 0.0;
}

double pearson(const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  const double mx = x.mean(), my = y.mean();
  const double sxy = ((x.array() - mx) * (y.array() - my)).sum();
  const double sxx = (x.array() - mx).square().sum(), syy = (y.array() - my).square().sum();
  return sxx > 0 && syy > 0 ? sxy / std::sqrt(sxx * syy) : 0.0;
}

std::vector<ConditionCorrelation> correlations(const DiagData& d, const Eigen::VectorXd& r) {
  std::vector<ConditionCorrelation> out;
  // Parent-level for slow conditions; sub-block deviations for the angle.
  const std::vector<double> rp = parent_block_means(d, r);
  for (const auto& name : condition_names()) {
    if (name == "angle") continue;
    std::vector<double> x(d.parents.size());
    for (std::size_t p = 0; p < d.parents.size(); ++p) {
      const ParentBlock& pb = d.parents[p];
      x[p] = condition_value(d, d.subs[pb.first + pb.count / 2], name);
      if (name == "dT/dt") x[p] = pb.dtemp;
    }
    out.push_back({name, pearson(x, rp)});
  }
  // Angle: amplitude-correlation of within-parent deviations with cos/sin of the angle (rotating).
  std::vector<double> dev, c, s;
  for (const auto& sb : d.subs)
    if (sb.rotating() && std::isfinite(sb.angle)) {
      dev.push_back(r(&sb - &d.subs[0]) - rp[sb.parent]);
      c.push_back(std::cos(sb.angle));
      s.push_back(std::sin(sb.angle));
    }
  if (dev.size() > 10) out.push_back({"angle", std::hypot(pearson(c, dev), pearson(s, dev))});
  std::sort(out.begin(), out.end(), [](const auto& x, const auto& y) { return std::abs(x.r) > std::abs(y.r); });
  return out;
}

std::vector<ConditionCorrelation> correlations(const DriveDiagData& d, const Eigen::VectorXd& r) {
  std::vector<ConditionCorrelation> out;
  const int N = static_cast<int>(d.parents.size());
  for (const auto& name : drive_condition_names(d.has_temperature)) {
    Eigen::VectorXd c(N);
    for (int k = 0; k < N; ++k) c(k) = drive_condition_value(d, k, name);
    out.push_back({name, pearson(c, r)});
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return std::abs(a.r) > std::abs(b.r); });
  return out;
}

// Amplitude of harmonics 1..4 of the table angle in the within-parent residual (rotating sub-blocks).
void angle_spectrum(const DiagData& d, const Eigen::VectorXd& r, int& best_k, double& best_amp) {
  best_k = 0;
  best_amp = 0;
  const std::vector<double> rp = parent_block_means(d, r);
  for (int k = 1; k <= 4; ++k) {
    double sc = 0, ss = 0, n = 0;
    for (const auto& sb : d.subs)
      if (sb.rotating() && std::isfinite(sb.angle)) {
        const double dev = r(&sb - &d.subs[0]) - rp[sb.parent];
        sc += dev * std::cos(k * sb.angle);
        ss += dev * std::sin(k * sb.angle);
        ++n;
      }
    if (n < 10) return;
    const double amp = 2 * std::hypot(sc, ss) / n;
    if (amp > best_amp) {
      best_amp = amp;
      best_k = k;
    }
  }
}

void strongest_sinusoid(const std::vector<double>& t, const std::vector<double>& x, double fmin, double fmax,
                        double& best_hz, double& best_amp, const std::vector<int>* group, const std::vector<double>* wt) {
  best_hz = 0;
  best_amp = 0;
  const std::size_t n = t.size();
  if (n < 20 || x.size() != n || !(fmax > fmin)) return;
  const int ng = group && !group->empty() ? *std::max_element(group->begin(), group->end()) + 1 : 0;
  std::vector<double> gw(static_cast<std::size_t>(ng), 0.0), gc(gw.size()), gs(gw.size()), cj(n), sj(n);
  for (std::size_t j = 0; ng > 0 && j < n; ++j) gw[static_cast<std::size_t>((*group)[j])] += wt ? (*wt)[j] : 1.0;
  std::vector<double> power, freq;
  double best_power = 0, hz_at = 0, amp_at = 0;
  for (double hz = fmin; hz <= fmax; hz *= 1.005) {
    const double w = 2 * M_PI * hz;
    for (std::size_t j = 0; j < n; ++j) {
      cj[j] = std::cos(w * t[j]);
      sj[j] = std::sin(w * t[j]);
    }
    if (ng > 0) {  // the regressors as deviations from their group means, like x
      std::fill(gc.begin(), gc.end(), 0.0);
      std::fill(gs.begin(), gs.end(), 0.0);
      for (std::size_t j = 0; j < n; ++j) {
        const std::size_t g = static_cast<std::size_t>((*group)[j]);
        const double q = (wt ? (*wt)[j] : 1.0) / gw[g];
        gc[g] += q * cj[j];
        gs[g] += q * sj[j];
      }
      for (std::size_t j = 0; j < n; ++j) {
        const std::size_t g = static_cast<std::size_t>((*group)[j]);
        cj[j] -= gc[g];
        sj[j] -= gs[g];
      }
    }
    double cc = 0, ss = 0, cs = 0, xc = 0, xs = 0;
    for (std::size_t j = 0; j < n; ++j) {
      const double c = cj[j], s = sj[j];
      cc += c * c;
      ss += s * s;
      cs += c * s;
      xc += x[j] * c;
      xs += x[j] * s;
    }
    const double det = cc * ss - cs * cs;
    if (det <= 1e-9 * cc * ss) continue;
    const double a = (xc * ss - xs * cs) / det, b = (xs * cc - xc * cs) / det;
    const double p = a * xc + b * xs;  // the sum of squares the sinusoid explains
    power.push_back(p);
    freq.push_back(hz);
    if (p > best_power) {
      best_power = p;
      hz_at = hz;
      amp_at = std::hypot(a, b);
    }
  }
  // The noise level near the peak: the median power within a factor 1.5 of its frequency, outside
  // its main lobe (±2/record length). A sinusoid stands alone there; broad-band structure (a
  // remainder that is not periodic) raises its neighbours with it.
  const double span = t.back() - t.front();
  std::vector<double> near;
  for (std::size_t q = 0; q < power.size(); ++q)
    if (freq[q] > hz_at / 1.5 && freq[q] < hz_at * 1.5 && std::abs(freq[q] - hz_at) > 2.0 / span) near.push_back(power[q]);
  if (near.size() < 10) return;
  std::nth_element(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(near.size() / 2), near.end());
  const double mean_noise = near[near.size() / 2] / std::log(2.0);  // median of Exp(μ) is μ ln 2
  const double m = std::max(1.0, (fmax - fmin) * span);
  if (mean_noise <= 0 || best_power / mean_noise < std::log(m / 1e-3)) return;
  best_hz = hz_at;
  best_amp = amp_at;
}

void time_spectrum(const DiagData& d, const Eigen::VectorXd& r, double& best_hz, double& best_amp) {
  // Deviations from each parent block's mean (the slow part belongs to the drift and the steps),
  // sampled at the sub-blocks' mid times; the sinusoid likewise.
  const std::vector<double> rp = parent_block_means(d, r);
  const std::size_t n = d.subs.size();
  std::vector<double> t(n), x(n), w(n);
  std::vector<int> g(n);
  for (std::size_t j = 0; j < n; ++j) {
    t[j] = d.subs[j].t_mid;
    x[j] = r(static_cast<Eigen::Index>(j)) - rp[static_cast<std::size_t>(d.subs[j].parent)];
    g[j] = d.subs[j].parent;
    w[j] = d.subs[j].n;
  }
  strongest_sinusoid(t, x, 0.02, 5.0, best_hz, best_amp, &g, &w);
}

void time_spectrum(const DriveDiagData& d, const Eigen::VectorXd& r, double& best_hz, double& best_amp) {
  best_hz = best_amp = 0;
  const std::size_t n = d.parents.size();
  if (n < 20) return;
  std::vector<double> t(n), x(n);
  double len = 0;
  for (std::size_t k = 0; k < n; ++k) {
    t[k] = d.parents[k].t_mid;
    x[k] = r(static_cast<Eigen::Index>(k));
    len += d.parents[k].duration;
  }
  len /= static_cast<double>(n);
  if (len <= 0) return;
  strongest_sinusoid(t, x, 0.01, 0.45 / len, best_hz, best_amp);
  if (best_hz > 0) {
    const double u = M_PI * best_hz * len;
    best_amp /= std::sin(u) / u;
  }
}

}  // namespace diag
}  // namespace calbench
