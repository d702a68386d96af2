// Bench simulator: the two-axis table executing a plan, and the simulated ADIS16488A on it.
// The table's nominal trajectory (BenchTimeline) gives the reference; the IMU sees the same
// kinematics through its error model (ImuErrorSimulator).
#pragma once
#include <functional>
#include <vector>

#include "calibration/bench_kinematics.hpp"
#include "calibration/effects/effect_terms.hpp"
#include "common/imu_error_sim.hpp"
#include "common/noise_spec.hpp"

namespace calbench {

// A contiguous time interval of the plan's execution.
struct BenchPhase {
  double t0 = 0, t1 = 0;
  int step = -1;          // plan step index while data counts; −1 while moving or settling
  int mount = 2;          // cube mount during the phase
  bool recording = true;  // false while the operator re-mounts the cube
};

class BenchTimeline {
 public:
  explicit BenchTimeline(const BenchPlan& plan);
  const std::vector<BenchPhase>& phases() const { return phases_; }
  AxisState outer(double t) const { return outer_.at(t); }
  AxisState inner(double t) const { return inner_.at(t); }
  double duration() const { return phases_.empty() ? 0.0 : phases_.back().t1; }

 private:
  void phase(double t1, int step, int mount, bool recording);
  AxisProfile outer_, inner_;
  std::vector<BenchPhase> phases_;
};

struct BenchSample {
  double t = 0;
  Vec3 gyro, accel;       // IMU output (rad/s, m/s²)
  double temp_c = 25;
  bool saturated = false;
  Vec3 w_ref, f_ref;      // what the nominal bench model says (reference.csv)
  int step = -1;
  double angle_deg = 0;   // inner-axis encoder angle, [0, 360)
};

struct BenchSimOptions {
  NoiseSpec noise = adis16488a_noise();
  std::uint64_t seed = 1;
  // Physics beyond the nominal bench and sensor model (docs/diagnosis.md), injected into what the
  // IMU sees; the reference stays nominal. All zero = the plain simulator.
  EffectTerms effects;
};

// Simulate the whole plan; `sink` receives every sample in time order.
void simulate_bench(const BenchPlan& plan, const Site& site, const SensorErrors& truth, const BenchSimOptions& opt,
                    const std::function<void(const BenchSample&)>& sink);

// The simulated device temperature: warm-up from 25 °C towards 31 °C (τ = 15 min), quantised
// to the TEMP_OUT step of 0.00565 °C.
double simulated_temperature(double t);
// Its time derivative dT/dt (K/s, not quantised): what drives the temperature_rate (thermal lag) term.
double simulated_temperature_rate(double t);

// The device temperature of a plan's [temperature] profile (TemperatureProfile), quantised like
// TEMP_OUT. Stateful (the lag is integrated forward): call with non-decreasing t.
class ProfileTemperature {
 public:
  explicit ProfileTemperature(const TemperatureProfile& p);
  double at(double t);
  // dT/dt (K/s, not quantised) at the time of the last at(t): the lag's (chamber − device)/lag_s
  // (or the chamber slope without a lag) plus the self-heating rate.
  double rate() const;

 private:
  TemperatureProfile p_;
  double t_ = 0, dev_ = 25;
};

}  // namespace calbench
