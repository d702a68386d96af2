// The effect registry's storage and truth-side hooks (calibration/effects/effect_registry.hpp):
// every effect's values live in EffectTerms::values at the slots the registry gives them, the
// typed views address exactly those slots, and the simulators' truth side is the rows' hooks.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "calibration/effects/effect_registry.hpp"

namespace calbench {
namespace {

// Every parameter of every effect has its own slot: setting one changes exactly that value and
// leaves every other effect absent.
TEST(EffectRegistry, EveryParameterHasItsOwnSlot) {
  std::set<const double*> seen;
  EffectTerms base;
  for (const EffectSpec& s : effect_specs()) {
    // Vector and noise effects have no axis (−1); triads and the gyro matrix one per axis.
    const bool per_axis = s.shape == EffectShape::triad_axis || s.shape == EffectShape::gyro_matrix ||
                          s.shape == EffectShape::axis_rows;
    for (int k = 0; k < 3; ++k)
      for (int a = per_axis ? 0 : -1; a < (per_axis ? 3 : 0); ++a)
        for (int p = 0; p < 6; ++p) {
          double* v = effect_param(s, base, k, a, p);
          if (!v) continue;
          EXPECT_TRUE(seen.insert(v).second) << s.key << " sensor " << k << " axis " << a << " p " << p;
          EffectTerms e;
          *effect_param(s, e, k, a, p) = 0.5;
          // A noise effect is there when its σ is (p 0); a correlation time alone is not a drift.
          const bool present = !(s.shape == EffectShape::noise && p == 1);
          for (const EffectSpec& o : effect_specs())
            EXPECT_EQ(effect_present(o, e), o.id == s.id && present) << "set " << s.key << " p " << p << ", looked at " << o.key;
          effect_clear(s, e);
          EXPECT_FALSE(e.any()) << s.key;
        }
  }
  EXPECT_GT(seen.size(), 100u);
}

TEST(EffectRegistry, TypedViewsAddressTheSameSlots) {
  EffectTerms e;
  effect_matrix(e, EffectId::g_sensitivity)(2, 0) = 7e-5;  // gyro z from f_x
  EXPECT_EQ(effect_value(effect_spec(EffectId::g_sensitivity), e, 0, 2, 0), 7e-5);
  effect_triad(e, EffectId::scale_asymmetry, 1)(1) = 3e-4;
  EXPECT_EQ(effect_value(effect_spec(EffectId::scale_asymmetry), e, 1, 1, 0), 3e-4);
  EXPECT_EQ(effect_value(effect_spec(EffectId::scale_asymmetry), e, 0, 1, 0), 0.0);
  effect_vector<3>(e, EffectId::lever_arm) = Vec3(0.1, -0.2, 0.3);
  EXPECT_EQ(effect_value(effect_spec(EffectId::lever_arm), e, 1, -1, 2), 0.3);
  // A view of another shape or size, or of a sensor the effect does not have, is a programming error.
  EXPECT_THROW(effect_vector<2>(e, EffectId::lever_arm), std::logic_error);
  EXPECT_THROW(effect_triad(e, EffectId::lever_arm, 1), std::logic_error);
  EXPECT_THROW(effect_triad(e, EffectId::cross_axis_rate, 0), std::logic_error);  // rows, not a triad
  EXPECT_THROW(effect_matrix(e, EffectId::temperature_bias), std::logic_error);
}

// An axis_rows effect: a row of components per axis of each allowed sensor, named for --inject.
TEST(EffectRegistry, AxisRowsAndTheirOutputs) {
  const EffectSpec& g2 = effect_spec(EffectId::g2_sensitivity);
  const EffectSpec& cc = effect_spec(EffectId::cross_coupling);
  EXPECT_EQ(effect_component_name(g2, 1, 3), "yz");
  EXPECT_EQ(effect_component_name(cc, 0, 0), "y");
  EXPECT_EQ(effect_component_name(cc, 0, 1), "z");
  EXPECT_EQ(effect_component_name(cc, 2, 0), "x");
  EffectTerms e;
  EXPECT_EQ(effect_param(g2, e, 1, 0, 0), nullptr);  // gyro only
  *effect_param(g2, e, 0, 0, 4) = 2e-6;       // gyro x: f_z·f_x
  *effect_param(cc, e, 1, 1, 1) = 3e-4;       // accel y: a_y·a_x
  *effect_param(cc, e, 0, 2, 0) = -1e-3;      // gyro z: ω_z·ω_x
  effect_triad(e, EffectId::size_effect, 1)(0) = 0.01;  // accel x sits 10 mm along x
  EffectContext c;
  c.w = Vec3(0.5, 0, 2.0);
  c.f = Vec3(3.0, 4.0, 9.0);
  Vec3 dg, da;
  sensor_side_terms(e, c, dg, da);
  EXPECT_DOUBLE_EQ(dg(0), 2e-6 * 9.0 * 3.0);
  EXPECT_DOUBLE_EQ(dg(2), -1e-3 * 2.0 * 0.5);
  EXPECT_DOUBLE_EQ(da(1), 3e-4 * 4.0 * 3.0);
  // The size effect is the x component of ω×(ω×r) at r = (0.01, 0, 0): ω_x(ω·r) − r_x|ω|².
  const Vec3 r(0.01, 0, 0);
  EXPECT_NEAR(da(0), c.w.cross(c.w.cross(r))(0), 1e-15);

  // The proof-mass offset: accel z's mass 2 mm along x (component 0: the next axis after z) and
  // 1 mm along y senses the z component of ω̇×r + ω×(ω×r) there; the others nothing of it.
  const EffectSpec& pm = effect_spec(EffectId::proof_mass_offset);
  EXPECT_EQ(effect_param(pm, e, 0, 0, 0), nullptr);  // accelerometers only
  EXPECT_EQ(effect_component_name(pm, 2, 0), "x");
  EffectTerms o;
  *effect_param(pm, o, 1, 2, 0) = 2e-3;
  *effect_param(pm, o, 1, 2, 1) = 1e-3;
  c.dw = Vec3(0.3, -0.7, 1.1);
  Vec3 og = Vec3::Zero(), oa = Vec3::Zero();
  sensor_side_terms(o, c, og, oa);
  const Vec3 rz(2e-3, 1e-3, 0);
  EXPECT_NEAR(oa(2), (c.dw.cross(rz) + c.w.cross(c.w.cross(rz)))(2), 1e-15);
  EXPECT_EQ(oa(0), 0.0);
  EXPECT_EQ(oa(1), 0.0);
  EXPECT_TRUE(og.isZero());
  EXPECT_TRUE(needs_rate_derivative(o));
}

// The truth side: identity without effects; with them, what the rows' hooks say.
TEST(EffectRegistry, TruthHooks) {
  EffectTerms none;
  EXPECT_EQ(truth_time(none, 12.5), 12.5);
  double angle = 1.0, rate = 0.5;
  truth_table_angle(none, angle, rate);
  EXPECT_EQ(angle, 1.0);
  EXPECT_EQ(rate, 0.5);
  EXPECT_EQ(time_stamp_offset(none), 0.0);
  EXPECT_FALSE(needs_rate_derivative(none));

  EffectTerms e;
  effect_vector<1>(e, EffectId::time_offset)(0) = 0.004;
  effect_vector<2>(e, EffectId::table_wobble) = Eigen::Vector2d(1e-4, -2e-4);
  effect_vector<2>(e, EffectId::misalignment) = Eigen::Vector2d(3e-4, 0.0);
  effect_vector<3>(e, EffectId::lever_arm)(0) = 0.01;
  effect_triad(e, EffectId::temperature_bias, 0)(0) = 1e-5;
  EXPECT_DOUBLE_EQ(truth_time(e, 12.5), 12.5 - 0.004);
  EXPECT_EQ(time_stamp_offset(e), 0.004);
  EXPECT_TRUE(needs_rate_derivative(e));
  truth_table_angle(e, angle, rate);
  EXPECT_DOUBLE_EQ(angle, 1.0 + 1e-4 * std::sin(1.0) - 2e-4 * std::cos(1.0));
  EXPECT_DOUBLE_EQ(rate, 0.5 * (1.0 + 1e-4 * std::cos(1.0) + 2e-4 * std::sin(1.0)));
  // A base tilted about north, IMU axes = level axes: gravity and the Earth rate turn by −ψ×.
  const Mat3 C = Mat3::Identity();
  const Vec3 f_b(0, 0, -9.8), w_ie_b(7e-5, 0, -3e-5);
  Vec3 f = f_b, w = w_ie_b;
  truth_level_frame(e, C, f_b, w_ie_b, f, w);
  EXPECT_NEAR(f(1), -(3e-4 * 9.8), 1e-12);  // −(ψ × f): ψ_N·f_D about north moves f into −east
  EXPECT_NEAR(f(0), 0.0, 1e-15);
  EXPECT_NEAR(w(1), -(0 - 3e-4 * -3e-5), 1e-18);

  // The time-stamp copy keeps the time offset and nothing else.
  const EffectTerms ts = time_stamp_terms(e);
  EXPECT_EQ(time_stamp_offset(ts), 0.004);
  EXPECT_EQ(effect_ids_present(ts), std::vector<std::string>{"time_offset"});
}

// The spec fields that replaced lists of names: what a simulated drive refuses, what the simulated
// factory calibration of a drive's unit leaves out, what folds into M.
TEST(EffectRegistry, RolesComeFromTheRows) {
  std::set<std::string> refused, installation, folds;
  for (const EffectSpec& s : effect_specs()) {
    if (s.drive_sim_refusal) refused.insert(s.key);
    if (s.drive_installation) installation.insert(s.key);
    if (s.folds_into_scale) folds.insert(s.key);
  }
  EXPECT_EQ(refused, (std::set<std::string>{"temperature_bias", "temperature_scale", "temperature_rate", "misalignment",
                                            "table_wobble"}));
  EXPECT_EQ(installation, (std::set<std::string>{"time_offset", "lever_arm", "scale_factor"}));
  EXPECT_EQ(folds, (std::set<std::string>{"scale_factor"}));
  EXPECT_EQ(noise_effect_spec().id, EffectId::correlated_drift);
}

}  // namespace
}  // namespace calbench
