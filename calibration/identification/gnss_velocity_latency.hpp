// How long before its stamp a GNSS velocity describes the motion, measured from the fixes alone
// (issue 53; applied by inmotion/velocity_latency.hpp). A receiver that forms its velocity from
// the positions of the last fix interval, or filters it, stamps it later than the motion it
// describes; RTK positions of centimetres show it: their differences over consecutive fixes are
// the mean velocity between the two, stamped at the midpoint.
//
// Measurement: for each candidate latency τ (−0.5 … 0.5 s in steps of 5 ms) the horizontal RMS
// difference between each fix's velocity and the position-difference velocity interpolated at
// t − τ, over the fixes with a velocity whose neighbours are at most 1.5 fix intervals away. The
// smallest RMS wins; it is taken only when it is at most 0.7× the RMS at τ = 0 (the lag is the
// larger part of the difference) and the fixes are precise enough to tell: the position
// differences' own noise, √2·σ_h / Δt, below half the RMS at τ = 0 — or the best RMS is below a
// quarter of that noise (the velocities are the differences of these very positions: a receiver
// that differences its fixes, whose lag is then certain however coarse they are). Otherwise the latency is 0
// (the fixes do not tell it, or there is none), and the result says why.
#pragma once
#include <string>
#include <vector>

#include "common/sensor_model.hpp"

namespace calbench::identification {

struct GnssFixSample {
  double t = 0;
  double lat = 0, lon = 0, h = 0;  // rad, rad, m
  Vec3 v_ned = Vec3::Zero();
  bool has_vel = false;
  double sigma_h = 0;  // m (≤ 0: unknown)
};

struct GnssVelocityLatency {
  double latency_s = 0;        // taken (0 when not established)
  double best_s = 0;           // the candidate with the smallest RMS
  double rms_at_zero = 0;      // m/s, horizontal
  double rms_at_best = 0;      // m/s
  double diff_noise = 0;       // m/s, the position differences' own noise
  std::size_t pairs = 0;       // fixes compared
  bool established = false;
  std::string reason;          // why not, when not
};

GnssVelocityLatency measure_gnss_velocity_latency(const std::vector<GnssFixSample>& fixes);

}  // namespace calbench::identification
