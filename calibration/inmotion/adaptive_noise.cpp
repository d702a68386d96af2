#include "calibration/inmotion/adaptive_noise.hpp"

#include <algorithm>
#include <cmath>

#include "calibration/qc/nis_test.hpp"

namespace calbench::inmotion {

void AdaptiveNoise::Window::push(const AdaptiveSample& x) {
  s.push_back(x);
  nis += x.nis;
  nu2 += x.nu2;
  trR += x.trR;
  trHPH += x.trHPH;
  speed += x.speed;
  turn += std::abs(x.turn_rate);
  accel += x.accel;
  dof += x.dof;
}

namespace {
// Covariance matching: the factor on the process-noise part of S that makes the predicted
// innovation power equal the actual one over the block.
double matching_factor(double nu2, double trR, double trHPH, double none) { return trHPH > 0 ? (nu2 - trR) / trHPH : none; }
}  // namespace

AdaptiveEvent AdaptiveNoise::event(const Window& b, int type, double from, double to) {
  const double n = static_cast<double>(std::max<std::size_t>(b.s.size(), 1));
  return AdaptiveEvent{b.s.back().t, type, from, to, b.nis / b.dof, b.speed / n, b.turn / n, b.accel / n};
}

void AdaptiveNoise::close_all_blocks() {
  for (Window& w : w_) w.clear();
}

bool AdaptiveNoise::raise(const Window& b, int type) {
  const double s = matching_factor(b.nu2, b.trR, b.trHPH, cfg_.max_step);
  if (!(s > 1)) return false;  // R alone explains the excess: nothing for Q to do
  // At most the block's NIS ratio: where R dominates S, a modest excess (NIS/dof 2: fixes whose σ
  // is optimistic as much as an IMU noisier than assumed) would otherwise read as ×36 on the IMU.
  const double step = std::min({s, b.nis / b.dof, cfg_.max_step});
  if (!(step > 1)) return false;
  const double q = std::min(cfg_.max_scale, q_ * step);
  if (q <= q_) return false;
  events_.push_back(event(b, type, q_, q));
  q_ = q;
  q_max_ = std::max(q_max_, q_);
  ++increases_;
  close_all_blocks();  // their innovations were predicted under the old q
  return true;
}

bool AdaptiveNoise::lower(const Window& b, int type) {
  if (!(q_ > 1) || b.nis > b.dof) return false;
  const double s = matching_factor(b.nu2, b.trR, b.trHPH, 1.0);
  const double step = std::clamp(std::isfinite(s) ? s : 1.0, cfg_.min_step_down, cfg_.max_step_down);
  const double q = std::max(1.0, q_ * step);
  events_.push_back(event(b, type, q_, q));
  q_ = q;
  ++decreases_;
  return true;
}

const AdaptiveEvent* AdaptiveNoise::above_fail_since() const {
  if (!(q_ > kFailScale)) return nullptr;
  const AdaptiveEvent* since = nullptr;
  for (const AdaptiveEvent& e : events_) {
    if (e.q_to > kFailScale && !(e.q_from > kFailScale)) since = &e;
    if (!(e.q_to > kFailScale)) since = nullptr;
  }
  return since;
}

bool AdaptiveNoise::add(int type, const AdaptiveSample& x) {
  if (!cfg_.enabled || type < 0 || type >= kTypes || !std::isfinite(x.nis)) return false;
  Window& w = w_[type];
  w.push(x);
  if (static_cast<int>(w.s.size()) < cfg_.min_epochs) return false;
  // Within a block, every epoch: a block already far beyond its χ² (p = 1e-7 per test, about 1e-5
  // per block of 100 epochs, Bonferroni) is decided at once, so that a run of rejections opens the
  // gate within a few epochs instead of waiting for the block's end.
  if (static_cast<int>(w.s.size()) >= cfg_.min_epochs_early && w.nis > qc::chi2_quantile(w.dof, cfg_.z_early)) {
    const Window b = w;
    w.clear();
    return raise(b, type);
  }
  // Blocks, not a sliding window: each innovation is tested once at the block's end, so the
  // false-alarm rate of the test is that of one block (a sliding window would test every epoch again).
  if (w.s.back().t - w.s.front().t < cfg_.window_s) return false;
  const Window b = w;
  w.clear();
  if (b.nis > qc::chi2_quantile(b.dof, cfg_.z_trigger)) return raise(b, type);
  return lower(b, type);  // consistent, and not even by excess: heal
}

}  // namespace calbench::inmotion
