// table_wobble in static steps (docs/diagnosis.md): the diagnosis derives, from the recording alone,
// the direction in IMU axes of the table axis whose angle reference.csv gives (rows where only that
// axis turns: ω = θ̇·u), and predicts the static-position part of the wobble with it: the table
// stands at θ + δ(θ), so gravity and the Earth rate turn by −δ about u.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "bench/bench_recording.hpp"
#include "bench/diagnose/diagnose_run.hpp"
#include "calibration/effects/effect_registry.hpp"
#include "calibration/bench_kinematics.hpp"
#include "calibration/diagnosis/catalogue.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

using namespace units;

PlanStep step(StepKind kind, int mount, double outer_deg, double inner_deg, double rate_dps = 0) {
  PlanStep s;
  s.kind = kind;
  s.mount = mount;
  s.outer = outer_deg * kDeg;
  s.inner = inner_deg * kDeg;
  s.rate = rate_dps * kDeg;
  s.dwell_s = 2.0;
  return s;
}

// Three mountings: z (statics, then a rate step), x (statics at different inner angles, back to
// inner 0) and y (one static at inner 0: the inner axis never turns while the cube is on y).
BenchPlan axis_plan() {
  BenchPlan p;
  p.name = "wobble-axis";
  p.site = {55.75, 37.62, 150.0};
  p.table.max_rate = 500 * kDeg;
  p.table.max_accel = 300 * kDeg;
  p.table.slew_rate = 120 * kDeg;
  p.table.settle_s = 0.5;
  p.table.remount_s = 5.0;
  p.steps = {step(StepKind::static_position, 2, 0, 0),    step(StepKind::static_position, 2, 90, 0),
             step(StepKind::rate, 2, 0, 0, -75),          step(StepKind::static_position, 0, 0, 0),
             step(StepKind::static_position, 0, 60, 30),  step(StepKind::static_position, 0, 90, 0),
             step(StepKind::static_position, 1, 45, 0)};
  return p;
}

struct TmpDir {
  std::filesystem::path path;
  TmpDir() {
    path = std::filesystem::temp_directory_path() / ("calbench_wobble_axis_" + std::to_string(std::random_device{}()));
    std::filesystem::create_directories(path);
  }
  ~TmpDir() { std::filesystem::remove_all(path); }
};

TEST(DiagnoseWobbleAxis, DerivedFromTheRecordingPerMounting) {
  const BenchPlan plan = axis_plan();
  TmpDir d;
  RecordingMeta meta;
  meta.kind = RecordingKind::bench;
  meta.site = plan.site;
  BenchSimOptions so;
  so.seed = 7;
  so.noise.output_rate_hz = 200;  // small files; the derivation does not depend on the rate
  meta.imu_rate_hz = so.noise.output_rate_hz;
  {
    RecordingWriter w(d.path, meta, ImuForm::rates, true, false, false);
    simulate_bench(plan, plan.site, draw_random_unit(7), so, [&](const BenchSample& s) { write_bench_sample(w, s); });
    w.finish();
  }
  const DiagInput in = load_diag_input(d.path);
  ASSERT_EQ(in.data.stretch_axes.size(), 3u) << "one gap-free stretch per mounting (the remounts are not recorded)";
  int checked[3] = {0, 0, 0};
  for (const SubBlock& s : in.data.subs) {
    const int mount = plan.steps.at(s.step).mount;
    if (mount == 1) {
      EXPECT_TRUE(s.inner_axis.isZero(0)) << "step " << s.step << ": the inner axis never turned on this mounting";
      ++checked[1];
      continue;
    }
    // Truth from the plan geometry (not from the recording): the platform z in IMU axes.
    const Vec3 truth = mount_rotation(mount).transpose() * Vec3::UnitZ();
    EXPECT_LT((s.inner_axis - truth).norm(), 1e-3) << "step " << s.step << " axis " << s.inner_axis.transpose();
    ++checked[mount];
  }
  EXPECT_GT(checked[0], 0);
  EXPECT_GT(checked[1], 0);
  EXPECT_GT(checked[2], 0);
}

// The static-step prediction has the simulator's sign and size: compare with the exact kinematics
// at θ + δ(θ) (what the simulator does), for several table positions and mounts.
TEST(DiagnoseWobbleAxis, StaticPredictionMatchesTheTurnedTable) {
  const SiteEarth earth(Site{55.75, 37.62, 150.0});
  EffectTerms e;
  effect_vector<2>(e, EffectId::table_wobble) = Eigen::Vector2d(30.0, -20.0) / 3600 * kDeg;
  int with_signal = 0;
  for (int mount = 0; mount < 3; ++mount)
    for (double outer : {0.0, 50.0, 90.0, 135.0})
      for (double inner : {0.0, 30.0, 120.0, 250.0}) {
        AxisState o, i;
        o.angle = outer * kDeg;
        i.angle = inner * kDeg;
        const BenchKinematics nominal = bench_kinematics(earth, o, i, mount);
        AxisState it = i;
        it.angle += wobble_angle(effect_vector<2>(e, EffectId::table_wobble), i.angle);
        const BenchKinematics turned = bench_kinematics(earth, o, it, mount);
        SubBlock s;
        s.w = nominal.w_ib_b;
        s.f = nominal.f_b;
        s.angle = i.angle;
        s.angle_rate = 0;
        s.temp_c = std::nan("");
        s.inner_axis = mount_rotation(mount).transpose() * Vec3::UnitZ();
        Vec3 dg, da;
        predict_extra(e, s, dg, da);
        const Vec3 df = turned.f_b - nominal.f_b, dw = turned.w_ib_b - nominal.w_ib_b;
        if (df.norm() < 1e-5) {  // gravity along the inner axis: the turn does not show in f
          EXPECT_LT(da.norm(), 1e-8);
          continue;
        }
        ++with_signal;
        // First order in δ (≈ 1.7e-4 rad): the error is O(δ²·g) ≈ 3e-7 m/s².
        EXPECT_LT((da - df).norm(), 1e-3 * df.norm() + 5e-7) << "mount " << mount << " outer " << outer << " inner " << inner;
        EXPECT_LT((dg - dw).norm(), 1e-3 * dw.norm() + 1e-11);
        // Without a known axis the static part is not predicted (as before the axis was derived).
        s.inner_axis.setZero();
        predict_extra(e, s, dg, da);
        EXPECT_TRUE(da.isZero(0));
      }
  EXPECT_GE(with_signal, 30);  // 36 of 48: at outer 0 gravity lies along the inner axis
}

}  // namespace
}  // namespace calbench
