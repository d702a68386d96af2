// Issue 7, item 4: the estimators understand the catalogue keys. A recording with a concealed
// effect biases the plain bench fit of b and M; the same fit with the effect's terms held fixed
// (the true terms, or those `diagnose` writes into IMPROVED.json) gives b and M within 3σ of the
// simulated truth. The estimator sees only the simulated recording (IMU output + nominal reference)
// and the terms; the simulator's b, M are used only for the comparison.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "bench/diagnose/diagnose_run.hpp"
#include "bench/diagnose/effects_json.hpp"
#include "bench/io/plan_toml.hpp"
#include "calibration/effects/effect_registry.hpp"
#include "calibration/bench_fit_effects.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

using namespace units;

const BenchPlan& plan() {
  static const BenchPlan p = load_plan(std::string(CALBENCH_SOURCE_DIR) + "/bench/plans/diagnose.toml");
  return p;
}

// Largest |estimate − truth| / σ over the estimated b and M of both triads, and where it is.
double worst_sigma(const SensorErrors& est, const SensorErrors& truth, std::string* where = nullptr) {
  double worst = 0;
  auto chk = [&](double e, double s, double t, const std::string& name) {
    if (!std::isfinite(s) || s <= 0) return;
    const double r = std::abs(e - t) / s;
    if (r > worst) {
      worst = r;
      if (where) *where = name;
    }
  };
  char name[32];
  for (int i = 0; i < 3; ++i) {
    std::snprintf(name, sizeof name, "gyro.bias[%d]", i);
    chk(est.gyro.bias(i), est.gyro.sigma_bias(i), truth.gyro.bias(i), name);
    std::snprintf(name, sizeof name, "accel.bias[%d]", i);
    chk(est.accel.bias(i), est.accel.sigma_bias(i), truth.accel.bias(i), name);
    for (int j = 0; j < 3; ++j) {
      std::snprintf(name, sizeof name, "gyro.M[%d][%d]", i, j);
      chk(est.gyro.M(i, j), est.gyro.sigma_M(i, j), truth.gyro.M(i, j), name);
      std::snprintf(name, sizeof name, "accel.M[%d][%d]", i, j);
      chk(est.accel.M(i, j), est.accel.sigma_M(i, j), truth.accel.M(i, j), name);
    }
  }
  return worst;
}

struct Case {
  const char* name;
  EffectTerms fx;
  std::uint64_t seed;
};

std::vector<Case> cases() {
  std::vector<Case> c;
  EffectTerms a;
  effect_vector<3>(a, EffectId::lever_arm)(2) = 0.004;
  c.push_back({"lever_arm z 4 mm", a, 3});
  EffectTerms b;
  effect_triad(b, EffectId::scale_nonlinearity, 0)(1) = -2e-5;
  c.push_back({"scale_nonlinearity gyro y", b, 4});
  EffectTerms d;
  effect_matrix(d, EffectId::g_sensitivity)(0, 1) = 0.009 * kDeg / kG0;
  effect_triad(d, EffectId::scale_asymmetry, 1)(0) = -300e-6;
  c.push_back({"g_sensitivity x←y + accel asymmetry x", d, 5});
  return c;
}

TEST(BenchFitEffects, HeldFixedTermsRemoveTheBiasOfAConcealedEffect) {
  for (const Case& cs : cases()) {
    BenchSimOptions so;
    so.seed = cs.seed;
    so.effects = cs.fx;
    const SensorErrors truth = draw_random_unit(700 + cs.seed);
    const DiagInput in = simulate_diag_input(plan(), truth, so);
    for (BenchMethod m : {BenchMethod::lsq, BenchMethod::ekf}) {
      BenchFitOptions o;
      o.table = plan().table;
      o.method = m;
      std::string w_plain, w_fixed;
      const double plain = worst_sigma(fit_bench(in.blocks, o).estimate, truth, &w_plain);
      const double fixed = worst_sigma(fit_bench_with_effects(in.data, cs.fx, o).estimate, truth, &w_fixed);
      std::printf("%-40s %s: plain fit worst %.1fσ (%s), terms held fixed worst %.2fσ (%s)\n", cs.name,
                  m == BenchMethod::lsq ? "lsq" : "ekf", plain, w_plain.c_str(), fixed, w_fixed.c_str());
      EXPECT_GT(plain, 3.0) << cs.name << ": the concealed effect should bias the plain fit";
      EXPECT_LE(fixed, 3.0) << cs.name << ": " << w_fixed;
    }
  }
}

// The real chain: diagnose finds the effect and writes IMPROVED.json; the fit reads its keys.
TEST(BenchFitEffects, ImprovedJsonFromDiagnoseGivesUnbiasedFit) {
  EffectTerms fx;
  effect_vector<3>(fx, EffectId::lever_arm)(1) = -0.003;
  effect_triad(fx, EffectId::scale_nonlinearity, 0)(2) = 3e-5;
  BenchSimOptions so;
  so.seed = 9;
  so.effects = fx;
  const SensorErrors truth = draw_random_unit(709);
  const DiagInput in = simulate_diag_input(plan(), truth, so);
  const DiagRun run = run_diagnosis(in, nullptr, plan().table);
  EffectTerms sigma;
  const EffectTerms found = effects_from_json(run.improved.extra, "IMPROVED.json", &sigma);
  const auto ids = effect_ids_present(found);
  std::string list;
  for (const auto& id : ids) list += " " + id;
  ASSERT_EQ(ids.size(), 2u) << "diagnose should add lever_arm and scale_nonlinearity, added:" << list;
  EXPECT_NEAR(effect_vector<3>(found, EffectId::lever_arm)(1), -0.003, 0.2 * 0.003);
  BenchFitOptions o;
  o.table = plan().table;
  std::string w_plain, w_fixed;
  const double plain = worst_sigma(fit_bench(in.blocks, o).estimate, truth, &w_plain);
  // σ of the terms (from the diagnosis's joint fit) propagated into the σ of b and M.
  const double fixed = worst_sigma(fit_bench_with_effects(in.data, found, o, &sigma).estimate, truth, &w_fixed);
  const double conditional = worst_sigma(fit_bench_with_effects(in.data, found, o).estimate, truth);
  std::printf("(σ conditional on exact terms: worst %.2fσ)\n", conditional);
  std::printf("IMPROVED.json terms: plain worst %.1fσ (%s), held fixed worst %.2fσ (%s)\n", plain, w_plain.c_str(),
              fixed, w_fixed.c_str());
  EXPECT_GT(plain, 3.0);
  EXPECT_LE(fixed, 3.0) << w_fixed;
}

// table_wobble held fixed: the static positions count too (the table stands at θ + δ(θ), gravity
// turned about the inner axis the diagnosis data derive from the recording). For comparison the
// same terms with the axis withheld (rotating steps only, as before the axis was derived). A large
// wobble (2′): at 40″ the plain fit is biased by only 2σ.
TEST(BenchFitEffects, TableWobbleHeldFixedIncludesStaticPositions) {
  EffectTerms fx;
  effect_vector<2>(fx, EffectId::table_wobble) = Eigen::Vector2d(30.0, 120.0) / 3600 * kDeg;
  BenchSimOptions so;
  so.seed = 14;
  so.effects = fx;
  const SensorErrors truth = draw_random_unit(714);
  const DiagInput in = simulate_diag_input(plan(), truth, so);
  DiagData rotating_only = in.data;
  for (SubBlock& s : rotating_only.subs) s.inner_axis.setZero();
  for (BenchMethod m : {BenchMethod::lsq, BenchMethod::ekf}) {
    BenchFitOptions o;
    o.table = plan().table;
    o.method = m;
    std::string w_plain, w_fixed, w_rot;
    const double plain = worst_sigma(fit_bench(in.blocks, o).estimate, truth, &w_plain);
    const double fixed = worst_sigma(fit_bench_with_effects(in.data, fx, o).estimate, truth, &w_fixed);
    const double rot = worst_sigma(fit_bench_with_effects(rotating_only, fx, o).estimate, truth, &w_rot);
    std::printf("table_wobble %s: plain worst %.1fσ (%s), held fixed worst %.2fσ (%s), rotating steps only %.2fσ (%s)\n",
                m == BenchMethod::lsq ? "lsq" : "ekf", plain, w_plain.c_str(), fixed, w_fixed.c_str(), rot, w_rot.c_str());
    EXPECT_GT(plain, 3.0);
    EXPECT_LE(fixed, 3.0) << w_fixed;
  }
}

// Without effects the corrected-block path is the plain fit on (nearly) the same blocks.
TEST(BenchFitEffects, NoTermsAgreesWithThePlainFit) {
  BenchSimOptions so;
  so.seed = 12;
  const SensorErrors truth = draw_random_unit(712);
  const DiagInput in = simulate_diag_input(plan(), truth, so);
  BenchFitOptions o;
  o.table = plan().table;
  const SensorErrors a = fit_bench(in.blocks, o).estimate;
  const SensorErrors b = fit_bench_with_effects(in.data, EffectTerms{}, o).estimate;
  // The blocks differ (~1.04 s parents of 0.05 s sub-blocks instead of 1 s sample blocks; in the
  // spinning steps a block mean samples a different part of the revolution), so the estimates move
  // by a fraction of σ, never more.
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT(std::abs(a.gyro.bias(i) - b.gyro.bias(i)), 1.0 * a.gyro.sigma_bias(i));
    EXPECT_LT(std::abs(a.accel.bias(i) - b.accel.bias(i)), 1.0 * a.accel.sigma_bias(i));
    for (int j = 0; j < 3; ++j) {
      if (std::isfinite(a.gyro.sigma_M(i, j))) {
        EXPECT_LT(std::abs(a.gyro.M(i, j) - b.gyro.M(i, j)), 1.0 * a.gyro.sigma_M(i, j));
      }
      if (std::isfinite(a.accel.sigma_M(i, j))) {
        EXPECT_LT(std::abs(a.accel.M(i, j) - b.accel.M(i, j)), 1.0 * a.accel.sigma_M(i, j));
      }
    }
  }
}

TEST(BenchFitEffects, CorrelatedDriftKeyReplacesTheDriftPrior) {
  EffectTerms e;
  *effect_param(effect_spec(EffectId::correlated_drift), e, 1, -1, 0) = 1e-2;
  *effect_param(effect_spec(EffectId::correlated_drift), e, 1, -1, 1) = 60;
  BenchFitOptions o;
  const BenchFitOptions p = options_with_effects(o, e);
  EXPECT_EQ(p.noise.accel.drift_sigma, 1e-2);
  EXPECT_EQ(p.noise.accel.drift_tau_s, 60);
  EXPECT_EQ(p.noise.gyro.drift_sigma, o.noise.gyro.drift_sigma);
  EXPECT_EQ(effect_ids_present(e), std::vector<std::string>{"correlated_drift"});
}

}  // namespace
}  // namespace calbench
