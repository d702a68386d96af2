// The in-motion state blocks (state_blocks.hpp): declared once, offsets computed from the list.
// These tests check that the declarations reproduce the paper's layout (eq 11) and that the offset
// rule places an extra block after the others without renumbering anything.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "calibration/inmotion/inmotion_filter.hpp"
#include "common/units.hpp"

using namespace calbench;
using namespace calbench::inmotion;

namespace {
// Every built-in block active: the exp-cosine aux states with an exp-cosine model on one axis.
StateLayout full_layout() {
  InMotionConfig cfg;
  cfg.gyro_drift = std::array<DriftPrior, 3>{DriftPrior{1e-5, 100, true, 0.01}, DriftPrior{1e-5, 100}, DriftPrior{1e-5, 100}};
  return make_layout(cfg);
}
}  // namespace

TEST(InMotionStateBlocks, OffsetsAreContiguousInDeclarationOrder) {
  const StateLayout L = full_layout();
  int next = 0;
  for (const BlockSpec& b : block_specs()) {
    EXPECT_EQ(L.offset(b.id), next) << b.name;
    next += b.size;
  }
  EXPECT_EQ(next, L.size());
  // The paper's offsets (eq 11), which stored series rely on.
  EXPECT_EQ(L.offset(Block::Mg), 15);
  EXPECT_EQ(L.offset(Block::mount), 33);
  EXPECT_EQ(L.offset(Block::da), 39);
  EXPECT_EQ(make_layout(InMotionConfig{}).size(), 42);
  EXPECT_EQ(L.offset(Block::da_aux), 45);
  EXPECT_EQ(L.size(), 48);
}

TEST(InMotionStateBlocks, AuxBlocksFollowTheDefaultLayout) {
  const StateLayout L = full_layout();
  const int n = make_layout(InMotionConfig{}).size();
  for (const BlockSpec& b : block_specs()) EXPECT_EQ(b.aux, L.offset(b.id) >= n) << b.name;
}

TEST(InMotionStateBlocks, ColumnNamesComeFromTheDeclarations) {
  const StateLayout L = full_layout();
  const auto n = column_names(L);
  EXPECT_EQ(n[L.offset(Block::pos)], "lat_deg");
  EXPECT_EQ(n[L.offset(Block::Mg) + 1], "gyro_M_xy_ppm");
  EXPECT_EQ(n[L.offset(Block::mount) + 2], "mount_yaw_deg");
  EXPECT_EQ(n[L.offset(Block::da) + 2], "accel_drift_z_mg");
  EXPECT_EQ(n[L.offset(Block::da_aux)], "accel_drift_aux_x_mg_s");
  std::set<std::string> unique(n.begin(), n.end());
  EXPECT_EQ(static_cast<int>(unique.size()), L.size());  // every column named, none twice
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
  constexpr std::array<int, 3> sizes = {48, 3, 0};  // the layout, the extra block, end
  constexpr auto off = filter::offsets_from_sizes(sizes);
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
  EXPECT_EQ(x.head<48>().norm(), 0.0);       // unobserved blocks untouched
  EXPECT_NEAR(P(15, 15), 1.0, 0.0);                // and their covariance too
}
