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
  dof += x.dof;
}

bool AdaptiveNoise::raise(const Window& b) {
  // Covariance matching: the process-noise part of S scaled so that the predicted innovation
  // power equals the actual one over the block.
  const double s = b.trHPH > 0 ? (b.nu2 - b.trR) / b.trHPH : cfg_.max_step;
  if (!(s > 1)) return false;  // R alone explains the excess: nothing for Q to do
  const double q = std::min(cfg_.max_scale, q_ * std::min(s, cfg_.max_step));
  if (q <= q_) return false;
  q_ = q;
  q_max_ = std::max(q_max_, q_);
  ++increases_;
  return true;
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
    return raise(b);
  }
  // Blocks, not a sliding window: each innovation is tested once at the block's end, so the
  // false-alarm rate of the test is that of one block (a sliding window would test every epoch again).
  if (w.s.back().t - w.s.front().t < cfg_.window_s) return false;
  const double dt = last_t_ > -1e299 ? std::max(0.0, x.t - last_t_) : 0.0;
  last_t_ = x.t;
  const Window b = w;
  w.clear();
  if (b.nis > qc::chi2_quantile(b.dof, cfg_.z_trigger)) return raise(b);
  if (q_ > 1 && b.nis <= b.dof && dt > 0) {  // consistent, and not even by excess: relax
    const double q = std::max(1.0, q_ * std::exp(-dt / cfg_.relax_s));
    const bool changed = q != q_;
    q_ = q;
    return changed;
  }
  return false;
}

}  // namespace calbench::inmotion
