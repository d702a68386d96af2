// A land-vehicle route as a sequence of manoeuvres, and its exact kinematics: forward speed,
// its rate, body attitude (roll, pitch, yaw of the forward-right-down body in NED) and the
// attitude rates, all analytic in time (raised-cosine transitions and a smoothstep lane change,
// so yaw acceleration, specific force and angular rate — including the suspension's roll and
// pitch rates — are continuous; the angular acceleration has at most finite steps). The vehicle does not slip: its velocity is along the body x axis.
// Body roll follows the lateral acceleration and pitch the longitudinal one (suspension), which
// is what makes the horizontal gyro axes move on a real car.
#pragma once
#include <string>
#include <vector>

#include "common/sensor_model.hpp"

namespace calbench::drivesim {

enum class SegmentKind { accelerate, cruise, turn, stop, climb, lane_change };
const char* segment_name(SegmentKind k);

struct Segment {
  SegmentKind kind = SegmentKind::cruise;
  double duration_s = 0;  // cruise, stop (standstill time), climb (total), lane_change
  double to_speed = 0;    // accelerate: target speed, m/s (lower = braking)
  double angle = 0;       // turn: heading change, rad (+ = right/clockwise)
  double radius = 0;      // turn: m
  double grade = 0;       // climb: road pitch, rad (+ = up; negative = descend)
  double ramp_s = 0;      // climb/turn transition time (0 = default)
  double width = 0;       // lane_change: lateral offset, m (+ = right)
  int line = 0;           // line in the route file, for messages
};

struct Route {
  std::string name;
  std::string description;
  double lat = 0, lon = 0, h = 0;  // start, rad, rad, m
  double heading = 0;              // start yaw, rad
  double roll_per_lat_accel = 0.006;   // body roll per lateral acceleration, rad/(m/s²)
  double pitch_per_long_accel = 0.004; // body pitch per longitudinal acceleration, rad/(m/s²)
  std::vector<Segment> segments;
};

struct Motion {
  double v = 0, v_dot = 0;     // forward speed, m/s, and its rate
  Vec3 rpy = Vec3::Zero();     // roll, pitch, yaw, rad
  Vec3 rpy_dot = Vec3::Zero(); // their rates, rad/s
};

// Segments laid out in time. Throws std::invalid_argument (with the segment's line) for a
// manoeuvre that is impossible (turn or lane change at standstill, non-positive durations, …).
class RouteProfile {
 public:
  explicit RouteProfile(const Route& r);
  double duration() const { return total_; }
  Motion at(double t) const;
  const Route& route() const { return route_; }

 private:
  struct Laid {
    Segment s;
    double t0 = 0, T = 0, v0 = 0, v1 = 0, psi0 = 0;
    double brake_T = 0;  // stop: braking time
    double rate = 0;     // turn: peak yaw rate; lane change: heading scale a (δψ = a·[x(1−x)]³)
    double ramp = 0;     // transition time
  };
  Route route_;
  std::vector<Laid> laid_;
  double total_ = 0;
};

}  // namespace calbench::drivesim
