// A filter block declared in this file only (issue 19: one declaration plus its Jacobian code, no
// edit of any filter file): an error of the nominal lever arm, 3 constant states in reference body
// axes, with its own initial covariance, feedback and observation part (position and velocity,
// eqs 13–14 extended by the extra lever ℓ). The real in-motion filter runs a simulated drive whose
// MEMS sits ℓ away from where the filter is told, and the block finds ℓ.
#include <gtest/gtest.h>

#include <cstdio>

#include "calibration/drive_sim/drive_simulator.hpp"
#include "calibration/inmotion/inmotion_filter.hpp"
#include "common/units.hpp"
#include "inmotion_test_drive.hpp"

using namespace calbench;
using namespace calbench::drivesim;
using namespace calbench::inmotion;
using namespace calbench::inmotion_test;

namespace {

const char* const kLeverCols[] = {"lever_err_x_m", "lever_err_y_m", "lever_err_z_m"};
constexpr double kLeverSigma0 = 0.5;  // m, prior of the lever error

// The declaration: ℓ̂ is the block's nominal value; the predicted reference body origin moves by
// −Ĉ_nb·ℓ̂ (position) and −Ĉ_nb·(ω_eb × ℓ̂) (velocity), so with δℓ = ℓ̂ − ℓ
//   z_pos += −Ĉ_nb·ℓ̂,  H_pos = −Ĉ_nb;   z_vel += −Ĉ_nb·(ω × ℓ̂),  H_vel = −Ĉ_nb·[ω×].
BlockSpec lever_error_block() {
  BlockSpec b{static_cast<Block>(100), "lever_error", 3, kLeverCols, "m", "m", 1.0, true, false};
  b.init = [](const BlockInit&, const filter::BlockLayout&, int off, MatRef P) {
    for (int i = 0; i < 3; ++i) P(off + i, off + i) = kLeverSigma0 * kLeverSigma0;
  };
  b.feedback = additive_feedback<3>;
  b.observe = [](const BlockObsInput& o, const Nominal& n, int type, int off, MatRef H, Eigen::Vector3d& z) {
    const Mat3 C_nb = predicted_body_attitude(o.c);
    const Vec3 l = n.x.segment<3>(off);
    if (type == 0) {
      z -= C_nb * l;
      H.block<3, 3>(0, off) = -C_nb;
    } else if (type == 1) {
      z -= C_nb * o.c.w_eb_b.cross(l);
      H.block<3, 3>(0, off) = -C_nb * ins::skew(o.c.w_eb_b);
    }
  };
  b.total = slice_total<3>;
  return b;
}

struct LeverRun {
  Vec3 est, sigma;
  int n_states;
  double mean_nis_pos;
};

LeverRun run_drive(const Vec3& lever_error, bool with_block) {
  const Vec3 lever_true(0.6, -0.4, 0.3);
  const DriveSimConfig cfg = drive_config(lap_route(48.1, 11.6, 520, 10, 2), 7, 200, Vec3(0.2, -0.1, 0.3), lever_true);
  InMotionConfig fc;
  if (with_block) fc.extra_blocks.push_back(lever_error_block());
  // The filter is told a lever arm that is ℓ short of the truth.
  FilterReplay<InMotionFilter> replay(fc, nominal_mounting(), lever_true - lever_error);
  DriveSinks sinks;
  sinks.imu = [&](const SimImu& m) { replay.imu(m); };
  sinks.reference = [&](const SimRef& r) { replay.reference(r); };
  simulate_drive(cfg, sinks);
  const InMotionFilter& f = replay.filter();
  LeverRun out{};
  out.n_states = f.layout().size();
  out.mean_nis_pos = f.consistency(0).mean_nis();
  const int off = f.layout().L.offset(100);
  if (off >= 0) {
    out.est = f.extra_values().segment<3>(off);
    for (int i = 0; i < 3; ++i) out.sigma(i) = std::sqrt(f.P()(off + i, off + i));
  }
  return out;
}

}  // namespace

TEST(InmotionExtraBlock, DeclaredOutsideTheFilterAndEstimated) {
  const Vec3 l(0.25, -0.15, 0.2);
  const LeverRun r = run_drive(l, true);
  EXPECT_EQ(r.n_states, make_layout(InMotionConfig{}).size() + 3);  // appended after the default layout
  std::printf("lever error: estimated %.3f %.3f %.3f m (truth %.3f %.3f %.3f), sigma %.3f %.3f %.3f, NIS pos %.2f\n",
              r.est(0), r.est(1), r.est(2), l(0), l(1), l(2), r.sigma(0), r.sigma(1), r.sigma(2), r.mean_nis_pos);
  for (int i = 0; i < 3; ++i) {
    EXPECT_LE(std::abs(r.est(i) - l(i)), 3 * r.sigma(i)) << i;  // consistent with its own σ
    EXPECT_LT(r.sigma(i), 0.5 * kLeverSigma0) << i;             // the drive taught it something
  }
  // Horizontal components: the turns make them well observable.
  EXPECT_NEAR(r.est(0), l(0), 0.05);
  EXPECT_NEAR(r.est(1), l(1), 0.05);
}

TEST(InmotionExtraBlock, WithoutItTheDefaultLayoutAndAWorseFit) {
  const Vec3 l(0.25, -0.15, 0.2);
  const LeverRun plain = run_drive(l, false), with = run_drive(l, true);
  EXPECT_EQ(plain.n_states, make_layout(InMotionConfig{}).size());
  // The wrong lever arm left unmodelled shows in the position innovations.
  std::printf("mean position NIS: %.2f without the block, %.2f with it\n", plain.mean_nis_pos, with.mean_nis_pos);
  EXPECT_GT(plain.mean_nis_pos, 1.15 * with.mean_nis_pos);  // measured 3.88 vs 3.02
}
