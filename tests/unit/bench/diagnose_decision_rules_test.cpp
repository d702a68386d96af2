// Issue 36, the diagnosis's decision rules: a finding is established only when the accepted model
// cuts the systematic residual of its axis by ≥ DiagnoseOptions::established_cut and leaves a
// remainder consistent with noise; otherwise it is "partial" with the fraction it explains, and an
// alternative explaining it as well makes it "not told apart" (docs/diagnosis.md, "Decision rules").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "bench/diagnose/diagnose_run.hpp"
#include "bench/diagnose/finding_text.hpp"
#include "bench/io/plan_toml.hpp"
#include "common/imu_error_sim.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

DiagFinding gyro_x_finding(double before, double after) {
  DiagFinding f;
  f.term = Term{EffectId::scale_asymmetry, 0, 0};
  f.report_sensor = 0;
  f.report_axis = 0;
  f.rms_before = before;
  f.rms_after = after;
  return f;
}

// The memory case: two names together cut 29.8 → 23.9 °/h (20 %): partial, never established.
TEST(DiagnoseDecisionRules, ExplainedFractionBelowCutIsPartial) {
  const DiagnoseOptions opt;
  DiagnoseResult res;
  DiagFinding f = gyro_x_finding(29.8, 23.9);
  finding_status(f, res, opt);
  EXPECT_STREQ(f.status, "partial");
  EXPECT_NEAR(f.explained_fraction, 1 - 23.9 / 29.8, 1e-12);
  // The same finding cutting 29.8 → 3 (90 %) with a noise-like remainder is established.
  f = gyro_x_finding(29.8, 3.0);
  finding_status(f, res, opt);
  EXPECT_STREQ(f.status, "established");
  EXPECT_TRUE(f.remainder_is_noise);
  // ... but not when its axis is left unexplained: the remainder is not noise.
  DiagUnexplained u;
  u.sensor = 0;
  u.axis = 0;
  res.unexplained.push_back(u);
  finding_status(f, res, opt);
  EXPECT_STREQ(f.status, "partial");
  EXPECT_FALSE(f.remainder_is_noise);
  // Another axis's remainder does not concern it.
  res.unexplained[0].axis = 1;
  finding_status(f, res, opt);
  EXPECT_STREQ(f.status, "established");
  // An alternative that explains it as well: not told apart, whatever the cut.
  f.alternatives.push_back(DiagAlternative{});
  finding_status(f, res, opt);
  EXPECT_STREQ(f.status, "not told apart");
}

// A gyro whose range (250 °/s) is exceeded by the plan's 300 °/s steps: the output clips. No
// polynomial or scale term may come out established on calbench's own diagnosis of it.
TEST(DiagnoseDecisionRules, ClippedGyroNamesNoEstablishedScaleTerm) {
  const BenchPlan plan = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/diagnose.toml");
  BenchSimOptions so;
  so.seed = 3601;
  so.noise.gyro.range = 250 * units::kDeg;
  const DiagInput in = simulate_diag_input(plan, draw_random_unit(3601), so);
  const DiagRun r = run_diagnosis(in, nullptr, plan.table);
  std::string all;
  for (const auto& f : r.result.findings) all += "\n  " + f.term.label() + " [" + f.status + "]: " + finding_sentence(f);
  bool gyro_left = false;
  for (const auto& u : r.result.unexplained) gyro_left = gyro_left || u.sensor == 0;
  for (const auto& f : r.result.findings) {
    if (f.report_sensor != 0) continue;
    EXPECT_STRNE(f.status, "established") << all;
    gyro_left = true;
  }
  EXPECT_TRUE(gyro_left || !r.result.saturation.empty()) << "the clipped gyro must leave something reported" << all;
  // The plateau rule: the output is frozen at the top rates, so the steps are named as saturation
  // (every gyro axis reaches 300 °/s on this plan) and left out, not fitted by polynomials.
  ASSERT_FALSE(r.result.saturation.empty()) << all;
  for (const auto& x : r.result.saturation) {
    EXPECT_EQ(x.sensor, 0);
    EXPECT_NEAR(std::max(std::abs(x.level_pos), std::abs(x.level_neg)), 250 * units::kDeg, 1 * units::kDeg);
    EXPECT_GT(x.reference_max, 250 * units::kDeg);
    EXPECT_FALSE(x.steps.empty());
  }
  std::printf("clipped gyro: %zu findings, %zu unexplained%s\n", r.result.findings.size(), r.result.unexplained.size(),
              all.c_str());
}

// The clean unit of the tests below: its diagnosis plan recording, simulated by calbench.
DiagInput clean_input(std::uint64_t seed, const char* plan_name = "diagnose") {
  const BenchPlan plan = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/" + plan_name + ".toml");
  BenchSimOptions so;
  so.seed = seed;
  return simulate_diag_input(plan, draw_random_unit(seed), so);
}

// Remainder power: a gyro z bias that remembers the direction of its last rotation (+m after a
// positive turn, −m after a negative one), added here to the sub-block means, outside the
// catalogue and outside calbench's simulator. It moves from step to step: the step-offset test must
// report the axis unexplained where the parent-level χ²/dof, spread over every block, does not reach
// its own threshold, and nothing may be established on the gyro.
TEST(DiagnoseDecisionRules, StepOffsetTestReportsAStepwiseRemainder) {
  const std::uint64_t seed = 3611;
  const DiagRun clean = run_diagnosis(clean_input(seed), nullptr, load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/diagnose.toml").table);
  for (int a = 0; a < 6; ++a) EXPECT_GT(clean.result.after[a].step_p, 1e-4) << "clean axis " << a;
  EXPECT_TRUE(clean.result.unexplained.empty());
  DiagInput in = clean_input(seed);
  const double m = 20 * units::kDegPerHour;
  double last = 0;
  for (auto& s : in.data.subs) {
    if (std::abs(s.w(2)) > units::kDeg) last = s.w(2) > 0 ? 1 : -1;
    s.gyro(2) += last * m;
  }
  const DiagRun r = run_diagnosis(in, nullptr, load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/diagnose.toml").table);
  const AxisStats& z = r.result.after[2];
  std::printf("memory 20 deg/h on gyro z: step-offset p %.3g (Q %.1f, dof %d), chi2/dof %.3f, Ljung-Box p %.3g\n", z.step_p, z.step_q,
              z.step_dof, z.chi2_dof, z.ljung_box_p);
  EXPECT_LT(z.step_p, 1e-4);
  bool unexplained_z = false;
  for (const auto& u : r.result.unexplained) unexplained_z = unexplained_z || (u.sensor == 0 && u.axis == 2);
  EXPECT_TRUE(unexplained_z);
  for (const auto& f : r.result.findings) EXPECT_FALSE(f.report_sensor == 0 && std::strcmp(f.status, "established") == 0) << f.term.label();
  // The power is the step test's: the parent-level χ² alone stays below its 6σ criterion here.
  const int n_low = static_cast<int>(r.result.parents);
  EXPECT_LT((z.chi2_dof - 1) * std::sqrt(n_low / 2.0), 6.0) << "the memory is too large to show the step test's power";
}

// The step-offset test's families and the smallest inputs (issue 36, the dead band): a gyro rate
// dead band of 0.01 °/s on the rate the axis receives (row z of (I + M)·ω, the unit's own M), made
// here on the sub-block means (the output lacks that rate where it is below 0.01 °/s). On the diagnosis plan only the Earth rate falls inside it (12 °/h in
// 8-s statics). The low-rate plan (bench/plans/lowrate.toml: ±0.005 and ±0.05 °/s steps) holds the
// input there for 16 s: the catalogue's model must leave the axis unexplained by the static family
// of the step-offset test (low-rate steps turn at < 1 °/s; its χ² shared over fewer degrees of
// freedom than all steps'), and the low-input test must find that gyro z does not sense its
// smallest inputs, with the band bracketing 0.01 °/s within 10 %; nothing established on the gyro. Clean: no
// axis below 10⁻⁴, nothing unexplained, the smallest inputs not found unsensed (verdict none or sensed).
TEST(DiagnoseDecisionRules, StepFamiliesFindADeadBand) {
  const std::uint64_t seed = 3613;
  const TableSpec table = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/lowrate.toml").table;
  const DiagRun clean = run_diagnosis(clean_input(seed, "lowrate"), nullptr, table);
  for (int a = 0; a < 6; ++a) EXPECT_GT(clean.result.after[a].step_p, 1e-4) << "clean axis " << a;
  EXPECT_TRUE(clean.result.unexplained.empty());
  const std::string clean_verdict = clean.result.low_input.verdict;
  EXPECT_TRUE(clean_verdict.empty() || clean_verdict == "sensed") << clean_verdict;
  DiagInput in = clean_input(seed, "lowrate");
  const double width = 0.01 * units::kDeg;
  const Mat3 M = draw_random_unit(seed).gyro.M;  // the unit's own: the band acts on what the axis receives
  int touched = 0;
  for (auto& s : in.data.subs)
    if (const double r = s.w(2) + M.row(2).dot(s.w); std::abs(r) < width) {
      s.gyro(2) -= r;
      ++touched;
    }
  ASSERT_GT(touched, 100);
  const DiagRun r = run_diagnosis(in, nullptr, table);
  const DiagLowInput& lo = r.result.low_input;
  std::printf("dead band 0.01 deg/s on gyro z: %s\n", low_input_sentence(lo).c_str());
  ASSERT_STREQ(lo.verdict, "not sensed");
  const AxisStats& z = lo.catalogue_after[2];
  std::printf("the catalogue's model on gyro z: step-offset p %.3g (%s steps, Q %.1f, dof %d), chi2/dof %.3f\n", z.step_p,
              z.step_family, z.step_q, z.step_dof, z.chi2_dof);
  EXPECT_LT(z.step_p, 1e-4);
  EXPECT_STREQ(z.step_family, "static") << "the dead band lives in the steps that do not turn";
  EXPECT_NE(std::find(lo.catalogue_unexplained.begin(), lo.catalogue_unexplained.end(), 2), lo.catalogue_unexplained.end());
  bool found_z = false;
  for (const auto& x : lo.axes)
    if (x.axis == 2) {
      found_z = true;
      // The widths tried are a factor 2 apart and a few sub-blocks lie near the edge: the inputs
      // taken as not sensed and those taken as sensed must bracket the band within 10 %.
      EXPECT_LT(x.below_max, 1.1 * width);
      EXPECT_TRUE(x.above_min > 0.9 * width || x.above_min == 0) << "the band must bracket the dead band's width";
    }
  EXPECT_TRUE(found_z);
  for (const auto& f : r.result.findings) EXPECT_FALSE(f.report_sensor == 0 && std::strcmp(f.status, "established") == 0) << f.term.label();
}

// The smallest inputs against the catalogue's names (issue 36): the same dead band on all three
// gyros of seed 3603, where the catalogue named the Earth rate missing on the statics an isotropic
// g-sensitivity of −Ω·sin L/g and the missing low-rate steps a larger drift, both established
// (docs/validation/diagnose-inject-confusion.md). The record with the smallest inputs taken as not
// sensed must fit decisively better; the names the catalogue gave are listed, not found; nothing
// established on the gyros.
TEST(DiagnoseDecisionRules, SmallestInputsNotSensedInsteadOfCatalogueNames) {
  const std::uint64_t seed = 3603;
  const TableSpec table = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/lowrate.toml").table;
  DiagInput in = clean_input(seed, "lowrate");
  const double width = 0.01 * units::kDeg;
  const Mat3 M = draw_random_unit(seed).gyro.M;
  for (auto& s : in.data.subs)
    for (int i = 0; i < 3; ++i)
      if (const double r = s.w(i) + M.row(i).dot(s.w); std::abs(r) < width) s.gyro(i) -= r;
  const DiagRun r = run_diagnosis(in, nullptr, table);
  const DiagLowInput& lo = r.result.low_input;
  std::printf("dead band 0.01 deg/s on gyros x, y, z: %s\n", low_input_sentence(lo).c_str());
  ASSERT_STREQ(lo.verdict, "not sensed");
  EXPECT_GE(lo.delta_score, DiagnoseOptions{}.ambiguity_chi2);
  EXPECT_EQ(lo.axes.size(), 3u);
  EXPECT_FALSE(lo.competing.empty() && lo.catalogue_unexplained.empty()) << "the catalogue alone said something";
  for (const auto& f : r.result.findings) EXPECT_FALSE(f.report_sensor == 0 && std::strcmp(f.status, "established") == 0) << f.term.label();
  for (const auto& u : r.result.unexplained) EXPECT_NE(u.sensor, 0) << "the corrected record leaves gyro " << u.axis << " unexplained";
}

// Drift against the class's stability: a gyro z bias following the unit's recorded temperature by
// 20 °/h over the run (4× the ADIS16488A's in-run bias stability), added to the sub-block means. On
// the 4-minute plan the class's drift model absorbs it (no temperature term reaches Δχ² 40); the
// diagnosis must still report it, not established, and say what it cannot tell apart. Clean: none.
TEST(DiagnoseDecisionRules, DriftBeyondStabilityIsReportedNotEstablished) {
  const std::uint64_t seed = 3612;
  const TableSpec table = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/diagnose.toml").table;
  const DiagRun clean = run_diagnosis(clean_input(seed), nullptr, table);
  EXPECT_TRUE(clean.result.drift_excess.empty());
  DiagInput in = clean_input(seed);
  ASSERT_TRUE(in.data.has_temperature);
  double t0 = in.data.subs.front().temp_c, t1 = t0;
  for (const auto& s : in.data.subs) {
    t0 = std::min(t0, s.temp_c);
    t1 = std::max(t1, s.temp_c);
  }
  ASSERT_GT(t1 - t0, 1.0);
  const double k = 20 * units::kDegPerHour / (t1 - t0);
  for (auto& s : in.data.subs) s.gyro(2) += k * (s.temp_c - t0);
  const DiagRun r = run_diagnosis(in, nullptr, table);
  std::string all;
  for (const auto& f : r.result.findings) all += "\n  " + f.term.label() + " [" + f.status + "]";
  for (const auto& f : r.result.findings) EXPECT_FALSE(f.report_sensor == 0 && f.report_axis == 2 && std::strcmp(f.status, "established") == 0 &&
                                                       !effect_spec(f.term.effect).temperature_driven)
      << "a wrong established name" << all;
  bool temperature_finding = false;
  for (const auto& f : r.result.findings)
    temperature_finding = temperature_finding || (f.report_sensor == 0 && f.report_axis == 2 && effect_spec(f.term.effect).temperature_driven);
  const DiagDriftExcess* x = nullptr;
  for (const auto& e : r.result.drift_excess)
    if (e.sensor == 0 && e.axis == 2) x = &e;
  ASSERT_TRUE(temperature_finding || x != nullptr) << "a 20 deg/h warm-up must not leave nothing reported" << all;
  if (x) {
    std::printf("warm-up gyro z: change %.2f deg/h (%.2fx stability, z %.2f); temperature term %.2f deg/h over the run, dchi2 %.2f\n",
                x->change / units::kDegPerHour, x->change / x->stability, x->z, x->temperature_change_total() / units::kDegPerHour,
                x->temperature_dchi2);
    EXPECT_TRUE(drift_excess_reported(*x));
    EXPECT_GT(x->temperature_change_total(), 2 * x->stability);
  }
}

// The note's rule, on its own: never with a report; a change beyond 2× the stability that the class's
// own drift reaches in at most kDriftNoteTail of the draws makes a note; not drawn (NaN), within 2×,
// or a strong temperature term alone, nothing.
TEST(DiagnoseDecisionRules, DriftNoteRule) {
  DiagDriftExcess x;
  x.stability = 1.0;
  x.change = 2.1;
  x.z = 0.5;
  EXPECT_FALSE(drift_excess_noted(x)) << "no null drawn: nothing to weigh it against";
  x.null_exceed_count = static_cast<int>(0.2 * kDriftExcessDraws);
  EXPECT_FALSE(drift_excess_noted(x)) << "beyond 2x, but the class's own drift gets there in 20 % of draws";
  x.null_exceed_count = static_cast<int>(kDriftNoteTail * kDriftExcessDraws);
  EXPECT_TRUE(drift_excess_noted(x));
  x.change = 1.9;
  EXPECT_FALSE(drift_excess_noted(x)) << "within 2x the stability";
  x.has_temperature = true;
  x.temperature_change = 10;
  x.temperature_coef = 0.3;  // 3x the stability over the run
  x.temperature_dchi2 = 2 * kDriftNoteChi2;
  EXPECT_FALSE(drift_excess_noted(x)) << "a temperature term alone (a quarter of clean units have one)";
  EXPECT_TRUE(drift_note_temperature(x));
  x.change = 2.1;
  x.z = kDriftExcessZ;  // now reported (change > 2x and z >= 4): a report, not a note
  EXPECT_TRUE(drift_excess_reported(x));
  EXPECT_FALSE(drift_excess_noted(x));
}

// Never nothing on a warm-up (issue 36): the 20 °/h over the run on gyro z, on seeds where
// the class's drift model absorbs it without a report, is noted with what the record cannot tell
// apart; the same recordings clean get no note on gyro z.
TEST(DiagnoseDecisionRules, WarmUpTheClassDriftAlsoMakesIsNoted) {
  const TableSpec table = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/diagnose.toml").table;
  for (const std::uint64_t seed : {3601u, 3603u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    auto gyro_z = [](const std::vector<DiagDriftExcess>& v) {
      for (const auto& e : v)
        if (e.sensor == 0 && e.axis == 2) return &e;
      return static_cast<const DiagDriftExcess*>(nullptr);
    };
    const DiagRun clean = run_diagnosis(clean_input(seed), nullptr, table);
    EXPECT_EQ(gyro_z(clean.result.drift_excess), nullptr);
    EXPECT_EQ(gyro_z(clean.result.drift_noted), nullptr) << "a clean unit of this seed has nothing to note on gyro z";
    DiagInput in = clean_input(seed);
    double t0 = in.data.subs.front().temp_c, t1 = t0;
    for (const auto& s : in.data.subs) {
      t0 = std::min(t0, s.temp_c);
      t1 = std::max(t1, s.temp_c);
    }
    ASSERT_GT(t1 - t0, 1.0);
    for (auto& s : in.data.subs) s.gyro(2) += 20 * units::kDegPerHour * (s.temp_c - t0) / (t1 - t0);
    const DiagRun r = run_diagnosis(in, nullptr, table);
    for (const auto& f : r.result.findings)
      EXPECT_FALSE(f.report_sensor == 0 && std::strcmp(f.status, "established") == 0 && !effect_spec(f.term.effect).temperature_driven)
          << f.term.label();
    const DiagDriftExcess* rep = gyro_z(r.result.drift_excess);
    const DiagDriftExcess* note = gyro_z(r.result.drift_noted);
    bool temperature_finding = false;
    for (const auto& f : r.result.findings)
      temperature_finding = temperature_finding || (f.report_sensor == 0 && f.report_axis == 2 && effect_spec(f.term.effect).temperature_driven);
    ASSERT_TRUE(temperature_finding || rep || note) << "a 20 deg/h warm-up must not leave nothing said";
    EXPECT_FALSE(temperature_finding || rep) << "these seeds are the report rule's misses: the note is what is tested";
    if (note) {
      const std::string text = drift_note_sentence(*note);
      std::printf("seed %llu: %s\n", static_cast<unsigned long long>(seed), text.c_str());
      EXPECT_NE(text.find("not a finding"), std::string::npos);
      EXPECT_NE(text.find("temperature or drift, not told apart"), std::string::npos);
      EXPECT_TRUE(note->follows_temperature);
      EXPECT_GT(note->null_exceed(), 0.0);
      EXPECT_LE(note->null_exceed(), kDriftNoteTail) << "the change is in the upper tail of the class's drift";
      EXPECT_GT(note->change, kDriftExcessFactor * note->stability);
    }
  }
}

}  // namespace
}  // namespace calbench
