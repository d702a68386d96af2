#include <gtest/gtest.h>

#include "db/fleet.hpp"

namespace calbench::db {
namespace {

TEST(DbFleet, RobustZFlagsTheOutlierOnly) {
  std::vector<FleetValue> v;
  const double xs[] = {1.0, 1.1, 0.9, 1.05, 0.95, 1.02, 0.98, 5.0};
  int i = 0;
  for (double x : xs) v.push_back({std::string("S").append(std::to_string(i++)), i, 1, "approved", "gyro.M.xx", x * 1e-3, 1e-5});
  const auto stats = fleet_stats(v);
  ASSERT_EQ(stats.size(), 24u);
  const auto& c = stats[3];  // gyro.M.xx
  ASSERT_EQ(c.name, "gyro.M.xx");
  EXPECT_EQ(c.n, 8u);
  EXPECT_NEAR(c.median, 1.01e-3, 1e-12);
  int outliers = 0;
  for (const auto& p : c.points) {
    outliers += p.outlier;
    if (p.outlier) {
      EXPECT_EQ(p.serial, "S7");
    }
  }
  EXPECT_EQ(outliers, 1);
  EXPECT_EQ(c.unit, "ppm");
  EXPECT_EQ(stats[0].n, 0u);
}

TEST(DbFleet, MedianOfEvenAndOdd) {
  EXPECT_DOUBLE_EQ(median_of({3, 1, 2}), 2);
  EXPECT_DOUBLE_EQ(median_of({4, 1, 3, 2}), 2.5);
}

}  // namespace
}  // namespace calbench::db
