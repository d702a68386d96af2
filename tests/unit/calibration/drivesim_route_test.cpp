// Drive simulator: route kinematics are self-consistent, and a strapdown INS fed with an
// error-free simulated MEMS IMU (with mounting rotation and lever arm) follows the truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "calibration/drive_sim/drive_simulator.hpp"
#include "calibration/ins/strapdown.hpp"
#include "common/units.hpp"

using namespace calbench;
using namespace calbench::drivesim;
using units::kDeg;

namespace {
Route test_route() {
  Route r;
  r.lat = 55.7 * kDeg;
  r.lon = 37.6 * kDeg;
  r.h = 150;
  r.heading = 30 * kDeg;
  auto seg = [&](SegmentKind k) { Segment s; s.kind = k; return s; };
  Segment s = seg(SegmentKind::stop); s.duration_s = 5; r.segments.push_back(s);
  s = seg(SegmentKind::accelerate); s.to_speed = 15; s.duration_s = 10; r.segments.push_back(s);
  s = seg(SegmentKind::turn); s.angle = 90 * kDeg; s.radius = 40; r.segments.push_back(s);
  s = seg(SegmentKind::climb); s.grade = 4 * kDeg; s.duration_s = 20; r.segments.push_back(s);
  s = seg(SegmentKind::lane_change); s.width = -3.5; s.duration_s = 5; r.segments.push_back(s);
  s = seg(SegmentKind::turn); s.angle = -120 * kDeg; s.radius = 60; r.segments.push_back(s);
  s = seg(SegmentKind::cruise); s.duration_s = 5; r.segments.push_back(s);
  s = seg(SegmentKind::stop); s.duration_s = 3; r.segments.push_back(s);
  return r;
}
}  // namespace

TEST(DrivesimRoute, HeadingAndSpeedFollowSegments) {
  const Route r = test_route();
  const RouteProfile p(r);
  const Motion end = p.at(p.duration());
  EXPECT_NEAR(end.v, 0.0, 1e-12);
  EXPECT_NEAR(std::remainder(end.rpy(2) - (30 - 30) * kDeg, 2 * units::kPi), 0.0, 1e-9);
  // Yaw rate integrates to yaw (numerically) over the whole route.
  double psi = r.heading, dt = 1e-3;
  for (double t = 0; t < p.duration() - dt / 2; t += dt) psi += 0.5 * (p.at(t).rpy_dot(2) + p.at(t + dt).rpy_dot(2)) * dt;
  EXPECT_NEAR(psi, p.at(p.duration()).rpy(2), 1e-6);
  // Speed rate integrates to speed.
  double v = 0;
  for (double t = 0; t < p.duration() - dt / 2; t += dt) v += 0.5 * (p.at(t).v_dot + p.at(t + dt).v_dot) * dt;
  EXPECT_NEAR(v, 0.0, 1e-6);
}

TEST(DrivesimRoute, RejectsTurnAtStandstill) {
  Route r;
  Segment s;
  s.kind = SegmentKind::turn;
  s.angle = 1;
  s.radius = 10;
  s.line = 7;
  r.segments.push_back(s);
  EXPECT_THROW(RouteProfile{r}, std::invalid_argument);
}

TEST(DrivesimRoute, ErrorFreeImuNavigatesWithTruthThroughMountingAndLeverArm) {
  DriveSimConfig cfg;
  cfg.route = test_route();
  cfg.noise = NoiseSpec{};  // no noise, no drift, no quantisation
  cfg.imu_rate_hz = 400;
  cfg.mounting_rpy = Vec3(2 * kDeg, -1 * kDeg, 90 * kDeg);
  cfg.lever_arm = Vec3(0.8, -0.3, -0.5);
  cfg.reference.rate_hz = 0;
  cfg.gnss.rate_hz = 0;
  const Mat3 C_mb = ins::dcm_from_rpy(cfg.mounting_rpy);

  ins::Strapdown nav;
  ins::RateIntegrator integ;
  bool started = false;
  SimTruth last;
  double t_prev = 0;
  DriveSinks sinks;
  sinks.truth = [&](const SimTruth& tr) {  // called after the IMU sample of the same instant
    last = tr;
    if (!started) {
      started = true;
      // Transfer the reference state to the MEMS IMU: position + C_nb·r, velocity + C_nb(ω×r).
      ins::NavState s;
      s.t = tr.t;
      s.lat = tr.lat;
      s.lon = tr.lon;
      s.h = tr.h;
      ins::geodetic_add_ned(s.lat, s.lon, s.h, tr.C_nb * cfg.lever_arm);
      s.v = tr.v_ned + tr.C_nb * (tr.w_ib_b.cross(cfg.lever_arm));
      s.q_nb = ins::Quat(tr.C_nb * C_mb);
      nav.reset(s);
    }
  };
  sinks.imu = [&](const SimImu& m) {
    Vec3 dth, dv;
    const double dt = m.t - t_prev;
    integ(m.gyro, m.accel, dt > 0 ? dt : 1.0 / cfg.imu_rate_hz, dth, dv);
    if (started) nav.update(dth, dv, dt);
    t_prev = m.t;
  };
  simulate_drive(cfg, sinks);
  const ins::NavState& s = nav.state();
  double lat = s.lat, lon = s.lon, h = s.h;
  const Mat3 C_nb = s.C_nb() * C_mb.transpose();
  ins::geodetic_add_ned(lat, lon, h, -(C_nb * cfg.lever_arm));
  const Vec3 dp = ins::geodetic_diff_ned(lat, lon, h, last.lat, last.lon, last.h);
  EXPECT_LT(dp.norm(), 0.05) << dp.transpose();
  EXPECT_LT(ins::rotvec_from_dcm(C_nb * last.C_nb.transpose()).norm(), 1e-5);
  EXPECT_LT((s.v - last.v_ned).norm(), 0.01);
}

// A vehicle's angular rate is continuous: the roll rate −k_r(v̇ψ̇ + vψ̈) and the pitch rate may not
// step where one manoeuvre ends and the next begins (a lane change whose ψ̈ started and ended at
// ±rate·w stepped the roll rate by k_r·v·rate·w, here 6.6e-3 rad/s). Over a step of h the rates
// change by at most |ω̈|max·h; this route's largest attitude acceleration is below 1 rad/s².
TEST(DrivesimRoute, AttitudeRatesAreContinuousAcrossManoeuvres) {
  const RouteProfile p(test_route());
  const double h = 1e-4;
  double worst[3] = {0, 0, 0}, at[3] = {0, 0, 0};
  Motion prev = p.at(0);
  for (long k = 1; k * h <= p.duration(); ++k) {
    const Motion m = p.at(k * h);
    for (int i = 0; i < 3; ++i) {
      const double d = std::abs(m.rpy_dot(i) - prev.rpy_dot(i));
      if (d > worst[i]) worst[i] = d, at[i] = k * h;
    }
    prev = m;
  }
  for (int i = 0; i < 3; ++i) EXPECT_LT(worst[i], 1.0 * h) << "rate " << i << " steps at t = " << at[i];
}

// The lane change keeps its meaning: the lateral offset is `width` (small angles; the exact offset
// v·∫sin δψ differs by ~δψ²/6, under 1 % here), the heading returns, and the peak yaw rate stays
// of the order of the lateral acceleration a lane change of that width and duration needs.
TEST(DrivesimRoute, LaneChangeOffsetsByItsWidth) {
  for (double width : {3.5, -3.0}) {
    Route r;
    r.heading = 10 * kDeg;
    Segment s;
    s.kind = SegmentKind::accelerate; s.to_speed = 20; s.duration_s = 10; r.segments.push_back(s);
    s = Segment{}; s.kind = SegmentKind::lane_change; s.width = width; s.duration_s = 4; r.segments.push_back(s);
    s = Segment{}; s.kind = SegmentKind::cruise; s.duration_s = 2; r.segments.push_back(s);
    const RouteProfile p(r);
    double y = 0, peak_rate = 0;
    const double h = 1e-4;
    for (double t = 10; t < 14 - h / 2; t += h) {
      const Motion a = p.at(t), b = p.at(t + h);
      y += 0.5 * (a.v * std::sin(a.rpy(2) - r.heading) + b.v * std::sin(b.rpy(2) - r.heading)) * h;
      peak_rate = std::max(peak_rate, std::abs(a.rpy_dot(2)));
    }
    EXPECT_NEAR(y, width, 0.01 * std::abs(width));
    EXPECT_NEAR(p.at(p.duration()).rpy(2), r.heading, 1e-12);
    // Lateral acceleration v·ψ̇: between the sine profile's 2π·W/T² and twice that.
    const double a_sine = 2 * units::kPi * std::abs(width) / 16;
    EXPECT_GT(20 * peak_rate, a_sine);
    EXPECT_LT(20 * peak_rate, 2 * a_sine);
  }
}
