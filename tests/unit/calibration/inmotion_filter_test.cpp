// In-motion EKF on a short simulated drive (in memory): the sensor errors of a random unit and
// the mounting misalignment are recovered within 3σ, the innovations are consistent, and the
// attitude observation (eq 15) shrinks the gyro-drift uncertainty (the paper's point).
#include <gtest/gtest.h>

#include "calibration/drive_sim/drive_simulator.hpp"
#include "calibration/inmotion/inmotion_filter.hpp"
#include "common/units.hpp"
#include "inmotion_test_drive.hpp"

using namespace calbench;
using namespace calbench::drivesim;
using namespace calbench::inmotion;
using namespace calbench::inmotion_test;
using units::kDeg;

namespace {
struct DriveRun {
  SensorErrors truth, est;
  Vec3 mount_true, mount_est, mount_sigma, gyro_total_sigma;
  double mean_nis[3];
};

// Two laps near Munich at 500 Hz, the unit and simulator of `seed`, streamed into the filter.
DriveRun run(std::uint64_t seed, bool att) {
  const DriveSimConfig cfg = drive_config(lap_route(48.1, 11.6, 520, 10, 2), seed, 500, Vec3(0.4, -0.3, 0.5),
                                          Vec3(0.6, -0.4, 0.3));
  InMotionConfig fc;
  fc.obs_att = att;
  FilterReplay<InMotionFilter> replay(fc, nominal_mounting(), cfg.lever_arm);
  DriveSinks sinks;
  sinks.imu = [&](const SimImu& m) { replay.imu(m); };
  sinks.reference = [&](const SimRef& r) { replay.reference(r); };
  simulate_drive(cfg, sinks);
  InMotionFilter& f = replay.filter();
  DriveRun out;
  out.truth = cfg.mems;
  out.est = f.estimate();
  out.mount_true = cfg.mounting_rpy;
  f.mounting_rpy(out.mount_est, out.mount_sigma);
  out.gyro_total_sigma = f.gyro_total_drift_sigma();
  for (int i = 0; i < 3; ++i) out.mean_nis[i] = f.consistency(i).mean_nis();
  return out;
}

int count_within(const TriadErrors& t, const TriadErrors& e, int& n) {
  int ok = 0;
  for (int i = 0; i < 3; ++i) {
    ok += std::abs(e.bias(i) - t.bias(i)) <= 3 * e.sigma_bias(i);
    ++n;
    for (int j = 0; j < 3; ++j) {
      ok += std::abs(e.M(i, j) - t.M(i, j)) <= 3 * e.sigma_M(i, j);
      ++n;
    }
  }
  return ok;
}
}  // namespace

TEST(InmotionFilter, RecoversRandomUnitAndMountingWithinThreeSigma) {
  const DriveRun r = run(11, true);
  int n = 0;
  const int ok = count_within(r.truth.gyro, r.est.gyro, n) + count_within(r.truth.accel, r.est.accel, n);
  EXPECT_GE(ok, static_cast<int>(0.9 * n)) << ok << " of " << n;
  for (int i = 0; i < 3; ++i) {
    EXPECT_LE(std::abs(r.mount_est(i) - r.mount_true(i)), 3 * r.mount_sigma(i) + 1e-9) << i;
    // The drive must actually inform: turn-on biases are far outside what the filter ends with.
    EXPECT_LT(r.est.gyro.sigma_bias(i), 0.05 * 0.5 * kDeg) << i;
    EXPECT_LT(r.est.accel.sigma_bias(i), 3 * units::kMilliG) << i;
    EXPECT_GT(r.mean_nis[i], 0.3);
    EXPECT_LT(r.mean_nis[i], 10.0);
  }
  EXPECT_LT(r.est.gyro.sigma_M(2, 2), 2e-3);  // yaw-axis scale from the turns
}

TEST(InmotionFilter, AttitudeObservationShrinksGyroDriftSigma) {
  const DriveRun with = run(12, true), without = run(12, false);
  for (int i = 0; i < 3; ++i) {
    std::printf("axis %d: total gyro drift sigma %.3f (pos,vel,att) vs %.3f deg/h (pos,vel); constant part %.3f vs %.3f;"
                " mount sigma %.4f vs %.4f deg\n", i,
                with.gyro_total_sigma(i) / units::kDegPerHour, without.gyro_total_sigma(i) / units::kDegPerHour,
                with.est.gyro.sigma_bias(i) / units::kDegPerHour, without.est.gyro.sigma_bias(i) / units::kDegPerHour,
                with.mount_sigma(i) / kDeg, without.mount_sigma(i) / kDeg);
    EXPECT_LT(with.gyro_total_sigma(i), without.gyro_total_sigma(i)) << i;
    EXPECT_LE(with.est.gyro.sigma_bias(i), without.est.gyro.sigma_bias(i)) << i;
  }
}
