// The logger's sample timing, measured from a recording's own stamps (issue 53): how far the stamps
// of the IMU's samples stray from the regular clock the sensor samples on.
//
// Why it matters. A strapdown INS integrates rates over the stamped intervals. A stamp that is late
// or early by ε moves the boundary between two samples, and the increments change by ε times the
// jump of the integrand there. With the trapezoidal rule (ins::RateIntegrator) and the mean rate
// of step i m_i = (y_i + y_{i−1})/2, the increments' error is Σ ε_i·(m_{i+1} − m_i): a white
// error of variance σ_τ²·|m_{i+1} − m_i|² per step, nothing at a standstill, large in shaky motion
// (a handheld unit, a vehicle's vibration). Real loggers stamp a sample when they read it, not when
// the sensor took it; simulators stamp the sensor's instant, so they never show it.
//
// Measurement. A row that repeats the previous row's six values is a second read of a sample
// already read (a logger polling faster than the sensor's data rate: the real walk's rows repeat
// 34 % of the time, 100.5 distinct samples per second read about 152 times per second). The
// distinct samples' stamps (their first reads) are fitted, in consecutive runs of `run` samples
// without a gap, by a straight line against their index (the sensor's own clock, locally
// regular); the residuals' σ (per run, stamps beyond 5 robust σ left out; the median over the
// runs) is σ_τ. Stamps regular to within `floor_s` (a simulator's, or a logger that
// stamps in the sensor) give σ_τ = 0, and the filter is then the one without the term, bit for bit.
//
// Lateness. A logger that stamps at the read is never early: each stamp is the sensor's instant plus
// a delay from 0 up to a read interval. The line through a run's stamps runs through their mean
// delay; the earliest stamps (the run's 1st percentile of the kept residuals) sit at the shortest
// delay. Their distance, the mean lateness above the shortest delay (median over the runs), is how
// far the stamps are late on average: T/2 for a delay uniform over T (a 300-Hz read of a 100-Hz
// sensor: 1.7 ms; stamps 5 ms late on average when the read interval reaches the sensor's). A
// constant delay common to every read (a transport latency) moves no stamp against another and is
// not seen here: that is the IMU-GNSS time offset's (fit drive --estimate time). From the stamps
// alone a delay uniform over [0, T] cannot be told from a scatter of ±T/2 about the clock; the
// second reads tell it (polling()). fit drive reports the lateness and does not move the stamps by
// it: on four simulated polling loggers the innovations' likelihood was lower with the move
// (docs/validation/inmotion-real-walk-cause.md); a delay of the stamps is --estimate time's.
#pragma once
#include <cstddef>
#include <vector>

#include "common/sensor_model.hpp"

namespace calbench::identification {

struct SampleTiming {
  std::size_t rows = 0;          // rows read
  std::size_t repeated = 0;      // rows repeating the previous row's six values (second reads)
  double distinct_rate_hz = 0;   // distinct samples per second (the sensor's data rate)
  double read_rate_hz = 0;       // rows per second (the logger's read rate)
  double sigma_s = 0;            // σ_τ of the distinct samples' stamps about their regular clock, s
  double lateness_s = 0;         // mean lateness of the stamps above the earliest ones, s (0 when regular)
  std::size_t runs = 0;          // runs of `run` distinct samples the σ is the median over
  bool regular = true;           // σ_τ below the floor: taken as 0
  // Second reads in more than 1 % of the rows: a logger polling faster than the sensor, whose
  // stamps are the reads' (never early: lateness_s is then a delay, not a symmetric scatter).
  bool polling() const { return rows > 0 && static_cast<double>(repeated) > 0.01 * static_cast<double>(rows); }
};

class SampleTimingEstimator {
 public:
  static constexpr std::size_t kRun = 256;
  static constexpr double kFloorS = 1e-5;  // below 10 µs: a regular clock (the term is 4·10⁴× below 2 ms's)

  // One row of the recording, in order: its stamp and its six values as read.
  void add(double t, const Vec3& w, const Vec3& f);
  SampleTiming result() const;

 private:
  void close_run();
  std::vector<double> run_;        // stamps of the current run's distinct samples
  std::vector<double> run_sigma_;  // each closed run's σ
  std::vector<double> run_late_;   // each closed run's mean lateness above its earliest stamps
  std::vector<double> scratch_r_, scratch_dev_, scratch_m_;  // reused by close_run
  SampleTiming s_;
  double t_first_ = 0, t_last_ = 0, last_dt_ = 0;
  std::size_t distinct_ = 0;
  Vec3 w_prev_ = Vec3::Zero(), f_prev_ = Vec3::Zero();
  bool have_prev_ = false;
};

}  // namespace calbench::identification
