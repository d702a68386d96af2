#include <gtest/gtest.h>

#include "calibration/qc/outage_plan.hpp"

namespace calbench::qc {
namespace {

// Fix epochs at 1 Hz over [0, T].
std::vector<double> times(int T) {
  std::vector<double> t;
  for (int k = 0; k <= T; ++k) t.push_back(k);
  return t;
}

TEST(QcOutagePlan, SpreadEvenlyWithoutOverlapInTheOrderGiven) {
  const auto t = times(900);
  std::vector<bool> ok(t.size(), true);
  for (int k = 0; k < 100; ++k) ok[static_cast<std::size_t>(k)] = false;  // not converged for 100 s
  OutageRequest req;  // 15, 30, 60 s, 3 each, 30 s gap
  const OutagePlan p = plan_outages(t, ok, 900, req);
  ASSERT_EQ(p.outages.size(), 9u);
  EXPECT_TRUE(p.not_placed.empty());
  // Evenly spread: the slack (800 - 315 - 240 = 245 s) shared in 10 equal parts, before the first
  // outage, between the outages and after the last.
  EXPECT_DOUBLE_EQ(p.outages[0].start_s, 125);  // the first converged epoch (100 s) + 24.5 s, on a fix
  const double lengths[] = {15, 30, 60};
  for (std::size_t i = 0; i < p.outages.size(); ++i) {
    EXPECT_DOUBLE_EQ(p.outages[i].length_s, lengths[i % 3]);
    EXPECT_LE(p.outages[i].start_s + p.outages[i].length_s, 900);
    EXPECT_TRUE(ok[p.outages[i].epoch]);
    if (i) EXPECT_GE(p.outages[i].start_s, p.outages[i - 1].start_s + p.outages[i - 1].length_s + 30);
  }
  EXPECT_NEAR(900 - (p.outages.back().start_s + 60), 24.5, 1.0);
}

TEST(QcOutagePlan, StartsOnlyWhereEligibleAndAfterTheEarliestTime) {
  const auto t = times(600);
  std::vector<bool> ok(t.size(), false);
  for (std::size_t k = 0; k < t.size(); ++k) ok[k] = (k / 50) % 2 == 1;  // moving 50 s, standing 50 s
  OutageRequest req;
  req.lengths_s = {15};
  req.count = 4;
  req.earliest_s = 200;
  const OutagePlan p = plan_outages(t, ok, 600, req);
  ASSERT_FALSE(p.outages.empty());
  for (const auto& o : p.outages) {
    EXPECT_GE(o.start_s, 200);
    EXPECT_TRUE(ok[o.epoch]);
    EXPECT_EQ(t[o.epoch], o.start_s);
  }
  EXPECT_EQ(p.outages.size() + p.not_placed.size(), 4u);
}

TEST(QcOutagePlan, WhatDoesNotFitIsListedNotPlaced) {
  const auto t = times(135);  // the walk: 135 s
  std::vector<bool> ok(t.size(), true);
  OutageRequest req;  // 3 x (15 + 30 + 60) s cannot fit
  const OutagePlan p = plan_outages(t, ok, 135, req);
  // 15 + 30 s and one 30-s gap (75 s) fit; with the 60-s outage and a second gap 165 s are needed.
  ASSERT_EQ(p.outages.size(), 2u);
  EXPECT_EQ(p.not_placed.size(), 7u);
  EXPECT_DOUBLE_EQ(p.not_placed.front().length_s, 60);
  EXPECT_NE(p.not_placed.front().reason.find("no room"), std::string::npos);
  // Nowhere converged: nothing placed, each with its reason.
  const OutagePlan none = plan_outages(t, std::vector<bool>(t.size(), false), 135, req);
  EXPECT_TRUE(none.outages.empty());
  EXPECT_EQ(none.not_placed.size(), 9u);
}

}  // namespace
}  // namespace calbench::qc
