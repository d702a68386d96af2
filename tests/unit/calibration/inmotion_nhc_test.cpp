// Vehicle constraints (issue 34, item 4): on a GNSS-only drive (position and velocity fixes, no
// attitude) the mounting's pitch and yaw stay near their prior; with the non-holonomic constraint
// and the zero-velocity updates they become observable: the error ends within 3σ and σ well below
// the prior. The true mounting is a few degrees off the nominal one the filter starts from. The
// standstills of the route are found from the IMU data. In memory, 100 Hz IMU, two laps.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "inmotion_test_drive.hpp"  // the simulator and the filter
#include "common/units.hpp"

namespace {

using namespace calbench;
using namespace calbench::drivesim;
using namespace calbench::inmotion;
using namespace calbench::inmotion_test;
using units::kDeg;

struct MountOutcome {
  Vec3 err_deg = Vec3::Zero(), sigma_deg = Vec3::Zero();  // δμ = estimate ⊖ truth, vehicle axes
  long nhc = 0, zupt = 0, zero_rate = 0, rejected = 0;
  double nhc_nis = 0, zupt_nis = 0;
  std::vector<Standstill> still;
  std::vector<std::pair<double, double>> true_stops;  // truth: speed 0 (evaluation only)
  std::vector<std::pair<double, double>> speed;       // truth: (t, speed) at every IMU sample
  double max_speed(double t0, double t1) const {
    double m = 0;
    for (const auto& [t, v] : speed)
      if (t >= t0 && t <= t1) m = std::max(m, v);
    return m;
  }
};

MountOutcome run(std::uint64_t seed, bool constraints) {
  Route route = lap_route(48.1, 11.6, 520, 35, 2);
  route.segments[0].duration_s = 40;  // the opening standstill (levelling)
  // True mounting: nominal + Euler (2°, −0.3°, −2.5°); with the nominal yaw of 90° the MEMS x axis
  // is the vehicle's y, so that is a vehicle pitch of 2°, roll 0.3°, yaw −2.5° (prior 1° per axis).
  DriveSimConfig cfg = drive_config(route, seed, 100, Vec3(2.0, -0.3, -2.5), Vec3(-1.0, 0.3, -0.4));
  cfg.gnss.rate_hz = 2;
  cfg.reference.rate_hz = 0;
  InMotionConfig fc;
  fc.obs_pos = fc.obs_vel = true;
  fc.obs_att = false;
  fc.ref_sigma_pos = 2.0;
  fc.ref_sigma_vel = 0.1;
  fc.obs_nhc = fc.obs_zupt = constraints;
  FilterReplay<InMotionFilter> replay(fc, nominal_mounting(), cfg.lever_arm);
  MountOutcome o;
  bool stopped = false;
  DriveSinks sinks;
  sinks.imu = [&](const SimImu& m) { replay.imu(m); };
  sinks.truth = [&](const SimTruth& s) {
    const bool st = s.v_ned.norm() < 1e-6;
    o.speed.push_back({s.t, s.v_ned.norm()});
    if (st && !stopped) o.true_stops.push_back({s.t, s.t});
    if (st) o.true_stops.back().second = s.t;
    stopped = st;
  };
  sinks.gnss = [&](const SimGnss& g) {
    replay.reference(gnss_fix_obs(g.t, g.lat, g.lon, g.h, &g.v_ned, g.sigma_h, g.sigma_v, g.sigma_vel));
  };
  simulate_drive(cfg, sinks);
  const InMotionFilter& f = replay.filter();
  const Mat3 C_true = ins::dcm_from_rpy(cfg.mounting_rpy);
  // Ĉ_mb = (I − δμ×)·C_mb: δμ = log(C_mb·Ĉ_mbᵀ).
  o.err_deg = ins::rotvec_from_dcm(C_true * f.mounting().transpose()) / kDeg;
  const int mo = f.offset(Block::mount);
  o.sigma_deg = f.P().block<3, 3>(mo, mo).diagonal().cwiseSqrt() / kDeg;
  o.nhc = f.consistency(kObsNhc).used;
  o.zupt = f.consistency(kObsZupt).used;
  o.zero_rate = f.consistency(kObsZeroRate).used;
  o.rejected = f.consistency(kObsNhc).rejected + f.consistency(kObsZupt).rejected + f.consistency(kObsZeroRate).rejected;
  o.nhc_nis = f.consistency(kObsNhc).mean_nis();
  o.zupt_nis = f.consistency(kObsZupt).mean_nis();
  o.still = f.standstills();
  std::printf("seed %llu constraints %d: mounting error (%.3f, %.3f, %.3f) deg, sigma (%.3f, %.3f, %.3f) deg; nhc %ld (NIS %.2f), "
              "zupt %ld (NIS %.2f), zero rate %ld, rejected %ld, %zu standstills found, %zu true stops\n",
              static_cast<unsigned long long>(seed), constraints ? 1 : 0, o.err_deg(0), o.err_deg(1), o.err_deg(2), o.sigma_deg(0),
              o.sigma_deg(1), o.sigma_deg(2), o.nhc, o.nhc_nis, o.zupt, o.zupt_nis, o.zero_rate, o.rejected, o.still.size(),
              o.true_stops.size());
  return o;
}

TEST(InmotionVehicleConstraints, NhcMakesMountingPitchAndYawObservableOnGnssOnlyDrive) {
  for (std::uint64_t seed : {7, 19}) {
    const MountOutcome without = run(seed, false), with = run(seed, true);
    // Without the constraints the GNSS-only drive leaves pitch and yaw near their 1° prior (the
    // checks with them can fail: this is the difference they measure).
    EXPECT_GT(without.sigma_deg(1), 0.35) << seed;
    EXPECT_GT(without.sigma_deg(2), 0.35) << seed;
    EXPECT_EQ(without.nhc + without.zupt, 0) << seed;
    // With them: σ well below the prior, the error within 3σ.
    for (int i : {1, 2}) {
      EXPECT_LT(with.sigma_deg(i), 0.25) << seed << " axis " << i;
      EXPECT_LT(with.sigma_deg(i), 0.25 * without.sigma_deg(i)) << seed << " axis " << i;
      EXPECT_LT(std::abs(with.err_deg(i)), 3 * with.sigma_deg(i)) << seed << " axis " << i;
    }
    // The 2° pitch stays off without them (the course over ground gives the yaw part of the way).
    EXPECT_GT(std::abs(without.err_deg(1)), 1.0) << seed;
    EXPECT_GT(with.nhc, 100) << seed;
    EXPECT_GT(with.zupt, 50) << seed;
    EXPECT_GT(with.zero_rate, 50) << seed;
    EXPECT_LT(with.rejected, (with.nhc + with.zupt) / 50 + 2) << seed;
    // The simulated vehicle does not slip at all: with σ = 0.1 m/s (a real car's) the NHC's NIS lies
    // far below its expectation of 2, never above it; the ZUPT's likewise below 3.
    EXPECT_LT(with.nhc_nis, 2.0) << seed;
    EXPECT_LT(with.zupt_nis, 3.0) << seed;
    // Every stop of the route longer than the detector's window is found, and wherever a
    // standstill was found the vehicle moved at most at walking-the-dog pace (a start creeps
    // a few mm/s before the IMU sees it).
    for (const auto& [t0, t1] : with.true_stops) {
      if (t1 - t0 < 3.0) continue;
      bool found = false;
      for (const Standstill& s : with.still) found = found || (s.t0 < t1 && s.t1 > t0);
      EXPECT_TRUE(found) << seed << ": stop " << t0 << "-" << t1 << " s not found";
    }
    for (const Standstill& s : with.still)
      EXPECT_LT(with.max_speed(s.t0, s.t1), 0.05) << seed << ": standstill " << s.t0 << "-" << s.t1 << " s while moving";
  }
}

}  // namespace
