#include "calibration/identification/standstill_noise.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "calibration/identification/allan.hpp"

namespace calbench::identification {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kMinWindowSamples = 8;

double class_level(const NoiseSpec& n, int axis) { return axis < 3 ? n.gyro.white_density : n.accel.white_density; }
}  // namespace

StandstillDetector::StandstillDetector(const NoiseSpec& cls, StandstillConfig cfg) : cls_(cls), cfg_(cfg) {}

void StandstillDetector::add(double t, const Vec3& gyro, const Vec3& accel) {
  if (std::isfinite(last_t_)) {
    const double step = t - last_t_;
    const double prev = last_step_ > 0 ? last_step_ : step;
    if (!(step > 0) || step > 5 * prev) {  // a gap or a step back: neither window nor standstill spans it
      wt_.clear();
      for (auto& v : wy_) v.clear();
      close_standstill();
    } else {
      last_step_ = step;
    }
  }
  last_t_ = t;
  wt_.push_back(t);
  for (int i = 0; i < 3; ++i) {
    wy_[static_cast<std::size_t>(i)].push_back(gyro(i));
    wy_[static_cast<std::size_t>(i + 3)].push_back(accel(i));
  }
  if (wt_.size() >= kMinWindowSamples && wt_.back() - wt_.front() >= cfg_.window_s) close_window();
}

void StandstillDetector::close_window() {
  const std::size_t n = wt_.size();
  const double dt = (wt_.back() - wt_.front()) / static_cast<double>(n - 1);
  bool still = dt > 0;
  for (std::size_t a = 0; a < 6 && still; ++a) {
    const auto& y = wy_[a];
    double mean = 0;
    for (double v : y) mean += v;
    mean /= static_cast<double>(n);
    double ss = 0;
    for (double v : y) ss += (v - mean) * (v - mean);
    const double sd = std::sqrt(ss / static_cast<double>(n - 1));
    const double limit = cfg_.ratio * class_level(cls_, static_cast<int>(a)) / std::sqrt(dt);
    still = sd <= limit;
  }
  if (still) {
    if (!open_) {
      cur_ = Standstill{};
      cur_.t0 = wt_.front();
      cur_n_ = 0;
      cur_dt_sum_ = 0;
      open_ = true;
    } else {
      cur_dt_sum_ += wt_.front() - cur_.t1;  // the step between the last window and this one
    }
    cur_.t1 = wt_.back();
    cur_dt_sum_ += wt_.back() - wt_.front();
    for (std::size_t a = 0; a < 6; ++a) {
      auto& dst = cur_.y[a];
      const std::size_t room = cfg_.max_samples > dst.size() ? cfg_.max_samples - dst.size() : 0;
      dst.insert(dst.end(), wy_[a].begin(), wy_[a].begin() + static_cast<std::ptrdiff_t>(std::min(room, n)));
    }
    cur_n_ += n;
  } else {
    close_standstill();
  }
  wt_.clear();
  for (auto& v : wy_) v.clear();
}

void StandstillDetector::close_standstill() {
  if (!open_) return;
  open_ = false;
  if (cur_.t1 - cur_.t0 < cfg_.min_duration_s || cur_n_ < 2) return;
  cur_.dt = cur_dt_sum_ / static_cast<double>(cur_n_ - 1);
  found_.push_back(std::move(cur_));
  cur_ = Standstill{};
}

void StandstillDetector::finish() {
  // A last window shorter than window_s is not judged; the open standstill ends where it ended.
  wt_.clear();
  for (auto& v : wy_) v.clear();
  close_standstill();
}

NoiseMeasurement measure_white_noise(const std::vector<Standstill>& s, const NoiseSpec& cls, double factor) {
  NoiseMeasurement m;
  m.factor = factor;
  for (int a = 0; a < 6; ++a) m.cls.v[static_cast<std::size_t>(a)] = class_level(cls, a);
  std::array<double, 6> sum{}, weight{};
  for (const Standstill& st : s) {
    StandstillNoise r;
    r.t0 = st.t0;
    r.t1 = st.t1;
    r.dt = st.dt;
    r.samples = st.y[0].size();
    if (r.samples < 8) continue;
    for (std::size_t a = 0; a < 6; ++a) {
      // Allan deviation at τ = dt only (max_m = 1): white level N = σ(dt)·√dt.
      const auto pts = allan_deviation(st.y[a], st.dt, 1);
      const double N = pts.empty() ? kNaN : pts.front().adev * std::sqrt(st.dt);
      r.level.v[a] = N;
      if (std::isfinite(N)) {
        const double w = static_cast<double>(r.samples - 1);
        sum[a] += w * N * N;
        weight[a] += w;
      }
    }
    m.standstills.push_back(r);
  }
  m.measured = weight[0] > 0;
  for (std::size_t a = 0; a < 6; ++a) {
    m.level.v[a] = weight[a] > 0 ? std::sqrt(sum[a] / weight[a]) : kNaN;
    m.ratio.v[a] = m.level.v[a] / m.cls.v[a];
  }
  for (std::size_t k = 0; k < 2; ++k) {
    m.used[k] = m.cls.v[3 * k];
    if (!m.measured) continue;
    double top = 0;
    bool differs = false;
    for (std::size_t a = 3 * k; a < 3 * k + 3; ++a) {
      const double r = m.ratio.v[a];
      if (std::isfinite(r) && (r > factor || r < 1.0 / factor)) differs = true;
      if (!(m.level.v[a] > 0)) m.zero[k] = true;
      top = std::max(top, m.level.v[a]);
    }
    m.differs[k] = differs && !m.zero[k];
    if (m.differs[k]) m.used[k] = top;
  }
  return m;
}

NoiseSpec apply_measured_noise(const NoiseSpec& cls, const NoiseMeasurement& m) {
  NoiseSpec n = cls;
  if (m.differs[0]) n.gyro.white_density = m.used[0];
  if (m.differs[1]) n.accel.white_density = m.used[1];
  return n;
}

}  // namespace calbench::identification
