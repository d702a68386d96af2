// The fit-quality part of the verdict (db/approval_quality.hpp): bench χ²/dof and systematic
// residuals, NIS bands, and a combined set against its parent (the tryout case of issue 35).
#include <gtest/gtest.h>

#include "common/input_error.hpp"
#include "common/units.hpp"
#include "db/approval.hpp"
#include "db_test_util.hpp"

namespace calbench::db {
namespace {
using namespace calbench::units;

int count_with(const std::vector<std::string>& reasons, const std::string& needle) {
  int n = 0;
  for (const auto& r : reasons) n += r.find(needle) != std::string::npos;
  return n;
}

inmotion::StabilityAllowance adis_allowance() {  // bench/imu_classes/adis16488a.toml [allowance]
  inmotion::StabilityAllowance a;
  a.device_class = "ADIS16488A";
  a.gyro_bias = 0.1 * kDeg;
  a.accel_bias = 5 * kMilliG;
  a.gyro_scale = a.accel_scale = 300 * kPpm;
  a.gyro_skew = a.accel_skew = 50 * kPpm;
  return a;
}

// The tryout's unchanged unit: accel z scale 6866 ± 11 → 6622 ± 258 ppm and gyro x scale σ 2.7 →
// 270 ppm were approved; both must be named. Every other coefficient as the parent: not named.
TEST(DbApprovalQuality, CombinedSetNamesGrownSigmaAndMovedCoefficients) {
  CoefficientSetRecord parent, set;
  parent.id = 1;
  parent.model = set.model = "ADIS16488A";
  parent.errors = test::random_errors(7);
  set.errors = parent.errors;
  set.source = SetSource::combined;
  set.parent_id = 1;
  parent.errors.accel.M(2, 2) = 6866 * kPpm;
  parent.errors.accel.sigma_M(2, 2) = 11 * kPpm;
  set.errors.accel.M(2, 2) = 6622 * kPpm;
  set.errors.accel.sigma_M(2, 2) = 258 * kPpm;
  parent.errors.gyro.sigma_M(0, 0) = 2.7 * kPpm;
  set.errors.gyro.sigma_M(0, 0) = 270 * kPpm;
  Thresholds t = default_thresholds();
  t.quality.allowances["adis16488a"] = adis_allowance();
  FitEvidence ev;
  ev.parent = parent;
  auto why = fit_quality_reasons(set, ev, t.quality);
  ASSERT_EQ(why.size(), 2u) << why[0];
  EXPECT_EQ(count_with(why, "combined accel.M.zz: σ grew from 11 to 258 ppm"), 1);
  EXPECT_EQ(count_with(why, "6866 ± 11 ppm → 6622 ± 258 ppm"), 1);
  EXPECT_EQ(count_with(why, "combined gyro.M.xx: σ grew from 2.7 to 270 ppm (100× the parent set 1's, limit 3×)"), 1);
  // The move of 244 ppm is inside √(11² + 300²) = 300 ppm; at 1000 ppm it is named as a move.
  set.errors.accel.M(2, 2) = 5866 * kPpm;
  why = fit_quality_reasons(set, ev, t.quality);
  EXPECT_EQ(count_with(why, "combined accel.M.zz moved -1000 ppm from the parent set 1"), 1);
  EXPECT_EQ(count_with(why, "= 300.2 ppm (ADIS16488A allowance 300 ppm)"), 1);
  // Without a device class the allowance is 0, and said so.
  t.quality.allowances.clear();
  set.errors.accel.M(2, 2) = 6622 * kPpm;
  why = fit_quality_reasons(set, ev, t.quality);
  EXPECT_EQ(count_with(why, "no device class for model 'ADIS16488A': allowance 0"), 1);
  // A file that accepts growth up to 200× names only the move.
  t = parse_thresholds(R"({"combined": {"max_sigma_growth": 200}})", "t.json");
  t.quality.allowances["adis16488a"] = adis_allowance();
  why = fit_quality_reasons(set, ev, t.quality);
  EXPECT_EQ(why.size(), 0u);
  // A bench set or an in-motion set is not compared (no parent comparison without "combined").
  set.source = SetSource::in_motion;
  t.quality.max_sigma_growth = 3;
  EXPECT_TRUE(fit_quality_reasons(set, ev, t.quality).empty());
}

TEST(DbApprovalQuality, BenchChi2AndSystematicResidualPerKind) {
  BenchFitQuality q;
  q.gyro_chi2_dof = Vec3(1.0, 0.9, 1.1);
  q.accel_chi2_dof = Vec3(1.0, 4.0, 1.0);
  q.steps.push_back({0, kStepStatic, Vec3(10, -70, 5) * kDegPerHour, Vec3(0.1, 0.2, 0.1) * kMilliG});
  q.steps.push_back({1, kStepRate, Vec3(10, 20, -30) * kDegPerHour, Vec3(0.1, 0.2, -1.5) * kMilliG});
  CoefficientSetRecord set;
  FitEvidence ev;
  ev.bench = q;
  const Thresholds t = default_thresholds();
  const auto why = fit_quality_reasons(set, ev, t.quality);
  ASSERT_EQ(why.size(), 3u);
  EXPECT_EQ(count_with(why, "bench fit accel y: χ²/dof = 4 exceeds 3"), 1);
  EXPECT_EQ(count_with(why, "bench fit gyro: largest systematic residual of the static positions = 70 °/h (step 0, axis y) exceeds 60 °/h"), 1);
  EXPECT_EQ(count_with(why, "bench fit accel: largest systematic residual of the rate steps = 1.5 mg (step 1, axis z) exceeds 1 mg"), 1);
  const auto loose = parse_thresholds(
      R"({"bench": {"max_chi2_dof": {"accel": 5}, "max_systematic_residual": {"static": {"gyro_dph": 80}, "rate": {"accel_mg": 2}}}})", "t");
  EXPECT_TRUE(fit_quality_reasons(set, ev, loose.quality).empty());
  // A bench set without the figures: refused only when required.
  set.source = SetSource::bench;
  EXPECT_TRUE(fit_quality_reasons(set, {}, t.quality).empty());
  EXPECT_EQ(count_with(fit_quality_reasons(set, {}, parse_thresholds(R"({"bench": {"require_fit_quality": true}})", "t").quality),
                       "bench fit quality not recorded"),
            1);
}

TEST(DbApprovalQuality, NisBandPerObservation) {
  std::map<std::string, NisConsistency> nis;
  nis["position"].mean_nis = 3.3;
  nis["position"].expected_nis = 3;
  nis["position"].epochs = 1000;
  nis["attitude"].mean_nis = 9;  // 3 per dof: outside the default band
  nis["attitude"].expected_nis = 3;
  nis["attitude"].epochs = 1000;
  nis["zupt"].mean_nis = 0.01;  // no epochs: not judged
  nis["zupt"].epochs = 0;
  CoefficientSetRecord set;
  FitEvidence ev;
  ev.nis = nis;
  auto why = fit_quality_reasons(set, ev, default_thresholds().quality);
  ASSERT_EQ(why.size(), 1u);
  EXPECT_EQ(count_with(why, "in-motion NIS attitude: mean 9 over 1000 epochs = 3 per degree of freedom, outside the band 0.1 – 2"), 1);
  const auto t = parse_thresholds(R"({"inmotion": {"mean_nis_per_dof": {"attitude": [0.5, 4], "position": [2, 3]}}})", "t");
  why = fit_quality_reasons(set, ev, t.quality);
  ASSERT_EQ(why.size(), 1u);
  EXPECT_EQ(count_with(why, "in-motion NIS position: mean 3.3 over 1000 epochs = 1.1 per degree of freedom, outside the band 2 – 3"), 1);
  EXPECT_THROW(parse_thresholds(R"({"inmotion": {"mean_nis_per_dof": {"pos": [0.1, 2]}}})", "t"), InputError);
  EXPECT_THROW(parse_thresholds(R"({"inmotion": {"mean_nis_per_dof": {"default": [2]}}})", "t"), InputError);
  EXPECT_THROW(parse_thresholds(R"({"inmotion": {"nis": {}}})", "t"), InputError);
  EXPECT_THROW(parse_thresholds(R"({"combined": {"max_move_sigmas": "1"}})", "t"), InputError);
}

TEST(DbApprovalQuality, AFilterThatScaledTheImuAwayIsRefused) {
  // Consistent NIS bought by the adaptive noise (the real walk before issue 53: ×3.5e5 at the end)
  // is no calibration; a scale that came back down (the same walk now: ×18.8 at most, ×1 at the
  // end) is not a reason.
  std::map<std::string, NisConsistency> nis;
  nis["position"].mean_nis = 3.01;
  nis["position"].expected_nis = 3;
  nis["position"].epochs = 470;
  CoefficientSetRecord set;
  FitEvidence ev;
  ev.nis = nis;
  ev.adaptive = AdaptiveNoiseSummary{};
  ev.adaptive->scale_max = 6.44e5;
  ev.adaptive->scale_end = 3.5e5;
  auto why = fit_quality_reasons(set, ev, default_thresholds().quality);
  ASSERT_EQ(why.size(), 1u);
  EXPECT_EQ(count_with(why, "in-motion filter: the navigation noise variance was scaled ×3.5e+05 at the end of the fit (limit 10)"), 1);
  ev.adaptive->scale_max = 18.8;
  ev.adaptive->scale_end = 1;
  EXPECT_TRUE(fit_quality_reasons(set, ev, default_thresholds().quality).empty());
}

}  // namespace
}  // namespace calbench::db
