// The opening standstill without attitude observations (issue 16, item 6): a 60 s standstill,
// then laps, raw-data (data-sheet) priors, GNSS position fixes at 1 Hz. The filter starts from a
// fix (no attitude), levels at the standstill, finds its heading from the course over ground once
// moving, and never locks out; the heading error of its navigation solution stays small.
// (The reference-INS case, --obs pos at 1 Hz, is covered by tests/cli/drive_gnss_only.sh on the
// 1 h route's first 300 s, where the old filter lost track.) In memory, 100 Hz IMU, a few minutes
// of drive: well under a second of CPU.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

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

struct Outcome {
  long used = 0, rejected = 0, forced = 0, realigned = 0;
  double t_motion = -1;             // first time the vehicle moves (truth, evaluation only)
  double heading_t = -1;            // the filter's first heading from the course (GNSS-only)
  double max_err_after = 0;         // max |heading error| from t_motion + settle_s to the end, deg
  double err_end = 0;               // at the end, deg
  std::string mode;
};

// A 60 s opening standstill, then `laps` laps at 100 Hz; aided by GNSS fixes at 1 Hz (else the
// reference INS's positions at 1 Hz); the filter with position observations only.
DriveSimConfig standstill_drive(std::uint64_t seed, int laps, bool gnss, const Vec3& lever, InMotionConfig& fc) {
  Route route = lap_route(48.1, 11.6, 520, 35, laps);
  route.segments[0].duration_s = 60;  // the opening standstill
  DriveSimConfig cfg = drive_config(route, seed, 100, Vec3(0.4, -0.3, 0.5), lever);
  cfg.gnss.rate_hz = gnss ? 1 : 0;
  if (gnss) cfg.reference.rate_hz = 0;
  fc.obs_pos = true;
  fc.obs_vel = fc.obs_att = false;
  fc.obs_rate_hz = 1;
  return cfg;
}

// seed: unit and simulator; gnss: aid with the GNSS fixes (else the reference INS at 1 Hz).
Outcome run(std::uint64_t seed, bool gnss, bool realign, double settle_s, const Vec3& lever = Vec3(-1.0, 0.3, -0.4)) {
  InMotionConfig fc;
  fc.realign_heading = realign;
  const DriveSimConfig cfg = standstill_drive(seed, 2, gnss, lever, fc);
  FilterReplay<InMotionFilter> replay(fc, nominal_mounting(), cfg.lever_arm);
  const Mat3 C_mb_true = ins::dcm_from_rpy(cfg.mounting_rpy);
  Outcome o;
  Mat3 C_true = Mat3::Identity();
  double v_true = 0;
  auto evaluate = [&](double t) {
    if (!replay.started() || !replay.filter().heading_known()) return;
    const InMotionFilter& f = replay.filter();
    // Heading error of the navigation solution (MEMS frame): down component of Ĉ_nm·C_nmᵀ = exp(−φ×).
    const double e = std::abs(ins::rotvec_from_dcm(f.nav().C_nb() * (C_true * C_mb_true).transpose())(2)) / kDeg;
    if (o.t_motion >= 0 && t >= o.t_motion + settle_s) o.max_err_after = std::max(o.max_err_after, e);
    o.err_end = e;
  };
  DriveSinks sinks;
  sinks.imu = [&](const SimImu& m) { replay.imu(m); };
  sinks.truth = [&](const SimTruth& s) {
    C_true = s.C_nb;
    v_true = s.v_ned.norm();
    if (o.t_motion < 0 && v_true > 0.5) o.t_motion = s.t;
  };
  sinks.reference = [&](const SimRef& r) {
    replay.reference(r);
    evaluate(r.t);
  };
  sinks.gnss = [&](const SimGnss& g) {
    replay.reference(gnss_fix_obs(g.t, g.lat, g.lon, g.h, nullptr, g.sigma_h, g.sigma_v, g.sigma_vel));
    evaluate(g.t);
  };
  simulate_drive(cfg, sinks);
  const InMotionFilter& f = replay.filter();
  o.used = f.consistency(0).used;
  o.rejected = f.consistency(0).rejected;
  o.forced = f.consistency(0).forced;
  for (const Recovery& r : f.recoveries()) o.realigned += r.action.rfind("heading", 0) == 0;
  o.heading_t = f.alignment().heading_t;
  o.mode = f.alignment().mode;
  std::printf("seed %llu %s realign %d: used %ld rejected %ld forced %ld realigned %ld; motion at %.1f s, heading at %.1f s;"
              " heading error max after +%.0f s %.2f deg, end %.3f deg\n",
              static_cast<unsigned long long>(seed), gnss ? "GNSS-only" : "reference pos@1Hz", realign ? 1 : 0, o.used,
              o.rejected, o.forced, o.realigned, o.t_motion, o.heading_t, settle_s, o.max_err_after, o.err_end);
  for (const Recovery& r : f.recoveries()) std::printf("  t %.0f s: %s -> %s\n", r.t, r.reason.c_str(), r.action.c_str());
  return o;
}

}  // namespace

TEST(InmotionGnss, GnssOnlyOpeningStandstillAlignsWithoutLockOut) {
  for (std::uint64_t seed : {5, 21}) {
    const Outcome o = run(seed, true, true, 120);
    EXPECT_EQ(o.mode, "gnss");
    // The heading comes from the course soon after the vehicle starts, not before.
    ASSERT_GE(o.heading_t, o.t_motion) << seed;
    EXPECT_LT(o.heading_t, o.t_motion + 20) << seed;
    EXPECT_EQ(o.forced, 0) << seed;                   // no lock-out
    EXPECT_LT(o.rejected, o.used / 50 + 2) << seed;   // the gate hardly rejects anything
    EXPECT_LT(o.max_err_after, 2.0) << seed;          // heading within 2° from 2 min after the start of motion
    EXPECT_LT(o.err_end, 1.0) << seed;
  }
}

// The opening standstill with the heading unknown teaches the filter nothing true about the sensor
// errors (its model puts the Earth rate in the wrong axes, linearised 100°+ from the truth): with
// restart_at_heading (the default) the sensor-error states go back to the end of levelling at the
// first heading, and the drive's estimates are within 3σ; without it the horizontal gyro drifts
// come out overconfident (issue 16: 76.7 % within 3σ over 1 h drives, raw priors, GNSS `pos`).
namespace {
struct Coverage {
  int within = 0, n = 0;
  double worst_gyro_bias_z = 0;  // largest |error|/σ of the gyro biases
  double sigma_gyro_bias = 0;     // largest σ of the gyro biases at the end, rad/s
};
// level: the gyro bias from the levelling standstill (InMotionConfig::level_gyro_bias).
Coverage coverage(std::uint64_t seed, bool restart, bool level = false) {
  InMotionConfig fc;
  fc.restart_at_heading = restart;
  fc.level_gyro_bias = level;
  const DriveSimConfig cfg = standstill_drive(seed, 3, true, Vec3(-1.0, 0.3, -0.4), fc);
  FilterReplay<InMotionFilter> replay(fc, nominal_mounting(), cfg.lever_arm);
  DriveSinks sinks;
  sinks.imu = [&](const SimImu& m) { replay.imu(m); };
  sinks.gnss = [&](const SimGnss& g) {
    replay.reference(gnss_fix_obs(g.t, g.lat, g.lon, g.h, nullptr, g.sigma_h, g.sigma_v, g.sigma_vel));
  };
  simulate_drive(cfg, sinks);
  const SensorErrors e = replay.filter().estimate();
  Coverage c;
  for (const auto* tr : {&e.gyro, &e.accel}) {
    const TriadErrors& t = tr == &e.gyro ? cfg.mems.gyro : cfg.mems.accel;
    for (int i = 0; i < 3; ++i) {
      const double zb = std::abs(tr->bias(i) - t.bias(i)) / tr->sigma_bias(i);
      if (tr == &e.gyro) c.worst_gyro_bias_z = std::max(c.worst_gyro_bias_z, zb);
      if (tr == &e.gyro) c.sigma_gyro_bias = std::max(c.sigma_gyro_bias, tr->sigma_bias(i));
      c.within += zb <= 3;
      ++c.n;
      for (int j = 0; j < 3; ++j) {
        c.within += std::abs(tr->M(i, j) - t.M(i, j)) <= 3 * tr->sigma_M(i, j);
        ++c.n;
      }
    }
  }
  std::printf("seed %llu restart_at_heading %d level_gyro_bias %d: %d of %d within 3 sigma, worst gyro bias %.1f sigma, largest sigma %.2f deg/h\n",
              static_cast<unsigned long long>(seed), restart ? 1 : 0, level ? 1 : 0, c.within, c.n, c.worst_gyro_bias_z,
              c.sigma_gyro_bias / units::kDegPerHour);
  return c;
}
}  // namespace

TEST(InmotionGnss, StandstillWithoutHeadingLeavesNoFalseInformation) {
  int within = 0, n = 0, within_old = 0;
  double worst = 0, worst_old = 0;
  for (std::uint64_t seed : {5, 21, 33}) {
    const Coverage c = coverage(seed, true), old = coverage(seed, false);
    within += c.within, n += c.n, within_old += old.within;
    worst = std::max(worst, c.worst_gyro_bias_z), worst_old = std::max(worst_old, old.worst_gyro_bias_z);
  }
  EXPECT_GE(within, static_cast<int>(std::ceil(0.95 * n))) << within << " of " << n;
  EXPECT_LT(worst, 3.0);
  // The check can fail: without the restart the same drives are overconfident.
  EXPECT_LT(within_old, within);
  EXPECT_GT(worst_old, 3.0);
}

// The gyro bias from the levelling standstill (the zero-rate observation with the heading unknown,
// obs_zupt.cpp): true information, so the drives stay within 3σ, and more of it than the drive gives
// without it (smaller σ at the end: asserted against the same drive with level_gyro_bias off).
TEST(InmotionGnss, LevellingStandstillGivesTheGyroBias) {
  int within = 0, n = 0;
  for (std::uint64_t seed : {5, 21, 33}) {
    const Coverage c = coverage(seed, true, true), without = coverage(seed, true, false);
    within += c.within, n += c.n;
    EXPECT_LT(c.worst_gyro_bias_z, 3.0) << seed;
    EXPECT_LT(c.sigma_gyro_bias, without.sigma_gyro_bias) << seed;
  }
  EXPECT_GE(within, static_cast<int>(std::ceil(0.95 * n))) << within << " of " << n;
}
