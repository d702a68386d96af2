// Motion of one table axis as a sequence of constant-acceleration segments: the nominal
// trajectory the table controller follows (used by the bench simulator and the table emulator).
#pragma once
#include <vector>

namespace calbench {

struct AxisState {
  double angle = 0;  // rad (unwrapped)
  double rate = 0;   // rad/s
  double accel = 0;  // rad/s²
};

class AxisProfile {
 public:
  explicit AxisProfile(double t0 = 0, double angle0 = 0) : t_end_(t0), end_{angle0, 0, 0} {}
  // Keep the current rate for `dur` seconds.
  void hold(double dur);
  // Change rate to `rate` with |acceleration| = max_accel.
  void ramp_to(double rate, double max_accel);
  // Move by `delta` from rest to rest with a trapezoidal (or triangular) rate profile.
  void slew(double delta, double max_rate, double max_accel);
  // Extend with a hold until time t (no-op if already past).
  void hold_until(double t);

  AxisState at(double t) const;
  double end_time() const { return t_end_; }
  AxisState end_state() const { return end_; }

 private:
  struct Segment { double t0, dur, angle0, rate0, accel; };
  void push(double dur, double accel);
  std::vector<Segment> segs_;
  double t_end_;
  AxisState end_;
  mutable std::size_t cursor_ = 0;  // last segment used: lookups are mostly monotonic in t
};

// Time to change rate from r0 to r1 at max_accel.
double move_duration(double r0, double r1, double max_accel);
// Time for a rest-to-rest move of `delta` with rate and acceleration limits.
double slew_duration(double delta, double max_rate, double max_accel);

}  // namespace calbench
