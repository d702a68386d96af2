#include "common/table_motion.hpp"

#include <algorithm>
#include <cmath>

namespace calbench {

void AxisProfile::push(double dur, double accel) {
  if (dur <= 0) return;
  segs_.push_back({t_end_, dur, end_.angle, end_.rate, accel});
  end_.angle += end_.rate * dur + 0.5 * accel * dur * dur;
  end_.rate += accel * dur;
  end_.accel = 0;
  t_end_ += dur;
}

void AxisProfile::hold(double dur) { push(dur, 0.0); }

void AxisProfile::hold_until(double t) {
  if (t > t_end_) push(t - t_end_, 0.0);
}

void AxisProfile::ramp_to(double rate, double max_accel) {
  const double d = rate - end_.rate;
  if (d == 0) return;
  const double a = std::copysign(max_accel, d);
  const double target = rate;
  push(d / a, a);
  end_.rate = target;  // exact, no rounding drift
}

void AxisProfile::slew(double delta, double max_rate, double max_accel) {
  if (delta == 0) return;
  const double s = delta > 0 ? 1.0 : -1.0;
  const double dist = std::abs(delta);
  const double target = end_.angle + delta;
  double t_acc = max_rate / max_accel;
  double v = max_rate;
  if (max_accel * t_acc * t_acc > dist) {  // triangular profile
    t_acc = std::sqrt(dist / max_accel);
    v = max_accel * t_acc;
  }
  const double t_cruise = (dist - max_accel * t_acc * t_acc) / v;
  push(t_acc, s * max_accel);
  push(t_cruise, 0.0);
  push(t_acc, -s * max_accel);
  end_.angle = target;
  end_.rate = 0;
}

AxisState AxisProfile::at(double t) const {
  if (segs_.empty() || t >= t_end_) {
    const double dt = t - t_end_;
    return {end_.angle + end_.rate * std::max(dt, 0.0), end_.rate, 0.0};
  }
  if (cursor_ >= segs_.size() || segs_[cursor_].t0 > t) cursor_ = 0;
  while (cursor_ + 1 < segs_.size() && segs_[cursor_ + 1].t0 <= t) ++cursor_;
  const Segment& g = segs_[cursor_];
  const double dt = std::max(t - g.t0, 0.0);
  return {g.angle0 + g.rate0 * dt + 0.5 * g.accel * dt * dt, g.rate0 + g.accel * dt, g.accel};
}

double move_duration(double r0, double r1, double max_accel) { return std::abs(r1 - r0) / max_accel; }

double slew_duration(double delta, double max_rate, double max_accel) {
  const double dist = std::abs(delta);
  if (dist == 0) return 0;
  const double t_acc = max_rate / max_accel;
  if (max_accel * t_acc * t_acc > dist) return 2 * std::sqrt(dist / max_accel);
  return 2 * t_acc + (dist - max_accel * t_acc * t_acc) / max_rate;
}

}  // namespace calbench
