// Composition of two successive corrections (common/sensor_model.hpp), as the store uses it
// to build combined sets: M = (I+M1)(I+M2) − I, b = b1 + (I+M1)·b2.
#include <gtest/gtest.h>

#include "db_test_util.hpp"

namespace calbench::db {
namespace {

TEST(DbCompose, MatchesTheFormulaExactly) {
  const SensorErrors a = test::random_errors(1), b = test::random_errors(2);
  const SensorErrors c = compose(a, b);
  const Mat3 I = Mat3::Identity();
  for (const auto* pair : {&c.gyro, &c.accel}) {
    const TriadErrors& t1 = pair == &c.gyro ? a.gyro : a.accel;
    const TriadErrors& t2 = pair == &c.gyro ? b.gyro : b.accel;
    const Mat3 M = (I + t1.M) * (I + t2.M) - I;
    const Vec3 bias = t1.bias + (I + t1.M) * t2.bias;
    EXPECT_EQ((pair->M - M).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((pair->bias - bias).cwiseAbs().maxCoeff(), 0.0);
  }
}

TEST(DbCompose, CorrectingTwiceEqualsCorrectingWithTheComposition) {
  // Raw data described by `first`; data corrected with `first` still has the errors `second`
  // (what an in-motion fit on bench-corrected data estimates). Correcting raw data with `first`
  // then `second` must equal correcting it once with compose(first, second).
  const SensorErrors first = test::random_errors(11), second = test::random_errors(12);
  const SensorErrors c = compose(first, second);
  std::mt19937 g(5);
  std::uniform_real_distribution<double> u(-5, 5);
  for (int k = 0; k < 100; ++k) {
    const Vec3 truth(u(g), u(g), u(g));
    // The sensor: true → second's errors → first's errors (raw = (I+M1)((I+M2)t + b2) + b1).
    const Vec3 raw = first.gyro.measure(second.gyro.measure(truth));
    const Vec3 twice = second.gyro.correct(first.gyro.correct(raw));
    const Vec3 once = c.gyro.correct(raw);
    EXPECT_LT((twice - once).cwiseAbs().maxCoeff(), 1e-13);
    EXPECT_LT((once - truth).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((c.gyro.measure(truth) - raw).cwiseAbs().maxCoeff(), 1e-13);
    const Vec3 raw_a = first.accel.measure(second.accel.measure(truth));
    EXPECT_LT((c.accel.correct(raw_a) - second.accel.correct(first.accel.correct(raw_a))).cwiseAbs().maxCoeff(), 1e-13);
  }
}

TEST(DbCompose, IdentityIsNeutralAndOrderMatters) {
  const SensorErrors a = test::random_errors(3), b = test::random_errors(4);
  SensorErrors zero;  // no errors, σ 0
  const SensorErrors l = compose(zero, a), r = compose(a, zero);
  EXPECT_LT((l.gyro.M - a.gyro.M).cwiseAbs().maxCoeff(), 1e-15);  // (I+0)(I+M) − I rounds
  EXPECT_LT((r.accel.bias - a.accel.bias).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_GT((compose(a, b).gyro.M - compose(b, a).gyro.M).cwiseAbs().maxCoeff(), 1e-9);
}

}  // namespace
}  // namespace calbench::db
