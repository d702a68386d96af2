#include "calibration/inmotion/velocity_latency.hpp"

#include <algorithm>

namespace calbench::inmotion {

void VelocityHistory::push(double t, const Vec3& dv) {
  A_ += dv;
  h_.push_back(Node{t, A_});
  while (h_.size() > 2 && h_[1].t < t - kKeepS) h_.pop_front();
}

Vec3 VelocityHistory::sum_at(double t) const {
  if (h_.empty()) return A_;
  if (t <= h_.front().t) return h_.front().A;
  if (t >= h_.back().t) return h_.back().A;
  const auto it = std::lower_bound(h_.begin(), h_.end(), t, [](const Node& n, double x) { return n.t < x; });
  const Node& b = *it;
  const Node& a = *(it - 1);
  const double u = (t - a.t) / (b.t - a.t);
  return a.A + u * (b.A - a.A);
}

Vec3 VelocityHistory::change(double t0, double t1) const { return sum_at(t1) - sum_at(t0); }

}  // namespace calbench::inmotion
