// White noise measured on standstills (calibration/identification/standstill_noise.hpp): samples
// made by the IMU simulator with the noise of one device class, detected and measured with the
// class of ANOTHER one (the fit's default, ADIS16488A), so that the level can only come from the
// data. The simulator's noise level is used only to score.
#include <gtest/gtest.h>

#include <cmath>

#include "bench/io/imu_class_toml.hpp"
#include "calibration/identification/standstill_noise.hpp"
#include "common/imu_error_sim.hpp"
#include "common/units.hpp"

using namespace calbench;
using namespace calbench::identification;
using namespace calbench::units;

namespace {

struct Phase {
  double duration_s;
  bool still;
};

// A unit of `truth` class standing and moving in turn at `rate_hz`; motion: rates of tens of °/s
// and accelerations of 1 m/s² varying at 0.5–2 Hz.
StandstillDetector run(const NoiseSpec& truth, const NoiseSpec& detector_class, const std::vector<Phase>& phases, double rate_hz,
                       std::uint64_t seed) {
  NoiseSpec n = truth;
  n.output_rate_hz = rate_hz;  // the simulator's per-sample σ is density·√(output rate), as drivesim sets it
  ImuErrorSimulator sim(draw_random_unit(seed), n, seed);
  StandstillDetector det(detector_class);
  double t = 0;
  const double dt = 1.0 / rate_hz;
  for (const Phase& p : phases) {
    const double t_end = t + p.duration_s;
    for (; t < t_end - 1e-9; t += dt) {
      Vec3 w = Vec3::Zero(), f(0, 0, -kG0);
      if (!p.still) {
        w = Vec3(0.3 * std::sin(2 * M_PI * 0.7 * t), 0.2 * std::sin(2 * M_PI * 1.3 * t), 0.5 * std::cos(2 * M_PI * 0.5 * t));
        f += Vec3(1.0 * std::sin(2 * M_PI * 1.1 * t), 0.8 * std::cos(2 * M_PI * 0.9 * t), 0.5 * std::sin(2 * M_PI * 2.0 * t));
      }
      const auto o = sim.sample(t, w, f);
      det.add(t, o.gyro, o.accel);
    }
  }
  det.finish();
  return det;
}

}  // namespace

TEST(StandstillNoise, TacticalUnitMeasuredAgainstTheAdisClass) {
  // KVH 1750 noise (ARW 0.012 °/√h, 20× below the ADIS16488A's), the detector and the comparison
  // with the ADIS16488A class.
  const NoiseSpec truth = builtin_imu_class("KVH 1750").noise, cls = builtin_imu_class("ADIS16488A").noise;
  const StandstillDetector det = run(truth, cls, {{12, true}, {20, false}, {6, true}, {15, false}, {0.6, true}, {5, false}}, 400, 3);
  // Two standstills long enough (the 0.6-s one is not), each within one window of the truth.
  ASSERT_EQ(det.standstills().size(), 2u);
  EXPECT_NEAR(det.standstills()[0].t0, 0.0, 1e-9);
  EXPECT_NEAR(det.standstills()[0].t1, 12.0, 0.5);
  EXPECT_NEAR(det.standstills()[1].t0, 32.0, 0.5);
  EXPECT_NEAR(det.standstills()[1].t1, 38.0, 0.5);
  const NoiseMeasurement m = measure_white_noise(det.standstills(), cls);
  ASSERT_TRUE(m.measured);
  for (int a = 0; a < 6; ++a) {
    const double want = a < 3 ? truth.gyro.white_density : truth.accel.white_density;
    // 18 s at 400 Hz: the σ of a level from 7200 differences is about 1 %.
    EXPECT_NEAR(m.level.v[static_cast<std::size_t>(a)] / want, 1.0, 0.05) << "axis " << a;
  }
  // Far below the class: the fit is told, and takes the measured level (largest axis per triad).
  EXPECT_TRUE(m.differs[0]);
  EXPECT_TRUE(m.differs[1]);
  const NoiseSpec used = apply_measured_noise(cls, m);
  EXPECT_NEAR(used.gyro.white_density / truth.gyro.white_density, 1.0, 0.06);
  EXPECT_NEAR(used.accel.white_density / truth.accel.white_density, 1.0, 0.06);
  EXPECT_EQ(used.gyro.drift_sigma, cls.gyro.drift_sigma);  // only the white noise is learnt
}

TEST(StandstillNoise, ConsumerUnitWithinTwiceTheAdisClassKeepsTheClass) {
  // ICM-42688-P noise at 200 Hz (ARW 0.65×, VRW 1.4× the ADIS16488A's; 16-bit LSB).
  const NoiseSpec truth = builtin_imu_class("ICM-42688-P").noise, cls = builtin_imu_class("ADIS16488A").noise;
  const StandstillDetector det = run(truth, cls, {{8, true}, {20, false}}, 200, 5);
  ASSERT_EQ(det.standstills().size(), 1u);
  const NoiseMeasurement m = measure_white_noise(det.standstills(), cls);
  for (int a = 0; a < 6; ++a) {
    const double want = a < 3 ? truth.gyro.white_density : truth.accel.white_density;
    EXPECT_NEAR(m.level.v[static_cast<std::size_t>(a)] / want, 1.0, 0.12) << "axis " << a;
  }
  EXPECT_FALSE(m.differs[0]);
  EXPECT_FALSE(m.differs[1]);
  EXPECT_EQ(apply_measured_noise(cls, m).gyro.white_density, cls.gyro.white_density);
}

TEST(StandstillNoise, MotionIsNeverAStandstillAndNoisierUnitsAreNotMeasured) {
  // Moving all the time: nothing found, nothing measured, the class kept.
  const NoiseSpec adis = builtin_imu_class("ADIS16488A").noise;
  const StandstillDetector moving = run(adis, adis, {{30, false}}, 400, 8);
  EXPECT_TRUE(moving.standstills().empty());
  const NoiseMeasurement m = measure_white_noise(moving.standstills(), adis);
  EXPECT_FALSE(m.measured);
  EXPECT_FALSE(m.differs[0]);
  EXPECT_TRUE(std::isnan(m.level.v[0]));
  // A consumer unit judged against the tactical class: its standstill noise is 14× the class's,
  // beyond the detector's 3×, so no standstill is claimed (the documented limit of the rule).
  const NoiseSpec kvh = builtin_imu_class("KVH 1750").noise, icm = builtin_imu_class("ICM-42688-P").noise;
  EXPECT_TRUE(run(icm, kvh, {{10, true}, {5, false}}, 200, 9).standstills().empty());
  // A noise-free signal (synthetic files): still, measured zero, never taken as the process noise.
  const StandstillDetector clean = run(NoiseSpec{}, adis, {{5, true}}, 200, 10);
  ASSERT_EQ(clean.standstills().size(), 1u);
  const NoiseMeasurement z = measure_white_noise(clean.standstills(), adis);
  EXPECT_TRUE(z.measured);
  EXPECT_TRUE(z.zero[0]);
  EXPECT_FALSE(z.differs[0]);
  EXPECT_EQ(apply_measured_noise(adis, z).gyro.white_density, adis.gyro.white_density);
}
