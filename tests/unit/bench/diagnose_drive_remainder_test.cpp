// The honest remainder on drives (issue 20, docs/diagnosis.md "Reading the output"): physics outside
// the catalogue must end under `unexplained`, never named as a catalogue effect. Here a bias that
// grows with the square of the speed (vibration rectifying as the car goes faster), added to the
// MEMS's measured accelerometer z after the simulation — no catalogue row makes it. A drift of the
// triad can take such a slow path, but a random wander is not tied to the motion: its smoothed path
// follows the speed (`drift_follows_condition`, on records of ≥ 10 independent stretches, length /
// 2τ), and it leaves the axis unexplained (`drift_leaves_axis_unexplained`): either way it is given
// up, and the terms it leaves behind are weighed against the axis's unexplained remainder (Δχ²/φ).
// The control: a genuine drift 16× the data sheet on the same drive is still named. 15 minutes of
// the 1-hour route, in memory.
#include <gtest/gtest.h>

#include <cmath>

#include "bench/diagnose/drive_run.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "common/noise_spec.hpp"

namespace calbench {
namespace {

const std::string kRoute = std::string(CALBENCH_SOURCE_DIR) + "/bench/routes/gnss_1h.toml";
constexpr double kMinutes = 15;

std::string describe(const DriveDiagRun& run) {
  std::string s;
  for (const auto& f : run.result.core.findings) s += f.term.label() + "; ";
  for (const auto& w : run.result.core.withdrawn) s += "withdrawn " + w.term.label() + "; ";
  for (const auto& u : run.result.core.unexplained) s += "unexplained " + std::to_string(u.sensor * 3 + u.axis) + "; ";
  return s.empty() ? "nothing" : s;
}

TEST(DiagnoseDriveRemainder, ASpeedDrivenBiasIsUnexplainedNotADrift) {
  DriveDiagInput in = simulate_drive_diag_input(kRoute, 31, EffectTerms{}, kMinutes * 60);
  // 1e-2 m/s² (1 mg) at 20 m/s, growing with the speed squared, on the measured accelerometer z.
  ASSERT_EQ(in.data.sub_speed.size(), in.data.subs.size());
  for (std::size_t k = 0; k < in.data.subs.size(); ++k)
    in.data.subs[k].accel(2) += 1e-2 * std::pow(in.data.sub_speed[k] / 20.0, 2);
  const DriveDiagRun run = run_drive_diagnosis(in, nullptr);
  const DiagnoseResult& r = run.result.core;
  for (const auto& f : r.findings) EXPECT_FALSE(f.term.sensor == 1) << "named on the accelerometers: " << describe(run);
  // The drift the search took for it is given up: on this 15-minute record because it leaves accel
  // z unexplained; on longer ones (the 35-minute default route: speed, r 0.9, z 7.7) already because
  // its path follows the speed.
  bool withdrawn = false;
  for (const auto& w : r.withdrawn) {
    if (w.term.effect != EffectId::correlated_drift || w.term.sensor != 1) continue;
    withdrawn = true;
    EXPECT_TRUE(w.why == WithdrawnWhy::follows_condition || w.why == WithdrawnWhy::leaves_unexplained);
    if (w.why == WithdrawnWhy::follows_condition) {
      EXPECT_EQ(w.condition, "speed") << describe(run);
      EXPECT_EQ(w.axis, 2);
    }
  }
  EXPECT_TRUE(withdrawn) << describe(run);
  bool az = false;
  for (const auto& u : r.unexplained) az = az || (u.sensor == 1 && u.axis == 2);
  EXPECT_TRUE(az) << describe(run);
  std::printf("speed² bias: %s\n", describe(run).c_str());
}

// The remainder's condition test (issue 36): a gyro z bias proportional to the speed, added to the
// measured gyro after the simulation on the level test route (3.6 minutes; no catalogue row makes
// it). The drift absorbs it and the axis's χ² stays near 1; the GLS test against the motion
// conditions finds the speed. 1.2 °/h per m/s: on this drive (seed 47) the χ² alone does not call
// the axis (from 1.5 °/h per m/s it does, and the test is then not reached), so here only the
// condition test can. Without it, the same drive's gyro z is tested and stays below the level: the
// figure (condition_test) the report gives as "largest below it".
TEST(DiagnoseDriveRemainder, ASpeedProportionalGyroBiasFollowsItsCondition) {
  const std::string level = std::string(CALBENCH_SOURCE_DIR) + "/tests/data/drive_diag_level.toml";
  DriveDiagInput in = simulate_drive_diag_input(level, 47, EffectTerms{});
  const DriveDiagRun clean = run_drive_diagnosis(in, nullptr);
  const auto& c = clean.result.condition_test[2];
  ASSERT_TRUE(c.tested) << describe(clean);
  EXPECT_LT(c.dchi2, DriveDiagnoseResult::kConditionTestLevel) << c.condition;
  for (const auto& u : clean.result.core.unexplained) EXPECT_FALSE(u.sensor == 0 && u.axis == 2) << describe(clean);
  constexpr double kDegPerHour = 3.14159265358979323846 / 180.0 / 3600.0;
  for (std::size_t k = 0; k < in.data.subs.size(); ++k) in.data.subs[k].gyro(2) += 1.2 * kDegPerHour * in.data.sub_speed[k];
  const DriveDiagRun run = run_drive_diagnosis(in, nullptr);
  const DiagnoseResult& r = run.result.core;
  for (const auto& f : r.findings) EXPECT_FALSE(f.term.touches(0, 2)) << "named: " << describe(run);
  const auto& t = run.result.condition_test[2];
  ASSERT_TRUE(t.tested) << describe(run);
  EXPECT_EQ(t.condition, "speed");
  EXPECT_GE(t.dchi2, DriveDiagnoseResult::kConditionTestLevel);
  bool gz = false;
  for (const auto& u : r.unexplained)
    if (u.sensor == 0 && u.axis == 2) {
      gz = true;
      EXPECT_EQ(u.condition_test, "speed") << describe(run);
    }
  EXPECT_TRUE(gz) << describe(run);
  std::printf("speed-proportional gyro z: clean Δχ² %.3g (%s); with it: %s (speed Δχ² %.3g)\n", c.dchi2, c.condition.c_str(),
              describe(run).c_str(), t.dchi2);
}

TEST(DiagnoseDriveRemainder, AGenuineDriftIsStillNamed) {
  EffectTerms fx;
  apply_inject_option("correlated_drift:sensor=accel,sigma=" + std::to_string(16 * adis16488a_noise().accel.drift_sigma) +
                          ",tau=60",
                      fx);
  const DriveDiagInput in = simulate_drive_diag_input(kRoute, 31, fx, kMinutes * 60);
  const DriveDiagRun run = run_drive_diagnosis(in, nullptr);
  const DiagnoseResult& r = run.result.core;
  bool named = false;
  for (const auto& f : r.findings) named = named || (f.term.effect == EffectId::correlated_drift && f.term.sensor == 1);
  EXPECT_TRUE(named) << describe(run);
  for (const auto& w : r.withdrawn) EXPECT_NE(w.why, WithdrawnWhy::follows_condition) << describe(run);
  std::printf("accel drift ×16: %s\n", describe(run).c_str());
}

}  // namespace
}  // namespace calbench
