// The simulated logger of `simulate drive` (issue 53, item 2): what real loggers do to a recording
// and simulators did not, so that the validation drives carry it and the fit must measure it.
//
// * A logger polling the IMU (--logger-read-hz R): the sensor samples on its own regular clock at
//   the route's IMU rate; the logger reads every 1/R s (each interval drawn uniformly within ±30 %
//   of it) and stamps the row with the time of the read. A read sees the newest sample the sensor
//   has taken: reads faster than the sensor repeat samples, and every row is late by up to one
//   sensor interval. The estimator never sees this model: fit drive measures the stamps' scatter
//   from the rows alone (identification/sample_timing.hpp).
// * A receiver that forms its velocity from its positions (--gnss-velocity-from-positions): the
//   velocity of a fix is the difference of its position and the previous fix's over their interval
//   (the mean velocity over the last interval, so it lags its stamp by half of it), with the σ that
//   difference has (√2·max(σ_h, σ_v)/Δt: gnss.csv has one velocity σ per row). fit drive measures the lag from
//   gnss.csv (identification/gnss_velocity_latency.hpp) and models it as a pure delay.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <random>

#include "bench/io/recording.hpp"

namespace calbench {

class PollingLogger {
 public:
  // read_hz 0: rows are the sensor's samples at their own instants (every simulator's logger).
  PollingLogger(double read_hz, std::uint64_t seed, std::function<void(const ImuRecord&)> out);
  // One sensor sample, in time order.
  void sample(const ImuRecord& r);
  // The reads up to the last sample's successor interval (call once at the end).
  void finish(double sensor_dt);

 private:
  void reads_until(double t_end);
  double read_hz_;
  std::mt19937_64 rng_;
  std::function<void(const ImuRecord&)> out_;
  std::optional<ImuRecord> cur_;
  double next_read_ = 0;
  bool started_ = false;
};

class DifferencingReceiver {
 public:
  explicit DifferencingReceiver(bool on) : on_(on) {}
  // A fix as the receiver would give it: its velocity replaced by the position difference to the
  // previous fix (the first fix keeps no velocity).
  GnssRow fix(const GnssRow& g);

 private:
  bool on_;
  std::optional<GnssRow> prev_;
};

}  // namespace calbench
