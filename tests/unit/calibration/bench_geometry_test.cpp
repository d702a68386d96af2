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

}  // namespace
}  // namespace calbench
