// Static detection of a multi-position recording (multipos_fit.hpp step 1; issue 37, rewritten for
// issue 55): the recording, not a guessed class, decides what is still.
//
//   Noise. The white noise per sample of each triad (its largest axis) is learned from the data:
//     - the quietest windows: the q-quantile (q = quiet_fraction) of the non-overlapping windows'
//       variances divided by the χ² distribution's own q-quantile per degree of freedom — right
//       while at least that fraction of the recording is still;
//     - the opening still interval, when the recording opens with one of min_opening_s or more (the
//       way IMU-TK's initial static period works): the windows from the start that pass the test
//       set by the quietest windows; their median variance over the χ² median sets the noise.
//   Test. A window centred on a sample is still when every axis's variance is below
//     margin·σ²·χ²_{n−1}(1−α)/(n−1) and its mean rate is the gyro bias (the median over the quiet
//     windows) within 5× the quiet windows' robust spread (at least 5σ/√n) plus 3× the bias
//     stability: a steady rotation is quiet but not still.
//   Poses. The samples covered by still windows, in runs of min_static_s or more; two runs whose
//     covers touch are split half-way through the gap between their still windows. The specific
//     force's mean is over the whole cover (its magnitude does not see the slow end of a turn); the
//     rate's over the still windows' centres only, half a window from any motion.
// No I/O.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "calibration/multipos/multipos_fit.hpp"
#include "calibration/qc/nis_test.hpp"
#include "common/units.hpp"

namespace calbench::multipos {
namespace {

using Six = Eigen::Matrix<double, 6, 1>;

// χ²_k(p)/k (Wilson–Hilferty).
double chi2_per_dof(double p, double k) { return qc::chi2_quantile(k, qc::normal_quantile(p)) / k; }

// Window means and variances of the six channels (gyro xyz, accel xyz) by prefix sums, centred on
// the channels' overall means for precision.
class Windows {
 public:
  Windows(const MultiposInput& in, std::size_t h) : n_(in.t.size()), h_(h), w_(2 * h + 1) {
    mean_.setZero();
    for (std::size_t i = 0; i < n_; ++i) mean_ += row(in, i);
    mean_ /= static_cast<double>(n_);
    s1_.assign(n_ + 1, Six::Zero());
    s2_.assign(n_ + 1, Six::Zero());
    for (std::size_t i = 0; i < n_; ++i) {
      const Six x = row(in, i) - mean_;
      s1_[i + 1] = s1_[i] + x;
      s2_[i + 1] = s2_[i] + x.cwiseProduct(x);
    }
  }
  std::size_t n() const { return n_; }
  std::size_t h() const { return h_; }
  std::size_t w() const { return w_; }
  // Centred at c, h ≤ c < n − h.
  Six var(std::size_t c) const {
    const Six a = s1_[c + h_ + 1] - s1_[c - h_], b = s2_[c + h_ + 1] - s2_[c - h_];
    return (b - a.cwiseProduct(a) / double(w_)) / double(w_ - 1);
  }
  Vec3 gyro_mean(std::size_t c) const { return (s1_[c + h_ + 1] - s1_[c - h_]).head<3>() / double(w_) + mean_.head<3>(); }
  // Centres of the non-overlapping windows.
  std::vector<std::size_t> tiles() const {
    std::vector<std::size_t> c;
    for (std::size_t k = h_; k + h_ < n_; k += w_) c.push_back(k);
    return c;
  }

 private:
  static Six row(const MultiposInput& in, std::size_t i) {
    Six x;
    x << in.gyro[i], in.accel[i];
    return x;
  }
  std::size_t n_, h_, w_;
  Six mean_;
  std::vector<Six> s1_, s2_;
};

// The q-quantile of channel ch's variance over the windows centred at cs, over χ²'s own.
double level_at(const Windows& W, const std::vector<std::size_t>& cs, int ch, double q) {
  std::vector<double> v;
  v.reserve(cs.size());
  for (std::size_t c : cs) v.push_back(W.var(c)(ch));
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * double(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return std::max(v[k], 0.0) / chi2_per_dof(q, double(W.w() - 1));
}

// σ per sample of each triad (its largest axis) over the windows centred at cs.
void triad_sigmas(const Windows& W, const std::vector<std::size_t>& cs, double q, double sigma[2]) {
  for (int triad = 0; triad < 2; ++triad) {
    sigma[triad] = 0;
    for (int ax = 0; ax < 3; ++ax) sigma[triad] = std::max(sigma[triad], std::sqrt(level_at(W, cs, 3 * triad + ax, q)));
  }
}

Six limit_of(const double sigma[2], double factor) {
  Six l;
  l << Vec3::Constant(sigma[0] * sigma[0] * factor), Vec3::Constant(sigma[1] * sigma[1] * factor);
  return l;
}

std::string fixed1(double v) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(1);
  os << v;
  return os.str();
}

// The output's quantisation step of each triad (its coarsest axis): the smallest non-zero change
// between consecutive samples; below it a still unit's noise is the rounding's, step/√12.
void quantisation_floor(const MultiposInput& in, double floor[2]) {
  for (int t = 0; t < 2; ++t) {
    const std::vector<Vec3>& v = t ? in.accel : in.gyro;
    double coarsest = 0;
    for (int ax = 0; ax < 3; ++ax) {
      double step = std::numeric_limits<double>::infinity();
      for (std::size_t i = 1; i < v.size(); ++i)
        if (const double d = std::abs(v[i](ax) - v[i - 1](ax)); d > 0 && d < step) step = d;
      if (std::isfinite(step)) coarsest = std::max(coarsest, step);
    }
    floor[t] = coarsest / std::sqrt(12.0);
  }
}

// The noise of both triads: the quietest windows', then the opening still interval's when there is
// one; never below the output's quantisation.
void learn_noise(const MultiposInput& in, const MultiposOptions& opt, const Windows& W, double factor, NoiseLevel lv[2]) {
  const std::vector<std::size_t> tiles = W.tiles();
  double quiet[2], floor[2];
  triad_sigmas(W, tiles, opt.quiet_fraction, quiet);
  quantisation_floor(in, floor);
  for (int t = 0; t < 2; ++t)
    if (quiet[t] > 0) quiet[t] = std::max(quiet[t], floor[t]);
  std::ostringstream qs;
  qs << "quietest " << std::lround(100 * opt.quiet_fraction) << " % of the " << opt.window_s << "-s windows";
  for (int t = 0; t < 2; ++t) {
    lv[t].quiet_sigma = lv[t].used_sigma = quiet[t];
    lv[t].source = qs.str();
  }
  if (!(quiet[0] > 0 && quiet[1] > 0)) return;  // the caller refuses a triad without noise
  const Six limit = limit_of(quiet, factor);
  std::vector<std::size_t> opening;
  for (std::size_t c : tiles) {
    if (!(W.var(c).array() <= limit.array()).all()) break;
    opening.push_back(c);
  }
  if (opening.size() < 2) return;
  opening.pop_back();  // the last still window may touch the first motion
  const double t0 = in.t.front(), t1 = in.t[opening.back() + W.h()];
  if (t1 - t0 < opt.min_opening_s) return;
  double open[2];
  triad_sigmas(W, opening, 0.5, open);
  for (int t = 0; t < 2; ++t) {
    if (!(open[t] > 0)) return;
    lv[t].used_sigma = std::max(open[t], floor[t]);
    lv[t].source = "opening still interval " + fixed1(t0) + "–" + fixed1(t1) + " s";
  }
}

// Marks the centres of still windows: quiet variance, and a mean rate that is the gyro bias.
std::vector<char> still_centres(const MultiposInput& in, const Windows& W, const Six& limit, double gyro_sigma) {
  const std::size_t n = W.n(), h = W.h();
  std::vector<char> quiet(n, 0);
  for (std::size_t c = h; c + h < n; ++c) quiet[c] = (W.var(c).array() <= limit.array()).all();
  std::vector<double> m[3];
  for (std::size_t c = h; c + h < n; c += h)
    if (quiet[c]) {
      const Vec3 v = W.gyro_mean(c);
      for (int i = 0; i < 3; ++i) m[i].push_back(v(i));
    }
  if (m[0].empty()) return quiet;
  // Per axis: the median of the quiet windows' means is the bias; their robust spread (1.4826·MAD:
  // the noise of a window mean, correlated noise and the bias's wander between poses together) sets
  // the tolerance, 5× it but no less than 5σ/√n, plus 3× the bias stability.
  const double stability = in.gyro_bias_stability > 0 ? in.gyro_bias_stability : kWideGyroBiasStability;
  Vec3 bias, tol;
  for (int i = 0; i < 3; ++i) {
    const auto mid = m[i].begin() + static_cast<long>(m[i].size() / 2);
    std::nth_element(m[i].begin(), mid, m[i].end());
    bias(i) = *mid;
    for (double& v : m[i]) v = std::abs(v - bias(i));
    std::nth_element(m[i].begin(), mid, m[i].end());
    const double spread = std::max(1.4826 * *mid, gyro_sigma / std::sqrt(double(W.w())));
    tol(i) = std::max(5 * spread + 3 * stability, 0.05 * units::kDeg);
  }
  for (std::size_t c = h; c + h < n; ++c)
    if (quiet[c] && ((W.gyro_mean(c) - bias).cwiseAbs().array() > tol.array()).any()) quiet[c] = 0;
  return quiet;
}

// The mean and spread of v over [i, j).
void mean_std(const std::vector<Vec3>& v, std::size_t i, std::size_t j, Vec3& mean, Vec3& sd) {
  Vec3 s = Vec3::Zero(), s2 = Vec3::Zero();
  for (std::size_t k = i; k < j; ++k) s += v[k];
  const double m = double(j - i);
  mean = s / m;
  for (std::size_t k = i; k < j; ++k) s2 += (v[k] - mean).cwiseAbs2();
  sd = m > 1 ? Vec3((s2 / (m - 1)).cwiseSqrt()) : Vec3::Zero();
}

StaticInterval interval_of(const MultiposInput& in, std::size_t a, std::size_t b, std::size_t c0, std::size_t c1) {
  StaticInterval s;
  s.i0 = a;
  s.i1 = b;
  s.c0 = c0;
  s.c1 = c1;
  s.t0 = in.t[a];
  s.t1 = in.t[b - 1];
  mean_std(in.accel, a, b, s.f_mean, s.f_std);
  mean_std(in.gyro, c0, c1, s.w_mean, s.w_std);
  return s;
}

// Runs of still centres → the samples their windows cover; covers that touch are split half-way.
std::vector<StaticInterval> poses_of(const MultiposInput& in, const std::vector<char>& still, std::size_t h, std::size_t min_len,
                                     std::vector<double>& too_short_s) {
  const std::size_t n = still.size();
  std::vector<std::pair<std::size_t, std::size_t>> runs;  // [first, last] still centre
  for (std::size_t i = 0; i < n;) {
    if (!still[i]) { ++i; continue; }
    std::size_t j = i;
    while (j + 1 < n && still[j + 1]) ++j;
    runs.emplace_back(i, j);
    i = j + 1;
  }
  std::vector<StaticInterval> out;
  for (std::size_t r = 0; r < runs.size(); ++r) {
    std::size_t a = runs[r].first - h, b = runs[r].second + h + 1;  // cover [a, b)
    if (r > 0 && runs[r - 1].second + 2 * h + 1 > runs[r].first) a = (runs[r - 1].second + runs[r].first + 1) / 2;
    if (r + 1 < runs.size() && runs[r].second + 2 * h + 1 > runs[r + 1].first) b = (runs[r].second + runs[r + 1].first + 1) / 2;
    if (b > a && b - a >= min_len) out.push_back(interval_of(in, a, b, runs[r].first, runs[r].second + 1));
    else if (b > a) too_short_s.push_back(double(b - a) / in.rate_hz);
  }
  return out;
}

}  // namespace

std::vector<StaticInterval> detect_statics(const MultiposInput& in, const MultiposOptions& opt, NoiseLevel* gyro_noise,
                                           NoiseLevel* accel_noise, double* threshold_factor, std::size_t* window,
                                           std::vector<double>* too_short_s) {
  const std::size_t n = in.t.size();
  if (in.gyro.size() != n || in.accel.size() != n) throw std::invalid_argument("multipos: series of unequal length");
  if (!(in.rate_hz > 0)) throw std::invalid_argument("multipos: the sample rate must be positive");
  const std::size_t h = std::max<std::size_t>(3, static_cast<std::size_t>(std::lround(0.5 * opt.window_s * in.rate_hz)));
  const Windows W(in, h);
  if (n < 10 * W.w())
    throw MultiposRefusal("the recording is too short for the static detector: " + std::to_string(n) + " samples, at least " +
                          std::to_string(10 * W.w()) + " needed");
  const double factor = opt.margin * chi2_per_dof(1 - opt.alpha, double(W.w() - 1));
  NoiseLevel lv[2];
  learn_noise(in, opt, W, factor, lv);
  const double density[2] = {in.gyro_density, in.accel_density};
  for (int t = 0; t < 2; ++t) {
    if (!(lv[t].used_sigma > 0))
      throw MultiposRefusal(std::string("the ") + (t ? "accelerometer" : "gyro") + " output does not vary at all on the " +
                            lv[t].source + ": no noise to set the static threshold from (a constant or stuck output)");
    lv[t].class_sigma = density[t] * std::sqrt(in.rate_hz);
    lv[t].differs = lv[t].class_sigma > 0 && (lv[t].used_sigma > 2 * lv[t].class_sigma || lv[t].used_sigma < 0.5 * lv[t].class_sigma);
  }
  const double used[2] = {lv[0].used_sigma, lv[1].used_sigma};
  const std::vector<char> still = still_centres(in, W, limit_of(used, factor), used[0]);
  const std::size_t min_len = std::max<std::size_t>(W.w(), static_cast<std::size_t>(std::lround(opt.min_static_s * in.rate_hz)));
  std::vector<double> short_s;
  std::vector<StaticInterval> out = poses_of(in, still, h, min_len, short_s);
  if (too_short_s) *too_short_s = short_s;
  for (auto& s : out) s.g_residual_raw = s.f_mean.norm() - in.gravity;
  if (gyro_noise) *gyro_noise = lv[0];
  if (accel_noise) *accel_noise = lv[1];
  if (threshold_factor) *threshold_factor = factor;
  if (window) *window = W.w();
  return out;
}

}  // namespace calbench::multipos
