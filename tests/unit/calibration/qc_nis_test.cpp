#include <gtest/gtest.h>

#include <cmath>

#include "calibration/qc/nis_test.hpp"

namespace calbench::qc {
namespace {

// Reference quantiles: the regularised incomplete gamma function (series / continued fraction)
// inverted by bisection in double precision, computed independently of this code.
TEST(QcNisTest, QuantilesMatchTheChiSquareDistribution) {
  EXPECT_NEAR(two_sided_z(0.95), 1.959963984540054, 1e-12);
  EXPECT_NEAR(two_sided_z(0.99), 2.5758293035489, 1e-12);
  const double z = two_sided_z(0.95);
  EXPECT_NEAR(chi2_quantile(100, z), 129.5612, 129.5612 * 1e-4);
  EXPECT_NEAR(chi2_quantile(100, -z), 74.22193, 74.22193 * 1e-4);
  EXPECT_NEAR(chi2_quantile(6000, z), 6216.59128, 0.01);
}

TEST(QcNisTest, RegionsAndVerdicts) {
  // 2000 epochs of 3-dof innovations: mean NIS region [2.8936, 3.1083] (exact χ²(6000) quantiles / 2000).
  const NisTest ok = nis_test(2000, 3, 3.01, 0.951);
  EXPECT_NEAR(ok.mean_lo, 2.8935986, 1e-5);
  EXPECT_NEAR(ok.mean_hi, 3.1082956, 1e-5);
  EXPECT_EQ(ok.mean, NisVerdict::consistent);
  EXPECT_EQ(ok.fraction, NisVerdict::consistent);
  EXPECT_NEAR(ok.frac_lo, 0.95 - 1.959964 * std::sqrt(0.95 * 0.05 / 2000), 1e-6);
  EXPECT_EQ(nis_test(2000, 3, 3.2, 0.93).mean, NisVerdict::too_large);
  EXPECT_EQ(nis_test(2000, 3, 3.2, 0.93).fraction, NisVerdict::too_large);
  EXPECT_EQ(nis_test(2000, 3, 0.4, 1.0).mean, NisVerdict::too_small);
  EXPECT_EQ(nis_test(2000, 3, 0.4, 1.0).fraction, NisVerdict::too_small);
  // Few epochs: a wide region; none: nothing to say.
  const NisTest few = nis_test(20, 3, 3.5, 0.9);
  EXPECT_EQ(few.mean, NisVerdict::consistent);
  EXPECT_GT(few.mean_hi, 4.0);
  EXPECT_EQ(nis_test(0, 3, 0, 0).mean, NisVerdict::no_data);
}

}  // namespace
}  // namespace calbench::qc
