// Where innovations grow by motion condition (calibration/diagnosis/innovation_conditions.hpp):
// consistent innovations grow with no condition, whatever the motion; innovations whose σ grows
// with the turn rate (a lever arm's, a timing error's signature) are found to grow with the turn
// rate and with nothing else; a wrong noise model at standstill is found at standstill; serially
// correlated innovations need a larger difference (fewer effective samples), so a modest growth
// that white innovations show significantly is not called on strongly correlated ones.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "calibration/diagnosis/innovation_conditions.hpp"

using namespace calbench;

namespace {

// 10 Hz, 600 s: standstill for the first 60 s, then moving with a speed, turn rate and acceleration
// each varying on its own period (independent of each other over the drive). `sd(speed, turn, accel,
// still)` multiplies the innovations' standard deviation; `ar` their lag-1 correlation.
template <class Sd>
std::vector<InnovationSample> drive(std::uint64_t seed, double ar, Sd sd) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<InnovationSample> x;
  Vec3 e = Vec3::Zero();
  for (int k = 0; k < 6000; ++k) {
    InnovationSample v;
    v.t = 0.1 * k;
    const bool still = v.t < 60;
    v.speed = still ? 0.01 : 8 + 6 * std::sin(2 * M_PI * v.t / 97.0);
    v.turn_rate = still ? 0.0 : 0.3 * std::sin(2 * M_PI * v.t / 23.0);
    v.accel = still ? 0.0 : 1.0 + std::sin(2 * M_PI * v.t / 41.0);
    const Vec3 w(n(rng), n(rng), n(rng));
    e = ar * e + std::sqrt(1 - ar * ar) * w;
    v.nu = sd(v.speed, std::abs(v.turn_rate), v.accel, still) * e;
    v.S = Mat3::Identity();
    v.nis = v.nu.squaredNorm();
    x.push_back(v);
  }
  return x;
}

const ConditionBreakdown& find(const std::vector<ConditionBreakdown>& b, const std::string& name) {
  for (const auto& c : b)
    if (c.condition == name) return c;
  throw std::runtime_error("no condition " + name);
}

}  // namespace

TEST(InnovationConditions, ConsistentInnovationsGrowWithNothing) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const auto b = innovation_conditions(drive(seed, 0.0, [](double, double, double, bool) { return 1.0; }));
    ASSERT_EQ(b.size(), 4u);
    for (const auto& c : b) EXPECT_FALSE(c.grows) << c.condition << " ratio " << c.ratio << " z " << c.z;
    EXPECT_TRUE(growing_conditions_text(b).empty());
    const auto& m = find(b, "motion");
    EXPECT_EQ(m.bins[1].label, "standstill");
    EXPECT_EQ(m.bins[1].epochs, 600);
    EXPECT_EQ(m.bins[2].label, "start of motion");
    EXPECT_EQ(m.bins[2].epochs, 50);
    EXPECT_NEAR(m.bins[0].nis_per_dof, 1.0, 0.08);
  }
}

TEST(InnovationConditions, GrowthWithTurnRateIsFoundThereOnly) {
  const auto b = innovation_conditions(drive(4, 0.0, [](double, double w, double, bool) { return 1.0 + 5 * w; }));
  const auto& t = find(b, "turn rate");
  EXPECT_TRUE(t.grows);
  EXPECT_GT(t.ratio, 2.0);
  EXPECT_GT(t.bins[2].lo, t.bins[0].hi);  // the terciles are ordered ranges
  EXPECT_FALSE(find(b, "speed").grows);
  EXPECT_FALSE(find(b, "acceleration").grows);
  EXPECT_NE(growing_conditions_text(b).find("turn rate"), std::string::npos);
}

TEST(InnovationConditions, ANoiseModelWrongAtStandstillIsFoundThere) {
  const auto b = innovation_conditions(drive(5, 0.0, [](double, double, double, bool still) { return still ? 2.0 : 1.0; }));
  const auto& m = find(b, "motion");
  EXPECT_TRUE(m.grows);
  EXPECT_EQ(m.bins[static_cast<std::size_t>(m.grown)].label, "standstill");
  EXPECT_NEAR(m.ratio, 4.0, 0.8);  // σ ×2: NIS ×4
}

TEST(InnovationConditions, CorrelatedInnovationsNeedMoreEvidence) {
  // A 30 % larger σ with acceleration above 1 m/s²: significant on white innovations; the same on
  // innovations with lag-1 correlation 0.97 carries ~65× fewer independent samples.
  auto sd = [](double, double, double a, bool) { return a > 1.0 ? 1.3 : 1.0; };
  const auto white = find(innovation_conditions(drive(6, 0.0, sd)), "acceleration");
  const auto corr = find(innovation_conditions(drive(6, 0.97, sd)), "acceleration");
  EXPECT_TRUE(white.grows) << white.ratio << " z " << white.z;
  EXPECT_GT(white.z, 2 * corr.z);
}

TEST(InnovationConditions, GatedEpochsAreLeftOut) {
  auto x = drive(7, 0.0, [](double, double, double, bool) { return 1.0; });
  for (std::size_t k = 1000; k < x.size(); k += 3) {  // every third moving epoch gated, with a huge NIS
    x[k].status = 1;
    x[k].nis = 1e6;
  }
  const auto b = innovation_conditions(x);
  for (const auto& c : b) EXPECT_FALSE(c.grows) << c.condition;
  EXPECT_LT(find(b, "motion").bins[0].nis_per_dof, 1.2);
}
