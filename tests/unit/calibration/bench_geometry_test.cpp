// The table geometry of the bench plans (calibration/bench_plan.hpp): the six fixtures — three cube
// faces and three faces of a 45° wedge — are rotations that put the named IMU direction on the
// inner (rate) axis, a rate step about the inner axis is seen by the IMU along that direction, and
// table angles solved for an orientation give it back.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "calibration/bench_kinematics.hpp"
#include "calibration/bench_plan.hpp"
#include "calibration/earth.hpp"

namespace calbench {
namespace {

TEST(BenchGeometry, MountsAreRotationsPuttingTheirDirectionOnTheInnerAxis) {
  const Vec3 expected[kMountCount] = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ(),
                                      (Vec3::UnitX() + Vec3::UnitY()) / std::sqrt(2.0),
                                      (Vec3::UnitY() + Vec3::UnitZ()) / std::sqrt(2.0),
                                      (Vec3::UnitZ() + Vec3::UnitX()) / std::sqrt(2.0)};
  for (int m = 0; m < kMountCount; ++m) {
    const Mat3 C = mount_rotation(m);
    EXPECT_LT((C * C.transpose() - Mat3::Identity()).norm(), 1e-12) << mount_name(m);
    EXPECT_NEAR(C.determinant(), 1.0, 1e-12) << mount_name(m);
    EXPECT_LT((mount_direction(m) - expected[m]).norm(), 1e-12) << mount_name(m);
    EXPECT_LT((C * expected[m] - Vec3::UnitZ()).norm(), 1e-12) << mount_name(m);  // onto platform z
    EXPECT_EQ(mount_from_name(mount_name(m)), m);
    EXPECT_EQ(mount_from_name(std::string("+") + mount_name(m)), m);
  }
  EXPECT_EQ(mount_from_name("xz"), -1);  // the wedge faces are xy, yz, zx
  EXPECT_EQ(mount_from_name("-x"), -1);
  EXPECT_EQ(mount_from_name(""), -1);
}

TEST(BenchGeometry, ARateStepTurnsTheMountDirection) {
  const SiteEarth earth(Site{55.75, 37.62, 150.0});
  const double rate = 300.0 * M_PI / 180.0;
  for (int m = 0; m < kMountCount; ++m)
    for (double outer : {0.0, 0.5 * M_PI, 1.0}) {
      const BenchKinematics k = bench_kinematics(earth, AxisState{outer, 0, 0}, AxisState{0.7, rate, 0}, m);
      const Vec3 earth_b = k.C_b_l.transpose() * earth.w_ie_ned;
      EXPECT_LT((k.w_ib_b - earth_b - rate * mount_direction(m)).norm(), 1e-12) << mount_name(m);
      // Gravity seen by the IMU is the level frame's, rotated.
      EXPECT_NEAR(k.f_b.norm(), earth.g_ned.norm(), 1e-12);
    }
  // On a wedge two IMU axes turn at once, equally: the product ω_i·ω_j is half the rate squared.
  const BenchKinematics k = bench_kinematics(earth, AxisState{0, 0, 0}, AxisState{0, rate, 0}, mount_from_name("xy"));
  const Vec3 w = k.w_ib_b - k.C_b_l.transpose() * earth.w_ie_ned;
  EXPECT_NEAR(w.x() * w.y(), 0.5 * rate * rate, 1e-9);
  EXPECT_NEAR(w.z(), 0.0, 1e-12);
}

TEST(BenchGeometry, TableAnglesSolvedForAnOrientationGiveItBack) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ang(-M_PI, M_PI);
  for (int m = 0; m < kMountCount; ++m)
    for (int i = 0; i < 20; ++i) {
      const double o = ang(rng), n = ang(rng);
      const Mat3 C = imu_attitude(o, n, m);
      double o2 = 0, n2 = 0;
      ASSERT_TRUE(solve_table_angles(C, m, o2, n2)) << mount_name(m);
      EXPECT_LT((imu_attitude(o2, n2, m) - C).norm(), 1e-9) << mount_name(m);
    }
  // An orientation with the mount direction along north (the outer axis) is not reachable.
  const Mat3 along_north = Eigen::Quaterniond::FromTwoVectors(mount_direction(3), Vec3::UnitX()).toRotationMatrix();
  double o = 0, n = 0;
  EXPECT_FALSE(solve_table_angles(along_north, 3, o, n));
}

// The angular acceleration of the IMU (both axes accelerating, the outer carrying the inner round) is
// the time derivative of its angular rate.
// Both axes on constant accelerations (rate0, accel each), at time t, mount m.
BenchKinematics accelerating(const SiteEarth& earth, double t, int m, double outer_rate0, double outer_accel,
                             double inner_rate0, double inner_accel) {
  const AxisState o{0.3 + outer_rate0 * t + 0.5 * outer_accel * t * t, outer_rate0 + outer_accel * t, outer_accel};
  const AxisState n{-1.1 + inner_rate0 * t + 0.5 * inner_accel * t * t, inner_rate0 + inner_accel * t, inner_accel};
  return bench_kinematics(earth, o, n, m);
}

TEST(BenchGeometry, AngularAccelerationIsTheDerivativeOfTheRate) {
  const SiteEarth earth(Site{55.75, 37.62, 150.0});
  auto at = [&](double t, int m) { return accelerating(earth, t, m, 0.7, 2.0, 3.0, -5.0); };
  const double h = 1e-5;
  for (int m = 0; m < kMountCount; ++m) {
    const Vec3 fd = (at(h, m).w_ib_b - at(-h, m).w_ib_b) / (2 * h);
    EXPECT_LT((at(0, m).dw_ib_b - fd).norm(), 1e-6) << mount_name(m) << ": " << at(0, m).dw_ib_b.transpose() << " vs "
                                                    << fd.transpose();
  }
}

// A unit off the centre of a multi-unit fixture (issue 21): the same rotation in its own axes, and
// the specific force at its origin — the second derivative of its position on the turning platform,
// less gravity (the local-level frame taken as fixed: earth rate's share, ~1e-4 m/s², is within the
// tolerance).
TEST(BenchGeometry, ASlotOffTheCentreFeelsItsOwnSpecificForce) {
  const SiteEarth earth(Site{55.75, 37.62, 150.0});
  SlotPose slot;
  slot.C_f_s = (Eigen::AngleAxisd(0.4, Vec3::UnitZ()) * Eigen::AngleAxisd(-0.2, Vec3::UnitX())).toRotationMatrix();
  slot.r_f = Vec3(0.08, -0.03, 0.02);
  auto at = [&](double t, int m) { return accelerating(earth, t, m, 0.5, 1.5, 5.0, -4.0); };
  const double h = 1e-4;
  for (int m = 0; m < kMountCount; ++m) {
    const BenchKinematics c = at(0, m), s = slot_kinematics(c, slot);
    const Vec3 acc_l = (at(h, m).C_b_l * slot.r_f - 2 * c.C_b_l * slot.r_f + at(-h, m).C_b_l * slot.r_f) / (h * h);
    const Vec3 f_s = (c.C_b_l * slot.C_f_s).transpose() * (acc_l - earth.g_ned);
    EXPECT_LT((s.f_b - f_s).norm(), 2e-4) << mount_name(m) << ": " << s.f_b.transpose() << " vs " << f_s.transpose();
    EXPECT_GT((s.f_b - slot.C_f_s.transpose() * c.f_b).norm(), 0.5);  // the lever arm is felt (~1 m/s²)
    EXPECT_LT((s.w_ib_b - slot.C_f_s.transpose() * c.w_ib_b).norm(), 1e-15);
    EXPECT_LT((s.C_b_l - c.C_b_l * slot.C_f_s).norm(), 1e-15);
  }
  // At the centre with the fixture's axes: the centre's kinematics.
  const BenchKinematics c = at(0, 2), s = slot_kinematics(c, SlotPose{});
  EXPECT_LT((s.f_b - c.f_b).norm(), 1e-15);
}

}  // namespace
}  // namespace calbench
