// A GNSS receiver's velocity that describes the motion some time before its stamp (issue 53): a
// velocity formed from the positions over the last fix interval, or filtered in the receiver,
// lags the position it is stamped with. The real walk's 4-Hz RTK velocities describe the motion
// 0.125 s before their stamps (half the fix interval; identification/gnss_velocity_latency.hpp
// measures it from gnss.csv alone). Walking changes the velocity by ±2 m/s² at every step, so
// 0.125 s is 0.2 m/s of misfit against fixes of σ 0.05 m/s: the innovations the adaptive noise
// then bought with ×10⁵ on the IMU's noise.
//
// The fix is compared with the INS velocity at the time it describes: v̂(t_fix − τ) =
// v̂(t) − [A(t) − A(t_fix − τ)], A the running sum of the INS's own velocity increments (the
// strapdown steps; the filter's feedback does not enter it, so the difference is the motion over
// the interval). The error state is taken as the same over τ (≤ 0.5 s: its change is second
// order), so the observation's Jacobian is eq 14's.
#pragma once
#include <deque>

#include "common/sensor_model.hpp"

namespace calbench::inmotion {

class VelocityHistory {
 public:
  static constexpr double kKeepS = 1.5;  // longest latency it can serve (the option is bounded below it)
  // One strapdown step ending at t with its velocity change (NED).
  void push(double t, const Vec3& dv);
  // A(t1) − A(t0) for t0 ≤ t1 within the kept history (interpolated linearly within a step; an
  // instant before the history clamps to its start).
  Vec3 change(double t0, double t1) const;

 private:
  Vec3 sum_at(double t) const;
  struct Node {
    double t;
    Vec3 A;
  };
  std::deque<Node> h_;
  Vec3 A_ = Vec3::Zero();
};

}  // namespace calbench::inmotion
