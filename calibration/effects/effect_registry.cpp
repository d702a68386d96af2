#include "calibration/effects/effect_registry.hpp"

#include <cmath>
#include <stdexcept>

#include "calibration/units.hpp"

namespace calbench {

namespace {

using namespace units;

constexpr unsigned kBoth = 3, kGyro = 1;

TriadEffectTerms& triad(EffectTerms& e, int sensor) { return sensor == 0 ? e.gyro : e.accel; }

// Storage of the per-axis triad terms: the member of TriadEffectTerms.
template <Vec3 TriadEffectTerms::*M>
double* triad_param(EffectTerms& e, int sensor, int axis, int p) {
  if (sensor < 0 || sensor > 1 || axis < 0 || axis > 2 || p != 0) return nullptr;
  return &(triad(e, sensor).*M)(axis);
}

double identity(double v, int) { return v; }

// The rows: catalogue order, which is the order of the candidate terms (per sensor and axis the
// triad_axis rows, then the others) and of every list of effects the programme prints.
std::vector<EffectSpec> make_specs() {
  std::vector<EffectSpec> v;
  EffectSpec s{};
  auto row = [&](EffectSpec x) { v.push_back(x); };

  // ---- temperature_bias
  s = EffectSpec{};
  s.id = EffectId::temperature_bias;
  s.key = "temperature_bias";
  s.physics = "bias b_T,i·(T − T0)";
  s.shape = EffectShape::triad_axis;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 1;
  s.param = triad_param<&TriadEffectTerms::temp_bias>;
  s.axis_output = [](double p, double, double dT, const EffectContext&) { return p * dT; };
  s.si_unit[0] = "rad/s/K";
  s.si_unit[1] = "m/s^2/K";
  s.bench_display = {[](double x, int k) { return k == 0 ? x / kDegPerHour : x / kMilliG; }, {"°/h/K", "mg/K"}};
  s.drive_display = {[](double x, int k) { return k == 0 ? x * (1.0 / kDegPerHour) : x * (1.0 / kMilliG); }, {"°/h/K", "mg/K"}};
  s.json_value[0] = "gyro_rad_s_per_K";
  s.json_value[1] = "accel_m_s2_per_K";
  s.json_t0 = true;
  s.bench_candidate = true;
  s.condition = "temperature";
  s.shows_on = -1;
  s.drive = DriveDiagnosis::with_temperature;
  s.drive_prior[0] = 1e-4;
  s.drive_prior[1] = 1e-2;
  s.compensation = DriveCompensation::with_temperature;
  s.drive_ignored_reason = "imu.csv has no temperature column";
  s.bench_sentence = "{who} error grows with temperature: temperature-dependent bias, ";
  s.drive_what = "temperature-dependent bias";
  s.lookalike = -1;
  row(s);

  // ---- temperature_scale
  s = EffectSpec{};
  s.id = EffectId::temperature_scale;
  s.key = "temperature_scale";
  s.physics = "scale s_T,i·(T − T0)·x_i";
  s.shape = EffectShape::triad_axis;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 1;
  s.param = triad_param<&TriadEffectTerms::temp_scale>;
  s.axis_output = [](double p, double x, double dT, const EffectContext&) { return p * dT * x; };
  s.si_unit[0] = s.si_unit[1] = "1/K";
  s.bench_display = {[](double x, int) { return x / kPpm; }, {"ppm/K", "ppm/K"}};
  s.drive_display = {[](double x, int) { return x * 1e6; }, {"ppm/K", "ppm/K"}};
  s.json_value[0] = "gyro_per_K";
  s.json_value[1] = "accel_per_K";
  s.json_t0 = true;
  s.bench_candidate = true;
  s.condition = "temperature";
  s.shows_on = -1;
  s.drive = DriveDiagnosis::with_temperature;
  s.drive_prior[0] = s.drive_prior[1] = 1e-3;
  s.own_input = true;
  s.compensation = DriveCompensation::with_temperature;
  s.drive_ignored_reason = "imu.csv has no temperature column";
  s.bench_sentence = "{who} scale factor changes with temperature: temperature-dependent scale factor, ";
  s.drive_what = "temperature-dependent scale factor";
  s.lookalike = -1;
  row(s);

  // ---- temperature_rate
  s = EffectSpec{};
  s.id = EffectId::temperature_rate;
  s.key = "temperature_rate";
  s.physics = "thermal lag: bias r_T,i·dT/dt (gradient-driven during warm-up and ramps)";
  s.shape = EffectShape::triad_axis;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 1;
  s.param = triad_param<&TriadEffectTerms::temp_rate>;
  s.axis_output = [](double p, double, double, const EffectContext& c) { return p * c.dtemp_k_s; };
  s.si_unit[0] = "rad/s/(K/s)";
  s.si_unit[1] = "m/s^2/(K/s)";
  s.bench_display = {[](double x, int k) { return k == 0 ? x / kDegPerHour / 60.0 : x / kMilliG / 60.0; },
                     {"°/h per K/min", "mg per K/min"}};
  s.drive_display = {identity, {"rad/s/(K/s)", "m/s^2/(K/s)"}};
  s.json_value[0] = "gyro_rad_s_per_K_per_s";
  s.json_value[1] = "accel_m_s2_per_K_per_s";
  s.bench_candidate = true;
  s.condition = "dT/dt";
  s.shows_on = -1;
  // Not on drives: no dT/dt is derived from a drive (simulated drives have no temperature).
  s.drive = DriveDiagnosis::never;
  s.drive_prior[0] = s.drive_prior[1] = 1;
  s.compensation = DriveCompensation::ignored;
  s.drive_ignored_reason = "needs dT/dt, which the drive estimator does not derive";
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
  s.physics = "gyro output G·f (3×3, output axis × force axis)";
  s.shape = EffectShape::gyro_matrix;
  s.sensor = 0;
  s.sensors = kGyro;
  s.nparams = 3;
  s.param = [](EffectTerms& e, int sensor, int axis, int p) -> double* {
    return sensor == 0 && axis >= 0 && axis < 3 && p >= 0 && p < 3 ? &e.g_sensitivity(axis, p) : nullptr;
  };
  s.sensor_output = [](const EffectTerms& e, const EffectContext& c, Vec3& dg, Vec3&) { dg += e.g_sensitivity * c.f; };
  s.si_unit[0] = s.si_unit[1] = "rad/s/(m/s^2)";
  s.bench_display = {[](double x, int) { return x * kG0 / kDeg; }, {"°/s/g", "°/s/g"}};
  s.drive_display = {[](double x, int) { return x * (1.0 / kDeg * kG0); }, {"°/s/g", "°/s/g"}};
  s.json_value[0] = s.json_value[1] = "gyro_rad_s_per_m_s2";
  s.bench_candidate = true;
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

  // ---- scale_nonlinearity
  s = EffectSpec{};
  s.id = EffectId::scale_nonlinearity;
  s.key = "scale_nonlinearity";
  s.physics = "quadratic scale error k_i·x_i·|x_i|";
  s.shape = EffectShape::triad_axis;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 1;
  s.param = triad_param<&TriadEffectTerms::nonlinearity>;
  s.axis_output = [](double p, double x, double, const EffectContext&) { return p * x * std::abs(x); };
  s.si_unit[0] = "1/(rad/s)";
  s.si_unit[1] = "1/(m/s^2)";
  s.bench_display = {[](double x, int k) { return k == 0 ? x * kDeg / kPpm : x * kG0 / kPpm; }, {"ppm/(°/s)", "ppm/g"}};
  s.drive_display = {[](double x, int k) { return k == 0 ? x * (1e6 * kDeg) : x * (1e6 * kG0); }, {"ppm/(°/s)", "ppm/g"}};
  s.json_value[0] = "gyro_per_rad_s";
  s.json_value[1] = "accel_per_m_s2";
  s.bench_candidate = true;
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
  s.physics = "a_i·|x_i|: scale M_ii + a_i for x_i > 0, M_ii − a_i for x_i < 0";
  s.shape = EffectShape::triad_axis;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 1;
  s.param = triad_param<&TriadEffectTerms::asymmetry>;
  s.axis_output = [](double p, double x, double, const EffectContext&) { return p * std::abs(x); };
  s.si_unit[0] = s.si_unit[1] = "1";
  s.bench_display = {[](double x, int) { return x / kPpm; }, {"ppm", "ppm"}};
  s.drive_display = {[](double x, int) { return x * 1e6; }, {"ppm", "ppm"}};
  s.json_value[0] = "gyro";
  s.json_value[1] = "accel";
  s.bench_candidate = true;
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
  s.physics = "s_i·x_i: the scale differs from the coefficients' M_ii (drives with given coefficients)";
  s.shape = EffectShape::triad_axis;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 1;
  s.param = triad_param<&TriadEffectTerms::scale>;
  s.axis_output = [](double p, double x, double, const EffectContext&) { return p * x; };
  s.si_unit[0] = s.si_unit[1] = "1";
  s.bench_display = {[](double x, int) { return x / kPpm; }, {"ppm", "ppm"}};
  s.drive_display = {[](double x, int) { return x * 1e6; }, {"ppm", "ppm"}};
  s.json_value[0] = "gyro";
  s.json_value[1] = "accel";
  s.bench_candidate = false;  // the bench refits M: it would be M_ii again
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

  // ---- time_offset
  s = EffectSpec{};
  s.id = EffectId::time_offset;
  s.key = "time_offset";
  s.physics = "IMU sample stamped t saw the truth at t − τ: Δx ≈ −τ·ẋ";
  s.shape = EffectShape::vector;
  s.sensor = 2;
  s.nparams = 1;
  s.param = [](EffectTerms& e, int, int, int p) -> double* { return p == 0 ? &e.time_offset_s : nullptr; };
  s.si_unit[0] = s.si_unit[1] = "s";
  s.bench_display = {[](double x, int) { return x * 1e3; }, {"ms", "ms"}};
  s.drive_display = {[](double x, int) { return x * 1e3; }, {"ms", "ms"}};
  s.json_value[0] = s.json_value[1] = "s";
  s.inject_keys = "value";
  s.bench_candidate = true;
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
  s.physics = "accel ω×(ω×r) + ω̇×r, r in IMU axes";
  s.shape = EffectShape::vector;
  s.sensor = 1;
  s.nparams = 3;
  s.param = [](EffectTerms& e, int, int, int p) -> double* { return p >= 0 && p < 3 ? &e.lever_arm_m(p) : nullptr; };
  s.sensor_output = [](const EffectTerms& e, const EffectContext& c, Vec3&, Vec3& da) {
    da += lever_arm_force(e.lever_arm_m, c.w, c.dw);
  };
  s.si_unit[0] = s.si_unit[1] = "m";
  s.bench_display = {[](double x, int) { return x * 1e3; }, {"mm", "mm"}};
  s.drive_display = {[](double x, int) { return x * 1e3; }, {"mm (IMU axes)", "mm (IMU axes)"}};
  s.json_value[0] = s.json_value[1] = "m";
  s.inject_keys = "x,y,z";
  s.bench_candidate = true;
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

  // ---- misalignment
  s = EffectSpec{};
  s.id = EffectId::misalignment;
  s.key = "misalignment";
  s.physics = "table base tilted by ψ = (ψN, ψE, 0): Δf = −C_bLᵀ (ψ × C_bL f)";
  s.shape = EffectShape::vector;
  s.sensor = 2;
  s.nparams = 2;
  s.param = [](EffectTerms& e, int, int, int p) -> double* { return p >= 0 && p < 2 ? &e.table_tilt_rad(p) : nullptr; };
  s.si_unit[0] = s.si_unit[1] = "rad";
  s.bench_display = {[](double x, int) { return x / kDeg * 3600; }, {"arcsec", "arcsec"}};
  s.drive_display = {identity, {"rad", "rad"}};
  s.json_value[0] = s.json_value[1] = "table_tilt_rad";
  s.inject_keys = "north,east";
  s.bench_candidate = true;
  s.condition = "f";
  s.shows_on = 1;
  s.drive = DriveDiagnosis::never;
  s.drive_prior[0] = s.drive_prior[1] = 1;
  s.compensation = DriveCompensation::ignored;
  s.drive_ignored_reason = "a rate-table term (bench only)";
  s.bench_sentence =
      "accelerometer error depends on the table orientation beyond any sensor model: table base tilted (misalignment), ";
  s.lookalike = -1;
  row(s);

  // ---- table_wobble
  s = EffectSpec{};
  s.id = EffectId::table_wobble;
  s.key = "table_wobble";
  s.physics = "inner-axis angle error δ(θ) = a·sin θ + c·cos θ: true rate θ̇·(1 + δ'(θ))";
  s.shape = EffectShape::vector;
  s.sensor = 2;
  s.nparams = 2;
  s.param = [](EffectTerms& e, int, int, int p) -> double* { return p >= 0 && p < 2 ? &e.wobble_rad(p) : nullptr; };
  s.si_unit[0] = s.si_unit[1] = "rad";
  s.bench_display = {[](double x, int) { return x / kDeg * 3600; }, {"arcsec", "arcsec"}};
  s.drive_display = {identity, {"rad", "rad"}};
  s.json_value[0] = s.json_value[1] = "encoder_rad";
  s.inject_keys = "sin,cos";
  s.bench_candidate = true;
  s.condition = "angle";
  s.shows_on = -1;
  s.drive = DriveDiagnosis::never;
  s.drive_prior[0] = s.drive_prior[1] = 1;
  s.compensation = DriveCompensation::ignored;
  s.drive_ignored_reason = "a rate-table term (bench only)";
  s.bench_sentence = "error periodic in the table angle (once per revolution): table wobble / encoder error, ";
  s.lookalike = -1;
  row(s);

  // ---- correlated_drift
  s = EffectSpec{};
  s.id = EffectId::correlated_drift;
  s.key = "correlated_drift";
  s.physics = "bias drift beyond the data-sheet prior (first-order Gauss–Markov σ, τ)";
  s.shape = EffectShape::noise;
  s.sensor = -1;
  s.sensors = kBoth;
  s.nparams = 0;
  s.param = [](EffectTerms& e, int sensor, int, int p) -> double* {
    if (sensor < 0 || sensor > 1) return nullptr;
    TriadEffectTerms& t = triad(e, sensor);
    return p == 0 ? &t.drift_sigma : p == 1 ? &t.drift_tau_s : nullptr;
  };
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
  s.lookalike = -1;
  row(s);

  return v;
}

// Slots of an effect in EffectTerms::generic, by shape.
int generic_slots(const EffectSpec& s) {
  switch (s.shape) {
    case EffectShape::triad_axis: return 6;   // sensor·3 + axis
    case EffectShape::gyro_matrix: return 9;  // axis·3 + p
    case EffectShape::vector: return s.nparams;
    case EffectShape::noise: return 4;  // sensor·2 + p
  }
  return 0;
}

struct Registry {
  std::vector<EffectSpec> specs = make_specs();
  std::vector<const EffectSpec*> by_id;
  std::vector<const EffectSpec*> triad_rows, output_rows;
  Registry() {
    by_id.assign(specs.size(), nullptr);
    int next = 0;
    for (EffectSpec& s : specs)
      if (!s.param) {
        s.generic_offset = next;
        next += generic_slots(s);
      }
    if (next > static_cast<int>(std::tuple_size<decltype(EffectTerms::generic)>::value))
      throw std::logic_error("effect registry: EffectTerms::generic is too small for the new effects");
    for (const EffectSpec& s : specs) {
      by_id.at(static_cast<std::size_t>(s.id)) = &s;
      if (s.axis_output) triad_rows.push_back(&s);
      if (s.sensor_output) output_rows.push_back(&s);
    }
    for (const EffectSpec* s : by_id)
      if (!s) throw std::logic_error("effect registry: an EffectId without a spec");
  }
};

const Registry& registry() {
  static const Registry r;
  return r;
}

double cparam(const EffectSpec& s, const EffectTerms& e, int sensor, int axis, int p) {
  const double* v = effect_param(s, const_cast<EffectTerms&>(e), sensor, axis, p);
  return v ? *v : 0.0;
}

}  // namespace

double* effect_param(const EffectSpec& s, EffectTerms& e, int sensor, int axis, int p) {
  if (s.param) return s.param(e, sensor, axis, p);
  if (!effect_allows_sensor(s, sensor)) return nullptr;
  int k = -1;
  switch (s.shape) {
    case EffectShape::triad_axis: k = axis >= 0 && axis < 3 && p == 0 ? sensor * 3 + axis : -1; break;
    case EffectShape::gyro_matrix: k = axis >= 0 && axis < 3 && p >= 0 && p < 3 ? axis * 3 + p : -1; break;
    case EffectShape::vector: k = p >= 0 && p < s.nparams ? p : -1; break;
    case EffectShape::noise: k = p >= 0 && p < 2 ? sensor * 2 + p : -1; break;
  }
  return k < 0 ? nullptr : &e.generic[static_cast<std::size_t>(s.generic_offset + k)];
}

double effect_value(const EffectSpec& s, const EffectTerms& e, int sensor, int axis, int p) {
  return cparam(s, e, sensor, axis, p);
}

const std::vector<EffectSpec>& effect_specs() { return registry().specs; }
const EffectSpec& effect_spec(EffectId e) { return *registry().by_id.at(static_cast<std::size_t>(e)); }
const char* effect_name(EffectId e) { return effect_spec(e).key; }
int effect_count() { return static_cast<int>(registry().specs.size()); }

bool effect_from_name(const std::string& s, EffectId& e) {
  for (const EffectSpec& x : effect_specs())
    if (s == x.key) {
      e = x.id;
      return true;
    }
  return false;
}

bool effect_allows_sensor(const EffectSpec& s, int sensor) {
  if (s.shape == EffectShape::triad_axis || s.shape == EffectShape::noise)
    return sensor >= 0 && sensor < 2 && (s.sensors >> sensor & 1u);
  return sensor == s.sensor;
}

bool effect_present(const EffectSpec& s, const EffectTerms& e) {
  switch (s.shape) {
    case EffectShape::triad_axis:
      for (int k = 0; k < 2; ++k)
        if (effect_allows_sensor(s, k))
          for (int a = 0; a < 3; ++a)
            if (cparam(s, e, k, a, 0) != 0) return true;
      return false;
    case EffectShape::gyro_matrix:
      for (int a = 0; a < 3; ++a)
        for (int p = 0; p < 3; ++p)
          if (cparam(s, e, s.sensor, a, p) != 0) return true;
      return false;
    case EffectShape::vector:
      for (int p = 0; p < s.nparams; ++p)
        if (cparam(s, e, s.sensor, -1, p) != 0) return true;
      return false;
    case EffectShape::noise:
      for (int k = 0; k < 2; ++k)
        if (effect_allows_sensor(s, k) && cparam(s, e, k, -1, 0) > 0) return true;
      return false;
  }
  return false;
}

std::vector<std::string> effect_ids_present(const EffectTerms& e) {
  std::vector<std::string> out;
  for (const EffectSpec& s : effect_specs())
    if (effect_present(s, e)) out.push_back(s.key);
  return out;
}

int Term::nparams() const { return effect_spec(effect).nparams; }

bool Term::touches(int s, int a) const {
  const EffectSpec& x = effect_spec(effect);
  switch (x.shape) {
    case EffectShape::triad_axis:
    case EffectShape::gyro_matrix: return s == sensor && a == axis;
    case EffectShape::vector: return x.shows_on < 0 || s == x.shows_on;
    case EffectShape::noise: return false;
  }
  return false;
}

std::string Term::label() const {
  std::string l = effect_name(effect);
  l += sensor == 0 ? " gyro" : sensor == 1 ? " accel" : " reference";
  if (axis >= 0) l += std::string(" ") + "xyz"[axis];
  return l;
}

void Term::add_param(EffectTerms& e, int p, double v) const {
  if (double* x = effect_param(effect_spec(effect), e, sensor, axis, p)) *x += v;
}

double Term::get_param(const EffectTerms& e, int p) const { return cparam(effect_spec(effect), e, sensor, axis, p); }

std::vector<Term> candidate_terms() {
  std::vector<Term> out;
  for (int s = 0; s < 2; ++s)
    for (int a = 0; a < 3; ++a)
      for (const EffectSpec& x : effect_specs())
        if (x.shape == EffectShape::triad_axis && effect_allows_sensor(x, s)) out.push_back({x.id, s, a});
  for (const EffectSpec& x : effect_specs()) {
    if (x.shape == EffectShape::gyro_matrix)
      for (int a = 0; a < 3; ++a) out.push_back({x.id, x.sensor, a});
    if (x.shape == EffectShape::vector) out.push_back({x.id, x.sensor, -1});
  }
  return out;
}

std::string term_unit(const Term& t) { return effect_spec(t.effect).si_unit[t.sensor == 0 ? 0 : 1]; }

NoiseSpec noise_with_effects(NoiseSpec n, const EffectTerms& e) {
  for (const EffectSpec& s : effect_specs()) {
    if (s.compensation != DriveCompensation::noise_model) continue;
    for (int k = 0; k < 2; ++k) {
      TriadNoise& t = k == 0 ? n.gyro : n.accel;
      const double sigma = cparam(s, e, k, -1, 0), tau = cparam(s, e, k, -1, 1);
      if (sigma > 0) {
        t.drift_sigma = sigma;
        if (tau > 0) t.drift_tau_s = tau;
      }
    }
  }
  return n;
}

const char* separation_note(EffectId finding, EffectId alternative) {
  const EffectSpec& f = effect_spec(finding);
  const EffectSpec& a = effect_spec(alternative);
  if (a.lookalike == static_cast<int>(finding)) return a.separation;
  if (f.lookalike == static_cast<int>(alternative)) return f.separation;
  return nullptr;
}

// Sensor-side output of all effects: the per-axis triad terms in catalogue order, then the others.
void sensor_side_terms(const EffectTerms& e, const EffectContext& c, Vec3& dgyro, Vec3& daccel) {
  const double dT = c.temp_c - e.t0_c;
  const Registry& r = registry();
  auto triad_out = [&](int k, const Vec3& x) {
    Vec3 d = Vec3::Zero();
    for (const EffectSpec* s : r.triad_rows) {
      if (!(s->sensors >> k & 1u)) continue;
      for (int i = 0; i < 3; ++i) {
        const double p = cparam(*s, e, k, i, 0);
        if (p != 0) d(i) += s->axis_output(p, x(i), dT, c);  // a zero term adds nothing
      }
    }
    return d;
  };
  dgyro = triad_out(0, c.w);
  daccel = triad_out(1, c.f);
  for (const EffectSpec* s : r.output_rows) s->sensor_output(e, c, dgyro, daccel);
}

}  // namespace calbench
