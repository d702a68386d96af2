#include "calibration/identification/sample_timing.hpp"

#include <algorithm>
#include <cmath>

namespace calbench::identification {

namespace {
constexpr std::size_t kMinRun = 32;  // a shorter run (cut by a gap) is not fitted

// The median of v (reordered in place).
double median_in_place(std::vector<double>& v) {
  if (v.empty()) return 0;
  const std::size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  return v[m];
}
}  // namespace

void SampleTimingEstimator::add(double t, const Vec3& w, const Vec3& f) {
  ++s_.rows;
  if (s_.rows == 1) t_first_ = t;
  t_last_ = t;
  const bool repeat = have_prev_ && w == w_prev_ && f == f_prev_;
  w_prev_ = w;
  f_prev_ = f;
  have_prev_ = true;
  if (repeat) {
    ++s_.repeated;
    return;
  }
  ++distinct_;
  if (!run_.empty()) {
    const double dt = t - run_.back();
    // A gap (a step over 5× the previous one) ends the run: the line does not reach across it.
    if (!(dt > 0) || (last_dt_ > 0 && dt > 5 * last_dt_)) close_run();
    last_dt_ = dt > 0 ? dt : last_dt_;
  }
  run_.push_back(t);
  if (run_.size() == kRun) close_run();
}

void SampleTimingEstimator::close_run() {
  const std::size_t n = run_.size();
  if (n >= kMinRun) {
    // Least-squares line t = a + b·k over the run, about its middle (well conditioned).
    const double k0 = 0.5 * static_cast<double>(n - 1);
    double st = 0, skt = 0, skk = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const double x = static_cast<double>(k) - k0;
      st += run_[k];
      skt += x * (run_[k] - run_[0]);
      skk += x * x;
    }
    const double a = st / static_cast<double>(n), b = skt / skk;
    std::vector<double>& r = scratch_r_;
    r.resize(n);
    for (std::size_t k = 0; k < n; ++k) r[k] = run_[k] - (a + b * (static_cast<double>(k) - k0));
    // The residuals' σ, a stamp far off (beyond 5 robust σ: a stall, a skipped read) left out.
    scratch_m_ = r;
    const double med = median_in_place(scratch_m_);
    std::vector<double>& dev = scratch_dev_;
    dev.resize(n);
    for (std::size_t k = 0; k < n; ++k) dev[k] = std::abs(r[k] - med);
    const double cut = 5 * 1.4826 * median_in_place(dev);
    std::vector<double>& kept = scratch_m_;  // in the run's order (never empty: the median is kept)
    kept.clear();
    for (double x : r)
      if (std::abs(x - med) <= cut) kept.push_back(x);
    const std::size_t m = kept.size();
    double ss = 0, mean = 0;
    for (double x : kept) mean += x;
    mean /= static_cast<double>(m);
    for (double x : kept) ss += (x - mean) * (x - mean);
    run_sigma_.push_back(m > 2 ? std::sqrt(ss / static_cast<double>(m - 2)) : 0.0);
    // The earliest kept stamps: the 1st percentile of the kept residuals (at least the 2nd smallest).
    const std::size_t q = std::min(m - 1, std::max<std::size_t>(1, m / 100));
    std::nth_element(kept.begin(), kept.begin() + static_cast<std::ptrdiff_t>(q), kept.end());
    run_late_.push_back(mean - kept[q]);
  }
  run_.clear();
}

SampleTiming SampleTimingEstimator::result() const {
  SampleTiming s = s_;
  SampleTimingEstimator tail = *this;  // the open run counts too
  tail.close_run();
  s.runs = tail.run_sigma_.size();
  const double span = t_last_ - t_first_;
  if (span > 0 && s.rows > 1) {
    s.read_rate_hz = static_cast<double>(s.rows - 1) / span;
    s.distinct_rate_hz = static_cast<double>(distinct_ - 1) / span;
  }
  const double sigma = median_in_place(tail.run_sigma_);
  s.regular = !(sigma >= kFloorS);
  s.sigma_s = s.regular ? 0.0 : sigma;
  s.lateness_s = s.regular ? 0.0 : std::max(0.0, median_in_place(tail.run_late_));
  return s;
}

}  // namespace calbench::identification
