// Shared by the in-motion filter tests (inmotion_filter_test.cpp, inmotion_drift_models_test.cpp):
// the simulated test drive — a route of laps, the random unit, the mounting — and the replay of a
// drive's samples through an in-motion filter as `fit drive` does with a recording: the rates are
// integrated to increments by the trapezoidal rule, the filter starts at the first reference
// epoch from the nominal mounting and the lever arm, and every later epoch is an observation.
// Only the simulator's output (IMU samples, reference epochs) and the nominal mounting reach the
// filter; the simulated unit's truth stays with the tests.
#pragma once
#include <cstdint>
#include <memory>

#include "calibration/drive_sim/drive_simulator.hpp"
#include "calibration/inmotion/inmotion_filter.hpp"

namespace calbench::inmotion_test {

// A route from the start (degrees, metres) of `laps` laps, after a 20 s standstill; each lap has
// accelerations and stops, turns of both signs and several radii, a climb and a descent and two
// lane changes.
drivesim::Route lap_route(double lat_deg, double lon_deg, double h_m, double heading_deg, int laps);

// The nominal mounting of the test drives (MEMS axes yawed 90° in the vehicle): rpy, rad, and C.
Vec3 nominal_mounting_rpy();
Mat3 nominal_mounting();

// A drive of `route` by the unit draw_random_unit(seed) (`seed` is the simulator's seed too):
// MEMS at imu_rate_hz, reference at 50 Hz, no GNSS; true mounting = nominal + misalignment_deg,
// MEMS at lever_arm_m. Everything else (noise, reference errors) is the simulator's default.
drivesim::DriveSimConfig drive_config(const drivesim::Route& route, std::uint64_t seed, double imu_rate_hz,
                                      const Vec3& misalignment_deg, const Vec3& lever_arm_m);

// A simulated reference epoch as the filter's observation (position, velocity, attitude, their σ).
inmotion::RefObs ref_obs(const drivesim::SimRef& r);

// One IMU sample into anything with imu(t, dθ, dv, dt) (the filter, an inertial-only QC run):
// the increments over the dt before sample m, by the trapezoid of m and the sample before it.
template <class Sink>
void imu_increment(Sink& sink, const drivesim::SimImu& m, const drivesim::SimImu& prev, double dt) {
  sink.imu(m.t, 0.5 * (m.gyro + prev.gyro) * dt, 0.5 * (m.accel + prev.accel) * dt, dt);
}

// Feeds a drive, sample by sample in time order, to a filter (InMotionFilter or InMotionFilterAug).
template <class Filter>
class FilterReplay {
 public:
  FilterReplay(const inmotion::InMotionConfig& fc, const Mat3& C_nominal, const Vec3& lever)
      : fc_(fc), C_nominal_(C_nominal), lever_(lever) {}

  // An IMU sample, dt after the previous one; none reaches the filter before it has started.
  void imu(const drivesim::SimImu& m, double dt) {
    if (f_ && have_prev_) imu_increment(*f_, m, prev_, dt);
    prev_ = m;
    have_prev_ = true;
  }
  // The same with dt = the time since the previous sample.
  void imu(const drivesim::SimImu& m) { imu(m, have_prev_ ? m.t - prev_.t : 0.0); }

  // A reference epoch: the first one starts the filter (false); after that, what the filter's
  // reference() says (true when the epoch was used).
  bool reference(const inmotion::RefObs& o) {
    if (!f_) {
      f_ = std::make_unique<Filter>(fc_, C_nominal_, lever_, o);
      return false;
    }
    return f_->reference(o);
  }
  bool reference(const drivesim::SimRef& r) { return reference(ref_obs(r)); }

  bool started() const { return f_ != nullptr; }
  Filter& filter() { return *f_; }
  const Filter& filter() const { return *f_; }

 private:
  inmotion::InMotionConfig fc_;
  Mat3 C_nominal_;
  Vec3 lever_;
  std::unique_ptr<Filter> f_;
  drivesim::SimImu prev_;
  bool have_prev_ = false;
};

}  // namespace calbench::inmotion_test
