// The hand-turn simulator of `calbench simulate multipos` (calibration/multipos/multipos_sim.hpp):
// the turn integrates to its stated rotation, the poses' up vectors are unit, true and spread over
// the sphere, the errors are applied in the spec's convention, and the white noise on a pose is
// K × the class's density × √rate.
#include "calibration/multipos/multipos_sim.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "common/units.hpp"

namespace calbench::multipos {
namespace {

using units::kDeg;

// The ICM-42688-P class's figures (bench/imu_classes/icm42688p.toml), SI.
NoiseSpec icm_noise() {
  NoiseSpec n;
  n.gyro.white_density = 2.8e-3 * kDeg;
  n.gyro.drift_sigma = 10 * units::kDegPerHour;
  n.gyro.drift_tau_s = 100;
  n.gyro.range = 2000 * kDeg;
  n.gyro.lsb = 0.061 * kDeg;
  n.accel.white_density = 70e-6 * units::kG0;
  n.accel.drift_sigma = 0.1 * units::kMilliG;
  n.accel.drift_tau_s = 100;
  n.accel.range = 16 * units::kG0;
  n.accel.lsb = units::kG0 / 2048;
  return n;
}

TEST(MultiposSim, TurnIntegratesToTheStatedRotation) {
  const Vec3 axis = Vec3(0.3, -0.5, 0.8).normalized();
  for (const double deg : {60.0, -95.0, 150.0})
    for (const std::size_t n : {100u, 173u, 300u}) {
      const double angle = deg * kDeg, rate = 100.0;
      double sum = 0, trapezoid = 0, last = 0;
      Mat3 C = Mat3::Identity();
      for (std::size_t k = 1; k <= n; ++k) {
        const TurnStep s = turn_step(angle, n, k, rate);
        sum += s.dangle;
        trapezoid += 0.5 * (last + s.rate) / rate;
        last = s.rate;
        C = C * Eigen::AngleAxisd(s.dangle, axis).toRotationMatrix();
      }
      EXPECT_NEAR(sum, angle, 1e-12) << deg << " " << n;
      EXPECT_NEAR(last, 0.0, 1e-12);  // the turn ends at rest
      // The sampled rates integrate to the angle too (the profile is smooth: trapezoid to ~1e-6).
      EXPECT_NEAR(trapezoid, angle, 1e-6 * std::abs(angle)) << deg << " " << n;
      EXPECT_LT((C - Eigen::AngleAxisd(angle, axis).toRotationMatrix()).norm(), 1e-12);
    }
}

TEST(MultiposSim, PlanKeepsTheHandsLimits) {
  HandTurnConfig h;
  h.opening_still_s = 20;
  const HandTurnPlan p = plan_hand_turns(h, 100, 7);
  ASSERT_EQ(p.poses.size(), 24u);
  ASSERT_EQ(p.turns.size(), 23u);
  EXPECT_NEAR(p.poses[0].t1 - p.poses[0].t0, 20 - 0.01, 1e-9);
  for (std::size_t k = 1; k < p.poses.size(); ++k) {
    const double d = (p.poses[k].i1 - p.poses[k].i0) / 100.0;
    EXPECT_GE(d, 1.0 - 0.005);
    EXPECT_LE(d, 3.0 + 0.005);
    EXPECT_EQ(p.poses[k].i0, p.turns[k - 1].i1);  // back to back, no gap
    EXPECT_EQ(p.turns[k - 1].i0, p.poses[k - 1].i1);
  }
  for (const SimTurn& t : p.turns) {
    const double d = (t.i1 - t.i0) / 100.0;
    EXPECT_GE(d, 1.0 - 0.005);
    EXPECT_LE(d, 3.0 + 0.005);
    EXPECT_GE(std::abs(t.angle), 60 * kDeg);
    EXPECT_LE(std::abs(t.angle), 150 * kDeg);
    EXPECT_NEAR(t.axis.norm(), 1.0, 1e-12);
  }
  EXPECT_EQ(p.samples, p.poses.back().i1);
  EXPECT_LT((p.poses[0].up_body - Vec3(0, 0, 1)).norm(), 1e-12);  // lying flat at the start
}

TEST(MultiposSim, PosesCoverTheSphereOverSeeds) {
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    const HandTurnPlan p = plan_hand_turns(HandTurnConfig{}, 100, seed);
    Vec3 lo = Vec3::Constant(2), hi = Vec3::Constant(-2), best_turn = Vec3::Zero();
    std::vector<Vec3> dirs;  // distinct directions, 10° apart as the fit counts them
    int tilted = 0;
    for (const SimPose& s : p.poses) {
      EXPECT_NEAR(s.up_body.norm(), 1.0, 1e-12);
      lo = lo.cwiseMin(s.up_body);
      hi = hi.cwiseMax(s.up_body);
      tilted += s.up_body.cwiseAbs().maxCoeff() < std::cos(20 * kDeg);
      bool seen = false;
      for (const Vec3& d : dirs) seen = seen || s.up_body.dot(d) > std::cos(10 * kDeg);
      if (!seen) dirs.push_back(s.up_body);
    }
    for (const SimTurn& t : p.turns) best_turn = best_turn.cwiseMax((t.angle * t.axis).cwiseAbs());
    for (int i = 0; i < 3; ++i) {
      EXPECT_GT(hi(i), 0.8) << "seed " << seed << " axis " << i << " never up";
      EXPECT_LT(lo(i), -0.8) << "seed " << seed << " axis " << i << " never down";
      EXPECT_GE(best_turn(i), 45 * kDeg) << "seed " << seed << " no 45° turn about axis " << i;
    }
    EXPECT_GE(dirs.size(), 20u) << "seed " << seed;
    EXPECT_GE(tilted, 4) << "seed " << seed;
  }
}

TEST(MultiposSim, ErrorsInTheSpecsConventionAndTrueUpVectors) {
  MultiposSimConfig c;
  c.site = Site{48.0, 0.0, 0.0};
  c.seed = 3;
  c.noise = hand_turn_noise(icm_noise(), 0.0, c.rate_hz);
  c.noise.gyro.drift_sigma = c.noise.accel.drift_sigma = 0;  // errors alone
  c.truth = draw_random_unit(5, UnitSpread{0.5 * kDeg, 20 * units::kMilliG, 5e-3, 1.25e-2, 5e-3, 1e-2});
  const double g = hand_turn_gravity(c.site);
  EXPECT_NEAR(g, 9.8089, 1e-3);  // WGS-84 normal gravity at 48°
  std::vector<MultiposSimSample> ss;
  const HandTurnPlan p = simulate_multipos(c, [&](const MultiposSimSample& s) { ss.push_back(s); });
  ASSERT_EQ(ss.size(), p.samples);
  for (std::size_t i = 0; i < ss.size(); ++i) {
    const MultiposSimSample& s = ss[i];
    EXPECT_DOUBLE_EQ(s.t, i / 100.0);
    EXPECT_LT((s.gyro - c.truth.gyro.measure(s.w_true)).norm(), 1e-12);
    EXPECT_LT((s.accel - c.truth.accel.measure(s.f_true)).norm(), 1e-12);
    EXPECT_NEAR(s.f_true.norm(), g, 1e-9);
    if (s.pose >= 0) {
      EXPECT_LT((s.f_true / g - p.poses[s.pose].up_body).norm(), 1e-9);
      EXPECT_NEAR(s.w_true.norm(), units::kEarthRate, 1e-12);  // still: the Earth's rate alone
      // Its vertical part: Ω sin φ along up.
      EXPECT_NEAR(s.w_true.dot(p.poses[s.pose].up_body), units::kEarthRate * std::sin(48 * kDeg), 1e-9);
    }
  }
}

TEST(MultiposSim, TheWanderIsWhatTheOutputCarriesBeyondTheErrors) {
  MultiposSimConfig c;
  c.seed = 4;
  c.noise = hand_turn_noise(icm_noise(), 0.0, c.rate_hz);  // no white noise: the wander alone
  c.truth = draw_random_unit(6, UnitSpread{0.5 * kDeg, 20 * units::kMilliG, 5e-3, 1.25e-2, 5e-3, 1e-2});
  double moved = 0;
  Vec3 first = Vec3::Constant(std::nan(""));
  simulate_multipos(c, [&](const MultiposSimSample& s) {
    EXPECT_LT((s.gyro - c.truth.gyro.measure(s.w_true) - s.gyro_wander).norm(), 1e-15);
    EXPECT_LT((s.accel - c.truth.accel.measure(s.f_true) - s.accel_wander).norm(), 1e-13);
    if (std::isnan(first(0))) first = s.accel_wander;
    moved = std::max(moved, (s.accel_wander - first).norm());
  });
  EXPECT_GT(moved, 1e-6);  // it wanders (0.1 mg over τ = 100 s)
  EXPECT_LT(moved, 10 * units::kMilliG);
}

TEST(MultiposSim, WhiteNoiseOnAPoseIsTheFactorTimesTheClassDensity) {
  for (const double K : {1.0, 2.5}) {
    MultiposSimConfig c;
    c.seed = 11;
    c.hand.poses = 3;
    c.hand.opening_still_s = 100;
    c.noise = hand_turn_noise(icm_noise(), K, c.rate_hz);
    c.truth = draw_random_unit(2, UnitSpread{0.5 * kDeg, 20 * units::kMilliG, 5e-3, 1.25e-2, 5e-3, 1e-2});
    Vec3 pg = Vec3::Zero(), pa = Vec3::Zero(), sg = Vec3::Zero(), sa = Vec3::Zero();
    std::size_t n = 0;
    bool first = true;
    simulate_multipos(c, [&](const MultiposSimSample& s) {
      if (s.pose != 0) return;
      if (!first) {  // first differences: the slow bias wander drops out
        sg += (s.gyro - pg).cwiseAbs2();
        sa += (s.accel - pa).cwiseAbs2();
        ++n;
      }
      first = false;
      pg = s.gyro;
      pa = s.accel;
    });
    ASSERT_GT(n, 9000u);
    const double want_g = K * 2.8e-3 * kDeg * 10, want_a = K * 70e-6 * units::kG0 * 10;  // × √100 Hz
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(std::sqrt(sg(i) / (2.0 * n)) / want_g, 1.0, 0.03) << "K " << K << " gyro " << i;
      EXPECT_NEAR(std::sqrt(sa(i) / (2.0 * n)) / want_a, 1.0, 0.03) << "K " << K << " accel " << i;
    }
  }
}

}  // namespace
}  // namespace calbench::multipos
