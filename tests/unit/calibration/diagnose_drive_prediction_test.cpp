// The drive diagnosis predicts the MEMS output from the reference trajectory
// (calibration/diagnosis/drive_data.hpp). With a perfect sensor and a perfect reference the
// prediction must match what the MEMS measured far below any effect the diagnosis looks for; an
// injected effect must show in the residual with its own size.
#include <gtest/gtest.h>

#include "calibration/diagnosis/drive_data.hpp"
#include "calibration/drive_sim/drive_simulator.hpp"
#include "calibration/effects/effect_registry.hpp"
#include "calibration/ins/strapdown.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

drivesim::Route test_route() {
  using drivesim::Segment;
  using drivesim::SegmentKind;
  drivesim::Route r;
  r.lat = 48.1 * units::kDeg;
  r.lon = 11.6 * units::kDeg;
  r.h = 500;
  r.heading = 0.3;
  auto seg = [&](SegmentKind k) {
    Segment s;
    s.kind = k;
    return s;
  };
  Segment s = seg(SegmentKind::stop);
  s.duration_s = 3;
  r.segments.push_back(s);
  s = seg(SegmentKind::accelerate);
  s.to_speed = 12;
  s.duration_s = 6;
  r.segments.push_back(s);
  s = seg(SegmentKind::turn);
  s.angle = 1.6;
  s.radius = 20;
  r.segments.push_back(s);
  s = seg(SegmentKind::climb);
  s.grade = 0.08;
  s.duration_s = 10;
  r.segments.push_back(s);
  s = seg(SegmentKind::turn);
  s.angle = -2.5;
  s.radius = 30;
  r.segments.push_back(s);
  s = seg(SegmentKind::stop);
  s.duration_s = 2;
  r.segments.push_back(s);
  return r;
}

struct Residual {
  double gyro_max = 0, accel_max = 0, gyro_rms_turn = 0;
  double gyro_block_max = 0, accel_block_max = 0;  // ~1 s blocks, what the diagnosis judges
  int subs = 0;
};

Residual run(const EffectTerms& fx, bool perfect, DriveDiagData* out = nullptr) {
  drivesim::DriveSimConfig cfg;
  cfg.route = test_route();
  cfg.imu_rate_hz = 200;
  cfg.mounting_rpy = Vec3(0.01, -0.02, 1.5);
  cfg.lever_arm = Vec3(-1.0, 0.3, -0.4);
  cfg.reference.rate_hz = 50;
  if (perfect) {
    cfg.noise = NoiseSpec{};
    cfg.reference.sigma_pos_m = cfg.reference.sigma_vel_m_s = cfg.reference.sigma_att_rad = 0;
  }
  cfg.gnss.rate_hz = 0;
  cfg.effects = fx;
  DriveDiagBuilder b(ins::dcm_from_rpy(cfg.mounting_rpy), cfg.lever_arm);
  ins::RateIntegrator integ;
  drivesim::DriveSinks sinks;
  sinks.imu = [&](const drivesim::SimImu& m) {
    DriveImuSample s;
    s.t = m.t;
    s.dt = 1.0 / cfg.imu_rate_hz;
    integ(m.gyro, m.accel, s.dt, s.dtheta, s.dv);
    b.imu(s);
  };
  sinks.reference = [&](const drivesim::SimRef& r) {
    DriveRefEpoch e;
    e.t = r.t;
    e.lat = r.lat;
    e.lon = r.lon;
    e.h = r.h;
    e.v_ned = r.v_ned;
    e.rpy = r.rpy;
    b.reference(e);
  };
  drivesim::simulate_drive(cfg, sinks);
  DriveDiagData d = b.finish();
  Residual res;
  res.subs = static_cast<int>(d.subs.size());
  double ss = 0;
  int n = 0;
  // Skip the first/last interval (one-sided derivatives) and the IMU's start-up sample.
  for (std::size_t j = 2; j + 2 < d.subs.size(); ++j) {
    const SubBlock& s = d.subs[j];
    res.gyro_max = std::max(res.gyro_max, (s.gyro - s.w).cwiseAbs().maxCoeff());
    res.accel_max = std::max(res.accel_max, (s.accel - s.f).cwiseAbs().maxCoeff());
    if (s.w.norm() > 0.1) {
      ss += (s.gyro - s.w).squaredNorm();
      ++n;
    }
  }
  res.gyro_rms_turn = n ? std::sqrt(ss / n) : 0;
  for (std::size_t k = 1; k + 1 < d.parents.size(); ++k) {
    const ParentBlock& p = d.parents[k];
    Vec3 g = Vec3::Zero(), a = Vec3::Zero();
    for (int j = p.first; j < p.first + p.count; ++j) {
      g += d.subs[j].duration * (d.subs[j].gyro - d.subs[j].w);
      a += d.subs[j].duration * (d.subs[j].accel - d.subs[j].f);
    }
    res.gyro_block_max = std::max(res.gyro_block_max, (g / p.duration).cwiseAbs().maxCoeff());
    res.accel_block_max = std::max(res.accel_block_max, (a / p.duration).cwiseAbs().maxCoeff());
  }
  if (out) *out = d;
  return res;
}

TEST(DiagnoseDrivePrediction, PerfectSensorAndReferenceMatchPrediction) {
  DriveDiagData d;
  const Residual r = run(EffectTerms{}, true, &d);
  ASSERT_GT(r.subs, 1500);  // ~40 s at 50 Hz
  EXPECT_GE(d.parents.size(), 35u);
  // Per 0.02 s interval a few °/h and < 1 mg (second-order terms of the interval-mean
  // prediction, the lever arm's ω̇ by differences); per ~1 s block far below the block noise of
  // ~30 °/h and ~1 mg.
  EXPECT_LT(r.gyro_max, 3 * units::kDegPerHour);
  EXPECT_LT(r.accel_max, 1 * units::kMilliG);
  EXPECT_LT(r.gyro_block_max, 0.5 * units::kDegPerHour);
  EXPECT_LT(r.accel_block_max, 0.05 * units::kMilliG);
  // Motion classes were recognised.
  int turning = 0, stationary = 0;
  for (const auto& i : d.info) {
    turning += i.motion == MotionClass::turning;
    stationary += i.motion == MotionClass::stationary;
  }
  EXPECT_GT(turning, 5);
  EXPECT_GT(stationary, 2);
}

TEST(DiagnoseDrivePrediction, TimeOffsetShowsAsRateDerivative) {
  EffectTerms fx;
  effect_vector<1>(fx, EffectId::time_offset)(0) = 0.01;
  DriveDiagData d;
  run(fx, true, &d);
  // measured − predicted ≈ −τ·ω̇ on every interval where the rate changes.
  double num = 0, den = 0;
  for (std::size_t j = 2; j + 2 < d.subs.size(); ++j) {
    const SubBlock& s = d.subs[j];
    num += (s.gyro - s.w).dot(-s.dw);
    den += s.dw.squaredNorm();
  }
  ASSERT_GT(den, 0);
  EXPECT_NEAR(num / den, 0.01, 0.001);
}

TEST(DiagnoseDrivePrediction, LeverArmOffsetShowsInAccelerometers) {
  EffectTerms fx;
  effect_vector<3>(fx, EffectId::lever_arm) = Vec3(0.0, 0.1, 0.0);
  DriveDiagData d;
  const Residual r = run(fx, true, &d);
  EXPECT_LT(r.gyro_max, 3 * units::kDegPerHour);  // the gyros do not see a lever arm
  double num = 0, den = 0;
  for (std::size_t j = 2; j + 2 < d.subs.size(); ++j) {
    const SubBlock& s = d.subs[j];
    const Vec3 x = lever_arm_force(Vec3(0, 1, 0), s.w, s.dw);
    num += (s.accel - s.f).dot(x);
    den += x.squaredNorm();
  }
  ASSERT_GT(den, 0);
  EXPECT_NEAR(num / den, 0.1, 0.01);
}

}  // namespace
}  // namespace calbench
