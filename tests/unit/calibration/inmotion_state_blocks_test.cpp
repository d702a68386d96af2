// The in-motion state blocks (state_blocks.hpp): declared once, offsets computed from the list.
// These tests check that the declarations reproduce the paper's layout (eq 11) and that the offset
// rule places an extra block after the others without renumbering anything.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "calibration/inmotion/state_layout.hpp"
#include "common/units.hpp"

using namespace calbench;
using namespace calbench::inmotion;

TEST(InMotionStateBlocks, OffsetsAreContiguousInDeclarationOrder) {
  int next = 0;
  for (const BlockSpec& b : block_specs()) {
    EXPECT_EQ(offset_of(b.id), next) << b.name;
    EXPECT_EQ(size_of(b.id), b.size) << b.name;
    next += b.size;
  }
  EXPECT_EQ(next, kStatesAug);
  // The paper's offsets, which the Jacobian code and stored series rely on.
  EXPECT_EQ(kMg, 15);
  EXPECT_EQ(kMount, 33);
  EXPECT_EQ(kDa, 39);
  EXPECT_EQ(kStates, 42);
  EXPECT_EQ(kDaAux, 45);
}

TEST(InMotionStateBlocks, AuxBlocksFollowTheDefaultLayout) {
  for (const BlockSpec& b : block_specs()) EXPECT_EQ(b.aux, offset_of(b.id) >= kStates) << b.name;
}

TEST(InMotionStateBlocks, ColumnNamesComeFromTheDeclarations) {
  const auto& n = state_names();
  EXPECT_EQ(n[kPos], "lat_deg");
  EXPECT_EQ(n[kMg + 1], "gyro_M_xy_ppm");
  EXPECT_EQ(n[kMount + 2], "mount_yaw_deg");
  EXPECT_EQ(n[kDa + 2], "accel_drift_z_mg");
  EXPECT_EQ(aux_state_names()[3], "accel_drift_aux_x_mg_s");
  std::set<std::string> unique(n.begin(), n.end());
  unique.insert(aux_state_names().begin(), aux_state_names().end());
  EXPECT_EQ(static_cast<int>(unique.size()), kStatesAug);  // every column named, none twice
}

TEST(InMotionStateBlocks, DisplayFactorsAreTheSeriesUnits) {
  const auto& s = block_specs();
  EXPECT_EQ(s[static_cast<int>(Block::bg)].si_per_display, units::kDegPerHour);
  EXPECT_EQ(s[static_cast<int>(Block::ba)].si_per_display, units::kMilliG);
  EXPECT_EQ(s[static_cast<int>(Block::Mg)].si_per_display, units::kPpm);
  EXPECT_EQ(s[static_cast<int>(Block::att)].si_per_display, units::kDeg);
  EXPECT_FALSE(s[static_cast<int>(Block::mount)].sensor);  // the smoother leaves navigation and mounting
  EXPECT_TRUE(s[static_cast<int>(Block::da_aux)].sensor);
}

// An extra constant 3-state block declared only here (e.g. a g-sensitivity column) goes after the
// layout; a Kalman filter built on the computed offsets estimates it through its own H while the
// other blocks keep their places.
TEST(InMotionStateBlocks, ExtraBlockGetsComputedOffsetAndIsEstimated) {
  constexpr std::array<int, 3> sizes = {kStatesAug, 3, 0};  // the layout, the extra block, end
  constexpr auto off = offsets_from_sizes(sizes);
  static_assert(off[1] == 48 && off[2] == 51 && off[3] == 51);
  constexpr int n = off[2], k = off[1];
  using Vec = Eigen::Matrix<double, n, 1>;
  using Mat = Eigen::Matrix<double, n, n>;
  const Eigen::Vector3d truth(0.3, -0.2, 0.05);
  Vec x = Vec::Zero();
  Mat P = Mat::Identity();
  const double r = 1e-4;
  for (int e = 0; e < 50; ++e) {
    // The extra block's H: z = c + δ (observes the constant block directly; the other states not).
    Eigen::Matrix<double, 3, n> H = Eigen::Matrix<double, 3, n>::Zero();
    H.block<3, 3>(0, k).setIdentity();
    const Eigen::Vector3d z = truth + 0.01 * Eigen::Vector3d(std::sin(e), std::cos(3 * e), std::sin(7 * e));
    const Eigen::Matrix3d S = H * P * H.transpose() + r * Eigen::Matrix3d::Identity();
    const Eigen::Matrix<double, n, 3> K = P * H.transpose() * S.inverse();
    x += K * (z - H * x);
    P = (Mat::Identity() - K * H) * P;
  }
  EXPECT_NEAR((x.segment<3>(k) - truth).norm(), 0.0, 5e-3);
  EXPECT_EQ(x.head<kStatesAug>().norm(), 0.0);       // unobserved blocks untouched
  EXPECT_NEAR(P(kMg, kMg), 1.0, 0.0);                // and their covariance too
}
