#include "calibration/bench_blocks.hpp"

#include <cmath>

namespace calbench {

void BenchBlockBuilder::add(double t, double dt, const Vec3& gyro, const Vec3& accel, const Vec3& w_ref,
                            const Vec3& f_ref, int step, double temp_c, bool saturated) {
  if (open_) {
    const bool gap = (t - t_last_) > 1.5 * std::max(dt, dt_last_) + 1e-9;
    if (step != cur_.step || gap || (t - t0_) >= block_s_ - 0.5 * dt) close();
  }
  t_last_ = t;
  dt_last_ = dt;
  if (step < 0) return;
  ++samples_;
  if (!open_) {
    open_ = true;
    cur_ = BenchBlock{};
    cur_.step = step;
    t0_ = t - dt;
    rg_mean_.setZero();
    ra_mean_.setZero();
    temp_sum_ = 0;
    temp_n_ = 0;
  }
  const int n = ++cur_.n;
  cur_.gyro += (gyro - cur_.gyro) / n;
  cur_.accel += (accel - cur_.accel) / n;
  cur_.w += (w_ref - cur_.w) / n;
  cur_.f += (f_ref - cur_.f) / n;
  const Vec3 rg = gyro - w_ref, ra = accel - f_ref;
  const Vec3 dg = rg - rg_mean_, da = ra - ra_mean_;
  rg_mean_ += dg / n;
  ra_mean_ += da / n;
  cur_.gyro_ss += dg.cwiseProduct(rg - rg_mean_);
  cur_.accel_ss += da.cwiseProduct(ra - ra_mean_);
  if (std::isfinite(temp_c)) {
    temp_sum_ += temp_c;
    ++temp_n_;
  }
  cur_.saturated = cur_.saturated || saturated;
  cur_.duration = t - t0_;
  cur_.t_mid = t0_ + 0.5 * cur_.duration;
}

void BenchBlockBuilder::close() {
  if (!open_) return;
  open_ = false;
  cur_.temp_c = temp_n_ > 0 ? temp_sum_ / temp_n_ : std::numeric_limits<double>::quiet_NaN();
  if (cur_.n >= 2) blocks_.push_back(cur_);
}

std::vector<BenchBlock> BenchBlockBuilder::finish() {
  close();
  return std::move(blocks_);
}

}  // namespace calbench
