// The antenna blocks (antenna_blocks.cpp, issue 34 item 4) on a simulated GNSS-only drive: the
// filter is told a lever arm 0.3 m off the truth per axis and the fixes reach it stamped 15 ms late
// (the fix stamped t describes the antenna at t − 15 ms). With the antenna blocks the time offset
// comes out within 2 ms of the truth (prior σ 20 ms) and the lever arm within 0.1 m horizontally
// and 0.2 m vertically (error told 0.3 m per axis), σ below half the prior, and the innovations are consistent again (without
// the blocks and without the adaptive process noise their NIS is 1.5–2.3× larger). Measured
// (2026-11-26): lever correction 0.372 −0.308 0.159 m (truth 0.3 −0.3 0.3), σ 0.009 0.009 0.040;
// time offset 16.3 ms σ 0.44 ms (seed 1); 0.364 −0.322 0.217 m, 16.0 ms (seed 2). NOT within 3σ:
// the forward (x) and vertical (z) lever components keep a bias of 0.06–0.14 m beyond their σ
// (docs/in-motion.md, "Lever arm and time offset"); the lateral one and the time offset are.
// The truth only scores.
// RTK-class fixes (2 cm, 5 Hz, velocity 2 cm/s), 60 s opening standstill, two laps, 100 Hz IMU.
#include <gtest/gtest.h>

#include <cstdio>
#include <deque>

#include "calibration/drive_sim/drive_simulator.hpp"
#include "calibration/inmotion/inmotion_filter.hpp"
#include "inmotion_test_drive.hpp"

using namespace calbench;
using namespace calbench::drivesim;
using namespace calbench::inmotion;
using namespace calbench::inmotion_test;

namespace {

constexpr double kStampLate = 0.015;  // s
const Vec3 kLeverTrue(-1.0, 0.3, -0.4);
const Vec3 kLeverError(0.3, -0.3, 0.3);  // told = truth − error

struct AntennaRun {
  Vec3 lever, lever_sigma;
  double dt = 0, dt_sigma = 0, nis_pos = 0, nis_vel = 0;
};

AntennaRun run(std::uint64_t seed, bool estimate) {
  InMotionConfig fc;
  fc.obs_pos = fc.obs_vel = true;
  fc.obs_att = false;
  fc.obs_rate_hz = 5;
  fc.estimate_lever_arm = fc.estimate_time_offset = estimate;
  fc.adaptive.enabled = false;  // the unmodelled errors show in the NIS instead of buying process noise
  Route route = lap_route(48.1, 11.6, 520, 35, 2);
  route.segments[0].duration_s = 60;
  DriveSimConfig cfg = drive_config(route, seed, 100, Vec3(0.4, -0.3, 0.5), kLeverTrue);
  cfg.reference.rate_hz = 0;
  cfg.gnss.rate_hz = 5;
  cfg.gnss.sigma_h_m = 0.02;
  cfg.gnss.sigma_v_m = 0.03;
  cfg.gnss.sigma_vel_m_s = 0.02;
  FilterReplay<InMotionFilter> replay(fc, nominal_mounting(), kLeverTrue - kLeverError);
  std::deque<RefObs> pending;  // fixes waiting for their (late) stamp
  DriveSinks sinks;
  sinks.imu = [&](const SimImu& m) {
    replay.imu(m);
    while (!pending.empty() && pending.front().t <= m.t) {
      replay.reference(pending.front());
      pending.pop_front();
    }
  };
  sinks.gnss = [&](const SimGnss& g) {
    pending.push_back(gnss_fix_obs(g.t + kStampLate, g.lat, g.lon, g.h, &g.v_ned, g.sigma_h, g.sigma_v, g.sigma_vel));
  };
  simulate_drive(cfg, sinks);
  const InMotionFilter& f = replay.filter();
  AntennaRun r;
  r.nis_pos = f.consistency(0).mean_nis();
  r.nis_vel = f.consistency(1).mean_nis();
  if (!estimate) return r;
  Eigen::VectorXd x, s;
  f.state_si(x, s);
  const int l = f.layout().L.offset(static_cast<int>(kLeverArmBlock)), t = f.layout().L.offset(static_cast<int>(kTimeOffsetBlock));
  EXPECT_GE(l, 0);
  EXPECT_GE(t, 0);
  r.lever = x.segment<3>(l);
  r.lever_sigma = s.segment<3>(l);
  r.dt = x(t);
  r.dt_sigma = s(t);
  return r;
}

}  // namespace

TEST(InmotionAntenna, LeverArmAndTimeOffsetEstimated) {
  const InMotionConfig def;
  for (std::uint64_t seed : {1, 2}) {
    const AntennaRun r = run(seed, true);
    std::printf("seed %llu: lever correction %.3f %.3f %.3f m (truth %.3f %.3f %.3f) sigma %.3f %.3f %.3f; time offset %.2f ms "
                "(truth %.2f) sigma %.2f ms; NIS pos %.2f vel %.2f\n",
                static_cast<unsigned long long>(seed), r.lever(0), r.lever(1), r.lever(2), kLeverError(0), kLeverError(1),
                kLeverError(2), r.lever_sigma(0), r.lever_sigma(1), r.lever_sigma(2), r.dt * 1e3, kStampLate * 1e3,
                r.dt_sigma * 1e3, r.nis_pos, r.nis_vel);
    for (int i = 0; i < 3; ++i) {
      // horizontal within 0.1 m, vertical (seen only through roll and pitch) within 0.2 m
      EXPECT_LT(std::abs(r.lever(i) - kLeverError(i)), i < 2 ? 0.1 : 0.2) << "seed " << seed << " axis " << i;
      EXPECT_LT(r.lever_sigma(i), 0.5 * def.lever_arm_sigma) << "seed " << seed << " axis " << i;
    }
    EXPECT_LE(std::abs(r.lever(1) - kLeverError(1)), 3 * r.lever_sigma(1)) << "seed " << seed;  // lateral: within 3σ
    EXPECT_LT(std::abs(r.dt - kStampLate), 0.002) << "seed " << seed;
    EXPECT_LT(r.dt_sigma, 0.5 * def.time_offset_sigma) << "seed " << seed;
  }
}

TEST(InmotionAntenna, OffByDefaultAndTheUnmodelledErrorsShow) {
  EXPECT_EQ(make_layout(InMotionConfig{}).size(), make_layout(InMotionConfig{}).size());  // the default layout is unchanged
  InMotionConfig on;
  on.estimate_lever_arm = on.estimate_time_offset = true;
  EXPECT_EQ(make_layout(on).size(), make_layout(InMotionConfig{}).size() + 4);
  const AntennaRun plain = run(1, false), with = run(1, true);
  std::printf("mean NIS pos %.2f vel %.2f without the blocks, %.2f %.2f with them\n", plain.nis_pos, plain.nis_vel, with.nis_pos,
              with.nis_vel);
  EXPECT_GT(plain.nis_pos + plain.nis_vel, 1.2 * (with.nis_pos + with.nis_vel));
}
