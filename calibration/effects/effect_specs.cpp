// The rows of the effect registry (effect_registry.hpp): one spec per effect. Adding an effect
// is one row here (and its EffectId); nothing outside calibration/effects/ names it.
#include <cmath>

#include "calibration/effects/bench_attitude.hpp"
#include "calibration/effects/effect_registry.hpp"
#include "common/units.hpp"

namespace calbench {

namespace {

using namespace units;

constexpr unsigned kBoth = 3, kGyro = 1;

double identity(double v, int) { return v; }

// The common part of a scale-factor polynomial term (K2, K3): one parameter per axis of both triads,
// a function of the axis's own input, revealed by the rate (or force) magnitudes on the bench; not a
// drive candidate (a car's inputs are too small for it), removed from the samples where a set
// carries it.
EffectSpec scale_polynomial_row(EffectId id, const char* key, double (*out)(double p, double x, double, const EffectContext&)) {
  EffectSpec s{};
  s.id = id;
  s.key = key;
  s.shape = EffectShape::triad_axis;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 1;
  s.axis_output = out;
  s.bench_candidate = true;
  s.condition = "rate";
  s.shows_on = -1;
  s.drive = DriveDiagnosis::alternative_only;  // x² beside the asymmetry's |x|, x³ beside x·|x|
  s.drive_prior[0] = s.drive_prior[1] = 1e-2;
  s.own_input = true;
  s.curvature = true;
  s.compensation = DriveCompensation::output;
  // A newer term beside an established look-alike of the same input (|x|, x·|x|): named only where
  // it explains the recording better than that one by Δχ² 10.
  s.prior_penalty = 10;
  return s;
}

// The rows: catalogue order, which is the order of the candidate terms (per sensor and axis the
// triad_axis rows, then the others) and of every list of effects the programme prints.
}  // namespace

std::vector<EffectSpec> make_effect_specs() {
  std::vector<EffectSpec> v;
  EffectSpec s{};
  auto row = [&](EffectSpec x) { v.push_back(x); };

  // ---- temperature_bias
  s = EffectSpec{};
  s.id = EffectId::temperature_bias;
  s.key = "temperature_bias";
  s.physics =
      "bias moves with die temperature (warm-up)";
  s.model = "b_T,i·(T − T0)";
  s.shape = EffectShape::triad_axis;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 1;
  s.axis_output = [](double p, double, double dT, const EffectContext&) { return p * dT; };
  s.si_unit[0] = "rad/s/K";
  s.si_unit[1] = "m/s^2/K";
  s.bench_display = {[](double x, int k) { return k == 0 ? x / kDegPerHour : x / kMilliG; }, {"°/h/K", "mg/K"}};
  s.drive_display = {[](double x, int k) { return k == 0 ? x * (1.0 / kDegPerHour) : x * (1.0 / kMilliG); }, {"°/h/K", "mg/K"}};
  s.json_value[0] = "gyro_rad_s_per_K";
  s.json_value[1] = "accel_m_s2_per_K";
  s.json_t0 = true;
  s.temperature_driven = true;
  s.bench_candidate = true;
  s.excited_by = "a temperature span (a thermal plan; the warm-up alone spans ~2 K)";
  s.condition = "temperature";
  s.shows_on = -1;
  s.drive = DriveDiagnosis::with_temperature;
  s.drive_prior[0] = 1e-4;
  s.drive_prior[1] = 1e-2;
  s.compensation = DriveCompensation::with_temperature;
  s.drive_ignored_reason = "imu.csv has no temperature column";
  s.drive_sim_refusal = "a simulated drive has no temperature: temperature terms cannot be injected";
  s.bench_sentence = "{who} error grows with temperature: temperature-dependent bias, ";
  s.drive_what = "temperature-dependent bias";
  s.lookalike = -1;
  row(s);

  // ---- temperature_scale
  s = EffectSpec{};
  s.id = EffectId::temperature_scale;
  s.key = "temperature_scale";
  s.physics =
      "scale factor moves with temperature";
  s.model = "s_T,i·(T − T0)·x_i";
  s.shape = EffectShape::triad_axis;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 1;
  s.axis_output = [](double p, double x, double dT, const EffectContext&) { return p * dT * x; };
  s.si_unit[0] = s.si_unit[1] = "1/K";
  s.bench_display = {[](double x, int) { return x / kPpm; }, {"ppm/K", "ppm/K"}};
  s.drive_display = {[](double x, int) { return x * 1e6; }, {"ppm/K", "ppm/K"}};
  s.json_value[0] = "gyro_per_K";
  s.json_value[1] = "accel_per_K";
  s.json_t0 = true;
  s.temperature_driven = true;
  s.bench_candidate = true;
  s.excited_by = "a temperature span with rates or forces of both signs at each temperature";
  s.condition = "temperature";
  s.shows_on = -1;
  s.drive = DriveDiagnosis::with_temperature;
  s.drive_prior[0] = s.drive_prior[1] = 1e-3;
  s.own_input = true;
  s.compensation = DriveCompensation::with_temperature;
  s.drive_ignored_reason = "imu.csv has no temperature column";
  s.drive_sim_refusal = "a simulated drive has no temperature: temperature terms cannot be injected";
  s.bench_sentence = "{who} scale factor changes with temperature: temperature-dependent scale factor, ";
  s.drive_what = "temperature-dependent scale factor";
  s.lookalike = -1;
  row(s);

  // ---- temperature_rate
  s = EffectSpec{};
  s.id = EffectId::temperature_rate;
  s.key = "temperature_rate";
  s.physics =
      "thermal lag: while the temperature changes the die is not isothermal, and the gradient (∝ dT/dt in a ramp or warm-up) shifts the bias — opposite while heating and cooling";
  s.model = "r_T,i·dT/dt";
  s.shape = EffectShape::triad_axis;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 1;
  s.axis_output = [](double p, double, double, const EffectContext& c) { return p * c.dtemp_k_s; };
  s.si_unit[0] = "rad/s/(K/s)";
  s.si_unit[1] = "m/s^2/(K/s)";
  s.bench_display = {[](double x, int k) { return k == 0 ? x / kDegPerHour / 60.0 : x / kMilliG / 60.0; },
                     {"°/h per K/min", "mg per K/min"}};
  s.drive_display = {identity, {"rad/s/(K/s)", "m/s^2/(K/s)"}};
  s.json_value[0] = "gyro_rad_s_per_K_per_s";
  s.json_value[1] = "accel_m_s2_per_K_per_s";
  s.temperature_driven = true;
  s.bench_candidate = true;
  s.excited_by = "a temperature that changes at different rates, heating and cooling (thermal_updown.toml)";
  s.condition = "dT/dt";
  s.shows_on = -1;
  // Not on drives: no dT/dt is derived from a drive (simulated drives have no temperature).
  s.drive = DriveDiagnosis::never;
  s.drive_prior[0] = s.drive_prior[1] = 1;
  s.compensation = DriveCompensation::ignored;
  s.drive_ignored_reason = "needs dT/dt, which the drive estimator does not derive";
  s.drive_sim_refusal = "a simulated drive has no temperature: temperature terms cannot be injected";
  s.bench_sentence =
      "{who} error follows the rate of temperature change (opposite on heating and cooling): thermal lag (dT/dt), ";
  s.lookalike = static_cast<int>(EffectId::temperature_bias);
  s.separation =
      "on a warm-up alone a bias ∝ T and one ∝ dT/dt look alike; a plan that heats and cools over the "
      "same range (thermal_updown) tells them apart";
  row(s);

  // ---- g_sensitivity
  s = EffectSpec{};
  s.id = EffectId::g_sensitivity;
  s.key = "g_sensitivity";
  s.physics =
      "gyro proof-mass responds to linear acceleration";
  s.model = "G·f (3×3, gyro)";
  s.shape = EffectShape::gyro_matrix;
  s.sensor = 0;
  s.sensors = kGyro;
  s.nparams = 3;
  s.sensor_output = [](const EffectTerms& e, const EffectContext& c, Vec3& dg, Vec3&) { dg += effect_matrix(e, EffectId::g_sensitivity) * c.f; };
  s.si_unit[0] = s.si_unit[1] = "rad/s/(m/s^2)";
  s.bench_display = {[](double x, int) { return x * kG0 / kDeg; }, {"°/s/g", "°/s/g"}};
  s.drive_display = {[](double x, int) { return x * (1.0 / kDeg * kG0); }, {"°/s/g", "°/s/g"}};
  s.json_value[0] = s.json_value[1] = "gyro_rad_s_per_m_s2";
  s.bench_candidate = true;
  s.excited_by = "positions with each specific-force component positive and negative";
  s.condition = "f";
  s.condition_by_column = true;
  s.shows_on = -1;
  s.drive = DriveDiagnosis::always;
  s.drive_prior[0] = s.drive_prior[1] = 2e-4;  // ~0.1 °/s/g
  s.compensation = DriveCompensation::output;
  s.bench_sentence = "{who} error grows with {condition}: g-sensitivity, ";
  s.drive_what = "g-sensitivity";
  s.lookalike = -1;
  row(s);

  // ---- g2_sensitivity: the anisoelastic (g²) gyro terms.
  s = EffectSpec{};
  s.id = EffectId::g2_sensitivity;
  s.key = "g2_sensitivity";
  s.physics =
      "gyro proof-mass suspension of unequal compliance: a drift ∝ products of specific-force components "
      "(anisoelastic, g² sensitivity; IEEE 1431). The squares are relative to f_z²: where |f| = g the "
      "isotropic part is a bias";
  s.model = "A_xx·f_x² + A_yy·f_y² + A_xy·f_x·f_y + A_yz·f_y·f_z + A_zx·f_z·f_x (per gyro axis)";
  s.shape = EffectShape::axis_rows;
  s.sensor = -1;
  s.sensors = kGyro;
  s.nparams = 5;
  s.sensor_output = [](const EffectTerms& e, const EffectContext& c, Vec3& dg, Vec3&) {
    const EffectSpec& x = effect_spec(EffectId::g2_sensitivity);
    const Vec3& f = c.f;
    const double q[5] = {f(0) * f(0), f(1) * f(1), f(0) * f(1), f(1) * f(2), f(2) * f(0)};
    for (int i = 0; i < 3; ++i)
      for (int p = 0; p < 5; ++p)
        if (const double v = effect_value(x, e, 0, i, p); v != 0) dg(i) += v * q[p];
  };
  s.si_unit[0] = s.si_unit[1] = "rad/s/(m/s^2)^2";
  s.bench_display = {[](double x, int) { return x * kG0 * kG0 / kDeg; }, {"°/s/g²", "°/s/g²"}};
  s.drive_display = {[](double x, int) { return x * (kG0 * kG0 / kDeg); }, {"°/s/g²", "°/s/g²"}};
  s.json_value[0] = s.json_value[1] = "gyro_rad_s_per_m2_s4";
  s.inject_keys = "xx,yy,xy,yz,zx";
  s.bench_candidate = true;
  s.prior_penalty = 10;  // a newer effect beside an established look-alike (g_sensitivity)
  s.excited_by = "positions with two or three specific-force components at once and the vertical axis both up and down (diagnose.toml's tilts)";
  s.condition = "f";
  s.shows_on = -1;
  // On a car f_z ≈ g: f_x·f_z is g-sensitivity to f_x again; not a candidate, an alternative.
  s.drive = DriveDiagnosis::alternative_only;
  s.drive_prior[0] = s.drive_prior[1] = 1e-4;
  s.compensation = DriveCompensation::output;
  s.bench_sentence = "{who} error grows with products of specific-force components: g²-sensitivity (anisoelastic), ";
  s.drive_what = "g²-sensitivity (anisoelastic)";
  s.lookalike = static_cast<int>(EffectId::g_sensitivity);
  s.separation =
      "where the IMU only stands with one axis up or down, f_x·f_z is ±g·f_x, a g-sensitivity; positions with "
      "the same horizontal force and the vertical axis up and down (diagnose.toml's axis-up/down positions and "
      "tilts) tell them apart";
  row(s);

  // ---- scale_nonlinearity
  s = EffectSpec{};
  s.id = EffectId::scale_nonlinearity;
  s.key = "scale_nonlinearity";
  s.physics =
      "scale factor grows linearly with |input| (quadratic error)";
  s.model = "k_i·x_i·|x_i|";
  s.shape = EffectShape::triad_axis;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 1;
  s.axis_output = [](double p, double x, double, const EffectContext&) { return p * x * std::abs(x); };
  s.si_unit[0] = "1/(rad/s)";
  s.si_unit[1] = "1/(m/s^2)";
  s.bench_display = {[](double x, int k) { return k == 0 ? x * kDeg / kPpm : x * kG0 / kPpm; }, {"ppm/(°/s)", "ppm/g"}};
  s.drive_display = {[](double x, int k) { return k == 0 ? x * (1e6 * kDeg) : x * (1e6 * kG0); }, {"ppm/(°/s)", "ppm/g"}};
  s.json_value[0] = "gyro_per_rad_s";
  s.json_value[1] = "accel_per_m_s2";
  s.bench_candidate = true;
  s.excited_by = "inputs of two or more magnitudes of both signs";
  s.condition = "rate";
  s.shows_on = -1;
  s.drive = DriveDiagnosis::always;
  s.drive_prior[0] = 1e-2;
  s.drive_prior[1] = 1e-3;
  s.own_input = true;
  s.curvature = true;
  s.compensation = DriveCompensation::output;
  s.bench_sentence = "{who} scale error grows with |input|: quadratic scale-factor nonlinearity, ";
  s.drive_what = "scale-factor nonlinearity";
  s.lookalike = -1;
  row(s);

  // ---- scale_asymmetry
  s = EffectSpec{};
  s.id = EffectId::scale_asymmetry;
  s.key = "scale_asymmetry";
  s.physics =
      "different scale for positive and negative input: M_ii ± a_i";
  s.model = "a_i·|x_i|";
  s.shape = EffectShape::triad_axis;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 1;
  s.axis_output = [](double p, double x, double, const EffectContext&) { return p * std::abs(x); };
  s.si_unit[0] = s.si_unit[1] = "1";
  s.bench_display = {[](double x, int) { return x / kPpm; }, {"ppm", "ppm"}};
  s.drive_display = {[](double x, int) { return x * 1e6; }, {"ppm", "ppm"}};
  s.json_value[0] = "gyro";
  s.json_value[1] = "accel";
  s.bench_candidate = true;
  s.excited_by = "inputs of both signs";
  s.condition = "rate";
  s.shows_on = -1;
  s.drive = DriveDiagnosis::always;
  s.drive_prior[0] = s.drive_prior[1] = 1e-2;
  s.own_input = true;
  s.curvature = true;
  s.compensation = DriveCompensation::output;
  s.bench_sentence = "{who} scale differs between positive and negative inputs: scale asymmetry, ";
  s.drive_what = "scale-factor asymmetry";
  s.lookalike = -1;
  row(s);

  // ---- scale_factor: a change of M_ii (a simulation's injected shift since the calibration, or
  // terms handed over by hand); a diagnosis that refits M folds it into M instead.
  s = EffectSpec{};
  s.id = EffectId::scale_factor;
  s.key = "scale_factor";
  s.physics =
      "the scale differs from the given coefficients' M_ii: changed since the calibration (ageing, shock), or set there at other rates (a nonlinearity the calibration model lacks). A candidate only where M is not refitted: drives with `--coeffs`";
  s.model = "s_i·x_i";
  s.shape = EffectShape::triad_axis;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 1;
  s.axis_output = [](double p, double x, double, const EffectContext&) { return p * x; };
  s.si_unit[0] = s.si_unit[1] = "1";
  s.bench_display = {[](double x, int) { return x / kPpm; }, {"ppm", "ppm"}};
  s.drive_display = {[](double x, int) { return x * 1e6; }, {"ppm", "ppm"}};
  s.json_value[0] = "gyro";
  s.json_value[1] = "accel";
  s.bench_candidate = false;  // the bench refits M: it would be M_ii again
  s.drive_installation = true;  // a shift since the calibration: the factory saw the unit without it
  s.folds_into_scale = true;
  s.condition = "rate";
  s.shows_on = -1;
  s.drive = DriveDiagnosis::fixed_scale;
  s.drive_prior[0] = s.drive_prior[1] = 1e-2;  // the data sheet's initial scale tolerance, ±1 %
  s.own_input = true;
  s.compensation = DriveCompensation::output;
  s.bench_sentence = "{who} scale differs from the given coefficients: scale factor, ";
  s.drive_what =
      "scale factor differs from the given coefficients (changed since the calibration, or a scale that depends "
      "on the input range — nonlinearity, asymmetry — set there at other rates; folded into M)";
  s.lookalike = -1;
  row(s);

  // ---- scale_k2: the even term of the scale-factor polynomial (IEEE Std 952/1431/1293).
  s = scale_polynomial_row(EffectId::scale_k2, "scale_k2", [](double p, double x, double, const EffectContext&) { return p * x * x; });
  s.physics =
      "scale factor grows with the square of the input, the same for both signs: the even K2 term of the "
      "scale-factor polynomial (gyros IEEE 952/1431, accelerometers IEEE 1293)";
  s.model = "K2,i·x_i²";
  s.si_unit[0] = "1/(rad/s)";
  s.si_unit[1] = "1/(m/s^2)";
  s.bench_display = {[](double x, int k) { return k == 0 ? x * kDeg / kPpm : x * kG0 / kPpm; }, {"ppm/(°/s)", "ppm/g"}};
  s.drive_display = {[](double x, int k) { return k == 0 ? x * (1e6 * kDeg) : x * (1e6 * kG0); }, {"ppm/(°/s)", "ppm/g"}};
  s.json_value[0] = "gyro_per_rad_s";
  s.json_value[1] = "accel_per_m_s2";
  // With one rate magnitude (thermal_short.toml: ±300 °/s) ω² and |ω| are the same column.
  s.excited_by = "inputs of two or more magnitudes of both signs";
  s.bench_sentence = "{who} scale error grows with the square of the input, the same for both signs: even scale-factor term K2, ";
  s.drive_what = "even scale-factor term K2·x²";
  s.lookalike = static_cast<int>(EffectId::scale_asymmetry);
  s.separation =
      "both are even in the input; only inputs of several magnitudes (rates 75, 150, 300 °/s in diagnose.toml; "
      "forces of 0.7 and 1 g in tilted positions) tell x² from |x|";
  row(s);

  // ---- scale_k3: the cubic term of the scale-factor polynomial.
  s = scale_polynomial_row(EffectId::scale_k3, "scale_k3", [](double p, double x, double, const EffectContext&) { return p * x * x * x; });
  s.physics =
      "scale factor grows with the square of the input, opposite for the two signs (odd): the cubic K3 term of "
      "the scale-factor polynomial (IEEE 952/1431/1293)";
  s.model = "K3,i·x_i³";
  s.si_unit[0] = "1/(rad/s)^2";
  s.si_unit[1] = "1/(m/s^2)^2";
  s.bench_display = {[](double x, int k) { return k == 0 ? x * kDeg * kDeg / kPpm : x * kG0 * kG0 / kPpm; },
                     {"ppm/(°/s)²", "ppm/g²"}};
  s.drive_display = {[](double x, int k) { return k == 0 ? x * (1e6 * kDeg * kDeg) : x * (1e6 * kG0 * kG0); },
                     {"ppm/(°/s)²", "ppm/g²"}};
  s.json_value[0] = "gyro_per_rad_s_2";
  s.json_value[1] = "accel_per_m_s2_2";
  // x³ and x·|x| are both odd: with two input magnitudes (after the scale factor) they are the same column.
  s.excited_by = "inputs of three or more magnitudes of both signs (factory.toml's 20, 75, 150, 300 °/s; forces of 0.7 and 1 g)";
  s.bench_sentence = "{who} scale error grows with the square of the input, opposite for the two signs: cubic scale-factor term K3, ";
  s.drive_what = "cubic scale-factor term K3·x³";
  s.lookalike = static_cast<int>(EffectId::scale_nonlinearity);
  s.separation =
      "both are odd in the input and correlate 0.994 after the scale factor over ±20…300 °/s (0.986 with 450 °/s): "
      "only a large K3 against the noise tells x³ from x·|x|";
  row(s);

  // ---- cross_coupling: products of the axis's input with the other axes' inputs.
  s = EffectSpec{};
  s.id = EffectId::cross_coupling;
  s.key = "cross_coupling";
  s.physics =
      "output of axis i grows with the product of its input and another axis's input: the cross-coupling "
      "coefficients K_ip·a_i·a_p, K_io·a_i·a_o of IEEE 1293 (accelerometers) and their gyro counterparts";
  s.model = "K_ij·x_i·x_j, j the two other axes";
  s.shape = EffectShape::axis_rows;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 2;
  s.components_other_axes = true;
  s.sensor_output = [](const EffectTerms& e, const EffectContext& c, Vec3& dg, Vec3& da) {
    const EffectSpec& x = effect_spec(EffectId::cross_coupling);
    for (int k = 0; k < 2; ++k) {
      const Vec3& in = k == 0 ? c.w : c.f;
      Vec3& out = k == 0 ? dg : da;
      for (int i = 0; i < 3; ++i)
        for (int p = 0; p < 2; ++p)
          if (const double v = effect_value(x, e, k, i, p); v != 0) out(i) += v * in(i) * in((i + 1 + p) % 3);
    }
  };
  s.si_unit[0] = "1/(rad/s)";
  s.si_unit[1] = "1/(m/s^2)";
  s.bench_display = {[](double x, int k) { return k == 0 ? x * kDeg / kPpm : x * kG0 / kPpm; }, {"ppm/(°/s)", "ppm/g"}};
  s.drive_display = {[](double x, int k) { return k == 0 ? x * (1e6 * kDeg) : x * (1e6 * kG0); }, {"ppm/(°/s)", "ppm/g"}};
  s.json_value[0] = "gyro_per_rad_s";
  s.json_value[1] = "accel_per_m_s2";
  s.inject_keys = "with";
  s.bench_candidate = true;
  s.excited_by = "accelerometers: positions with two specific-force components at once (tilts); gyros: rotation about a direction between two IMU axes, with rotations about each axis alone to separate K2 and the cross-axis terms (bench/plans/wedge.toml, a 45° wedge fixture)";
  s.condition = "rate";
  s.shows_on = -1;
  // A car's inputs rarely have two large components at once, and f_x·f_z ≈ g·f_x is a scale error.
  s.drive = DriveDiagnosis::alternative_only;
  s.drive_prior[0] = s.drive_prior[1] = 1e-2;
  s.compensation = DriveCompensation::output;
  s.bench_sentence = "{who} error grows with the product of its input and another axis's input: cross-coupling, ";
  s.drive_what = "cross-coupling";
  s.lookalike = -1;
  row(s);

  // ---- cross_axis_rate: a gyro responds to the square of the rate about another axis.
  s = EffectSpec{};
  s.id = EffectId::cross_axis_rate;
  s.key = "cross_axis_rate";
  s.physics =
      "gyro output grows with the square of the rate about another axis, the same for both signs (centrifugal "
      "load on the proof mass): cross-axis rate sensitivity beyond the linear skew in M";
  s.model = "C_ij·ω_j², j the two other axes";
  s.shape = EffectShape::axis_rows;
  s.sensor = -1;
  s.sensors = kGyro;
  s.nparams = 2;
  s.components_other_axes = true;
  s.sensor_output = [](const EffectTerms& e, const EffectContext& c, Vec3& dg, Vec3&) {
    const EffectSpec& x = effect_spec(EffectId::cross_axis_rate);
    for (int i = 0; i < 3; ++i)
      for (int p = 0; p < 2; ++p)
        if (const double v = effect_value(x, e, 0, i, p); v != 0) dg(i) += v * c.w((i + 1 + p) % 3) * c.w((i + 1 + p) % 3);
  };
  s.si_unit[0] = s.si_unit[1] = "1/(rad/s)";
  s.bench_display = {[](double x, int) { return x * kDeg / kPpm; }, {"ppm/(°/s)", "ppm/(°/s)"}};
  s.drive_display = {[](double x, int) { return x * (1e6 * kDeg); }, {"ppm/(°/s)", "ppm/(°/s)"}};
  s.json_value[0] = "gyro_per_rad_s";
  s.inject_keys = "with";
  s.bench_candidate = true;
  s.excited_by = "rate steps about each of the other IMU axes (mounts x, y and z)";
  s.condition = "rate";
  s.shows_on = -1;
  s.drive = DriveDiagnosis::never;  // a car's roll and pitch rates are small
  s.drive_prior[0] = s.drive_prior[1] = 1e-2;
  s.compensation = DriveCompensation::output;
  s.bench_sentence = "{who} error grows with the square of the rate about another axis: cross-axis rate sensitivity, ";
  s.drive_what = "cross-axis rate sensitivity";
  s.lookalike = -1;
  row(s);

  // ---- time_offset
  s = EffectSpec{};
  s.id = EffectId::time_offset;
  s.key = "time_offset";
  s.physics =
      "IMU timestamps late by τ: sample stamped t saw the truth at t − τ";
  s.model = "−τ·ẋ (reference derivative)";
  s.shape = EffectShape::vector;
  s.sensor = 2;
  s.nparams = 1;
  // The true input differs from the reference by −τ·ẋ; the output by ≈ that.
  s.reference_output = [](const EffectTerms& e, const EffectContext& c, Vec3& dg, Vec3& da) {
    const double tau = effect_vector<1>(e, EffectId::time_offset)(0);
    if (tau == 0) return;
    dg -= tau * c.dw;
    da -= tau * c.df;
  };
  // The simulators: the sample stamped t saw the motion at t − τ (exact).
  s.truth_time = [](const EffectTerms& e, double t) { return t - effect_vector<1>(e, EffectId::time_offset)(0); };
  s.drive_installation = true;  // the stamping of the drive's logger, not the unit
  s.si_unit[0] = s.si_unit[1] = "s";
  s.bench_display = {[](double x, int) { return x * 1e3; }, {"ms", "ms"}};
  s.drive_display = {[](double x, int) { return x * 1e3; }, {"ms", "ms"}};
  s.json_value[0] = s.json_value[1] = "s";
  s.inject_keys = "value";
  s.bench_candidate = true;
  s.excited_by = "rate changes, or gravity turning through the IMU (rate steps about a horizontal inner axis)";
  s.condition = "angle";
  s.shows_on = -1;
  s.drive = DriveDiagnosis::always;
  s.drive_prior[0] = s.drive_prior[1] = 0.05;
  s.own_input = true;
  s.compensation = DriveCompensation::time_stamp;
  s.bench_sentence = "IMU and reference are offset in time (errors follow the rate of change of the input): time offset, ";
  s.drive_what = "time offset between IMU and reference (IMU late by τ)";
  s.drive_head = "all axes follow the derivative of their input";
  s.lookalike = -1;
  row(s);

  // ---- lever_arm
  s = EffectSpec{};
  s.id = EffectId::lever_arm;
  s.key = "lever_arm";
  s.physics =
      "IMU origin at r from the rotation centre: centripetal and tangential acceleration, the same offset for "
      "the three axes (each axis's own offset: size_effect)";
  s.model = "accel: ω×(ω×r) + ω̇×r";
  s.shape = EffectShape::vector;
  s.sensor = 1;
  s.nparams = 3;
  s.sensor_output = [](const EffectTerms& e, const EffectContext& c, Vec3&, Vec3& da) {
    da += lever_arm_force(effect_vector<3>(e, EffectId::lever_arm), c.w, c.dw);
  };
  s.needs_rate_derivative = true;
  s.drive_installation = true;  // where the unit sits in the vehicle, not a property of the unit
  s.si_unit[0] = s.si_unit[1] = "m";
  s.bench_display = {[](double x, int) { return x * 1e3; }, {"mm", "mm"}};
  s.drive_display = {[](double x, int) { return x * 1e3; }, {"mm (IMU axes)", "mm (IMU axes)"}};
  s.json_value[0] = s.json_value[1] = "m";
  s.inject_keys = "x,y,z";
  s.bench_candidate = true;
  s.excited_by = "rate steps (centripetal) and their accelerations";
  s.condition = "rate";
  s.dominant_component = true;
  s.shows_on = 1;
  s.drive = DriveDiagnosis::always;
  s.drive_prior[0] = s.drive_prior[1] = 0.3;
  s.compensation = DriveCompensation::output;
  s.bench_sentence = "accelerometer error grows with the square of the table rate: IMU off the rotation centre (lever arm), ";
  s.drive_what = "lever arm: the MEMS sits elsewhere than meta.json says";
  s.drive_head = "accelerometer error grows with rotation rate and angular acceleration";
  s.lookalike = -1;
  row(s);

  // ---- size_effect: each accelerometer's proof mass sits off the IMU origin along its own axis.
  s = EffectSpec{};
  s.id = EffectId::size_effect;
  s.key = "size_effect";
  s.physics =
      "the three accelerometers' proof masses sit apart: accelerometer i sits r_i along its own axis from the "
      "IMU origin and senses the centripetal acceleration there (size effect: sensitivity to the square of the "
      "rate about the other axes). An offset shared by the three is the lever arm";
  s.model = "accel i: −r_i·(ω_j² + ω_k²) = e_i·(ω×(ω×r_i e_i))";
  s.shape = EffectShape::triad_axis;
  s.sensor = -1;
  s.sensors = 2;  // accel
  s.nparams = 1;
  s.axis_output = nullptr;
  s.sensor_output = [](const EffectTerms& e, const EffectContext& c, Vec3&, Vec3& da) {
    const Eigen::Map<const Vec3> r = effect_triad(e, EffectId::size_effect, 1);
    const double w2 = c.w.squaredNorm();
    for (int i = 0; i < 3; ++i)
      if (r(i) != 0) da(i) -= r(i) * (w2 - c.w(i) * c.w(i));
  };
  s.si_unit[0] = s.si_unit[1] = "m";
  s.bench_display = {[](double x, int) { return x * 1e3; }, {"mm", "mm"}};
  s.drive_display = {[](double x, int) { return x * 1e3; }, {"mm", "mm"}};
  s.json_value[0] = s.json_value[1] = "accel_m";
  s.bench_candidate = true;
  // Without angular acceleration in the data (the bench's blocks lie inside constant-rate steps) and
  // without rates about two axes at once, an accelerometer's own offset is a lever arm along that
  // axis. The lever arm is the common case (a unit off the table's centre by centimetres; a MEMS
  // die's proof masses sit < 1 mm apart), so a size effect must explain the recording better than
  // the lever arm by Δχ² 30 (prior odds e^15).
  s.prior_penalty = 30;
  s.excited_by = "rate steps about each of the other IMU axes (mounts x, y and z)";
  s.condition = "rate";
  s.shows_on = -1;
  s.drive = DriveDiagnosis::alternative_only;  // a car turns too slowly for millimetre offsets; a lever arm's shape
  s.drive_prior[0] = s.drive_prior[1] = 0.05;
  s.own_input = false;
  s.compensation = DriveCompensation::output;
  s.bench_sentence = "{who} error grows with the square of the rate about the other axes, unlike the other accelerometers: size effect, ";
  s.drive_what = "size effect";
  s.lookalike = static_cast<int>(EffectId::lever_arm);
  s.separation =
      "within constant-rate steps about single IMU axes an accelerometer's own offset along its axis is a lever "
      "arm along that axis; rates about the face diagonals tell them apart (bench/plans/wedge.toml: there a lever "
      "arm along y reaches accelerometer x as ω_x·ω_y·r_y, a size effect of y does not), and so would angular "
      "acceleration (ω̇×r reaches the other accelerometers for a lever arm, not for a size effect)";
  row(s);

  // ---- proof_mass_offset: each accelerometer's effective proof mass off the IMU origin across its
  // axis (a pendulous sensor's arm). Together with size_effect (along the axis) it is a lever arm per
  // accelerometer; the part across the axis is the angular-acceleration sensitivity of IEEE 1293.
  s = EffectSpec{};
  s.id = EffectId::proof_mass_offset;
  s.key = "proof_mass_offset";
  s.physics =
      "accelerometer i's effective proof mass sits r_i off the IMU origin across its own axis (a pendulous "
      "sensor's arm): it senses the tangential acceleration ω̇×r_i (angular-acceleration sensitivity, IEEE "
      "1293) and, on rates about two axes at once, the centripetal ω_i·(ω·r_i). An offset shared by the three "
      "is the lever arm";
  s.model = "accel i: e_i·(ω̇×r_i + ω×(ω×r_i)), r_i across e_i (components along the other two axes)";
  s.shape = EffectShape::axis_rows;
  s.sensor = -1;
  s.sensors = 2;  // accel
  s.nparams = 2;
  s.components_other_axes = true;
  s.sensor_output = [](const EffectTerms& e, const EffectContext& c, Vec3&, Vec3& da) {
    const EffectSpec& x = effect_spec(EffectId::proof_mass_offset);
    for (int i = 0; i < 3; ++i) {
      Vec3 r = Vec3::Zero();
      for (int p = 0; p < 2; ++p) r((i + 1 + p) % 3) = effect_value(x, e, 1, i, p);
      if (!r.isZero()) da(i) += lever_arm_force(r, c.w, c.dw)(i);
    }
  };
  s.needs_rate_derivative = true;
  s.si_unit[0] = s.si_unit[1] = "m";
  s.bench_display = {[](double x, int) { return x * 1e3; }, {"mm", "mm"}};
  s.drive_display = {[](double x, int) { return x * 1e3; }, {"mm", "mm"}};
  s.json_value[1] = "accel_m";
  s.inject_keys = "with";
  s.bench_candidate = true;
  // Within constant-rate steps about one IMU axis ω_i·(ω·r_i) is zero for r_i across e_i: only
  // rates about a face diagonal (or the angular acceleration of the transitions, which the bench's
  // blocks leave out) reach it.
  s.excited_by =
      "rates about two IMU axes at once (bench/plans/wedge.toml: ω_i·ω_j·r_ij), or angular acceleration about "
      "the third axis (ω̇×r_i; the bench diagnosis uses constant-rate steps only)";
  s.condition = "rate";
  s.shows_on = -1;
  // A car's ω̇ and ω² reach millimetre offsets far below the noise; a lever arm's shape.
  s.drive = DriveDiagnosis::alternative_only;
  s.drive_prior[0] = s.drive_prior[1] = 0.05;
  s.own_input = false;
  s.compensation = DriveCompensation::output;
  s.bench_sentence =
      "{who} error grows with the product of rates about two axes, unlike the other accelerometers: its proof "
      "mass sits off the IMU origin across its axis (angular-acceleration sensitivity), ";
  s.drive_what = "proof-mass offset";
  s.lookalike = -1;
  row(s);

  // ---- misalignment
  s = EffectSpec{};
  s.id = EffectId::misalignment;
  s.key = "misalignment";
  s.physics =
      "table base not level: tilt ψ = (about north, about east)";
  s.model = "Δf = −C_bLᵀ(ψ × C_bL f), Δω = −C_bLᵀ(ψ × ω_ie) (below)";
  s.shape = EffectShape::vector;
  s.sensor = 2;
  s.nparams = 2;
  // The tilted base turns the level frame seen by the IMU: gravity and the Earth rate, both fixed
  // in the level frame, reach the IMU through C_bLᵀ(I − [ψ×]) (the table's own rate is
  // unaffected). Static and rotating steps alike; C_bL from the reference (bench_attitude).
  s.reference_output = [](const EffectTerms& e, const EffectContext& c, Vec3& dg, Vec3& da) {
    const Eigen::Vector2d psi = effect_vector<2>(e, EffectId::misalignment);
    if (psi.isZero(0)) return;
    Mat3 C;
    if (!bench_attitude(c.w, c.f, C)) return;
    da += table_tilt_force(psi, C, c.f);
    // Earth-rate part (≤ Ω·|ψ|, 2e-8 rad/s at 60″): its vertical component is known from the
    // reference only when the table is still or spins about a horizontal axis.
    const Vec3 wl = C * c.w;
    if (c.w.norm() <= 1e-3 || std::abs(C.row(2).dot(c.w.normalized())) < 1e-6)
      dg += table_tilt_force(psi, C, C.transpose() * Vec3(wl(0), 0.0, wl(2)));
  };
  // The simulator (exact): gravity and the Earth rate, fixed in the level frame, reach the IMU
  // through C_bLᵀ(I − [ψ×]); the table's own rate (relative to its base) is unchanged in IMU axes.
  s.truth_level_frame = [](const EffectTerms& e, const Mat3& C_b_l, const Vec3& f_b, const Vec3& w_ie_b, Vec3& f, Vec3& w) {
    const Eigen::Vector2d psi = effect_vector<2>(e, EffectId::misalignment);
    if (psi.isZero(0)) return;
    f += table_tilt_force(psi, C_b_l, f_b);
    w += table_tilt_force(psi, C_b_l, w_ie_b);
  };
  s.si_unit[0] = s.si_unit[1] = "rad";
  s.bench_display = {[](double x, int) { return x / kDeg * 3600; }, {"arcsec", "arcsec"}};
  s.drive_display = {identity, {"rad", "rad"}};
  s.json_value[0] = s.json_value[1] = "table_tilt_rad";
  s.inject_keys = "north,east";
  s.bench_candidate = true;
  s.excited_by = "static positions over several table angles";
  s.condition = "f";
  s.shows_on = 1;
  s.drive = DriveDiagnosis::never;
  s.drive_prior[0] = s.drive_prior[1] = 1;
  s.compensation = DriveCompensation::ignored;
  s.drive_ignored_reason = "a rate-table term (bench only)";
  s.drive_sim_refusal =
      "table terms belong to the bench; on a drive the mounting is drawn by --truth random "
      "(misalignment_sigma_deg) and estimated by fit drive";
  s.bench_sentence =
      "accelerometer error depends on the table orientation beyond any sensor model: table base tilted (misalignment), ";
  s.lookalike = -1;
  row(s);

  // ---- table_wobble
  s = EffectSpec{};
  s.id = EffectId::table_wobble;
  s.key = "table_wobble";
  s.physics =
      "inner-axis encoder / wobble error periodic in the table angle: δ(θ) = a·sin θ + c·cos θ";
  s.model = "gyro: δ'(θ)·ω_table; accel: δ(θ)·∂f/∂θ (rotating steps); static steps: Δf = δ(θ)·(f × u), Δω = δ(θ)·(ω × u), u the inner axis derived from the recording (below)";
  s.shape = EffectShape::vector;
  s.sensor = 2;
  s.nparams = 2;
  s.reference_output = [](const EffectTerms& e, const EffectContext& c, Vec3& dg, Vec3& da) {
    const Eigen::Vector2d ac = effect_vector<2>(e, EffectId::table_wobble);
    if (ac.isZero(0) || !std::isfinite(c.angle)) return;
    if (std::abs(c.angle_rate) > 0.0174533) {
      // True angle θ + δ(θ): rate scaled by 1 + δ'(θ), attitude advanced by δ about the rate axis
      // (the Earth rate is negligible beside the table rate).
      dg += wobble_slope(ac, c.angle) * c.w;
      da += wobble_angle(ac, c.angle) * c.df / c.angle_rate;
    } else if (!c.inner_axis.isZero(0)) {
      // Static position: the table stands at θ + δ(θ). Everything fixed in the level frame —
      // gravity and the Earth rate — turns in IMU axes by −δ about the axis u of the angle column
      // (the same f × u = ∂f/∂θ as in a rotating step): Δf = δ·(f × u), Δω = δ·(ω × u).
      const double d = wobble_angle(ac, c.angle);
      dg += d * c.w.cross(c.inner_axis);
      da += d * c.f.cross(c.inner_axis);
    }
  };
  // The simulator (exact): the inner axis stands at θ + δ(θ) and turns at θ̇·(1 + δ'(θ)).
  s.truth_table_angle = [](const EffectTerms& e, double& angle, double& rate) {
    const Eigen::Vector2d ac = effect_vector<2>(e, EffectId::table_wobble);
    if (ac.isZero(0)) return;
    const double th = angle;
    angle += wobble_angle(ac, th);
    rate *= 1.0 + wobble_slope(ac, th);
  };
  s.si_unit[0] = s.si_unit[1] = "rad";
  s.bench_display = {[](double x, int) { return x / kDeg * 3600; }, {"arcsec", "arcsec"}};
  s.drive_display = {identity, {"rad", "rad"}};
  s.json_value[0] = s.json_value[1] = "encoder_rad";
  s.inject_keys = "sin,cos";
  s.bench_candidate = true;
  s.excited_by = "rate steps (a full revolution of the inner axis)";
  s.condition = "angle";
  s.shows_on = -1;
  s.drive = DriveDiagnosis::never;
  s.drive_prior[0] = s.drive_prior[1] = 1;
  s.compensation = DriveCompensation::ignored;
  s.drive_ignored_reason = "a rate-table term (bench only)";
  s.drive_sim_refusal =
      "table terms belong to the bench; on a drive the mounting is drawn by --truth random "
      "(misalignment_sigma_deg) and estimated by fit drive";
  s.bench_sentence = "error periodic in the table angle (once per revolution): table wobble / encoder error, ";
  s.lookalike = -1;
  row(s);

  // ---- correlated_drift
  s = EffectSpec{};
  s.id = EffectId::correlated_drift;
  s.key = "correlated_drift";
  s.physics =
      "bias drift larger / slower than the data-sheet prior: points to `calbench identify`";
  s.model = "first-order Gauss–Markov σ, τ (noise model)";
  s.shape = EffectShape::noise;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 0;
  s.si_unit[0] = "rad/s";
  s.si_unit[1] = "m/s^2";
  s.bench_display = {[](double x, int k) { return k == 0 ? x / kDegPerHour : x / kMilliG; }, {"°/h", "mg"}};
  s.drive_display = {[](double x, int k) { return k == 0 ? x / kDegPerHour : x / kMilliG; }, {"°/h", "mg"}};
  s.json_value[0] = "gyro_sigma_rad_s";
  s.json_value[1] = "accel_sigma_m_s2";
  s.inject_keys = "sigma,tau";
  s.bench_candidate = false;
  s.condition = "time";
  s.shows_on = -1;
  s.drive = DriveDiagnosis::never;  // found by the noise model, not as a linear term
  s.drive_prior[0] = s.drive_prior[1] = 1;
  s.compensation = DriveCompensation::noise_model;
  s.bench_sentence = "{who} residual wanders slowly beyond the data-sheet drift: correlated drift, ";
  s.drive_what = "bias drift larger than the data sheet's (run calbench identify)";
  s.drive_head = "{who} residual wanders slowly in time";
  // A slow bias change on a warm-up: a temperature term or a drift (DiagFinding::versus_drift).
  s.lookalike = static_cast<int>(EffectId::temperature_bias);
  s.separation =
      "a slow bias change while the unit warms up is either a temperature term or a drift; a plan that holds "
      "the temperature at several levels, or heats and cools over the same range (bench/plans/thermal.toml), "
      "tells them apart (record length and span needed: docs/diagnosis.md)";

  row(s);

  return v;
}


}  // namespace calbench
