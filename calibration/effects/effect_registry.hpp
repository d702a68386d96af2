// The effect registry of `calbench diagnose` (docs/diagnosis.md, "The catalogue"): one spec per
// effect holds everything the programme knows about it — ID and JSON key, the shape of its
// parameters, SI and display units, where its value is stored, its physics on the sensor output,
// how a drive compensates it, its prior on drives, which conditions reveal it, its sentences and
// its look-alike. The simulators, the compensation, the bench fit with effects, both diagnoses,
// the JSON codec, `--inject`, the reports and the catalogue table of the docs loop over
// effect_specs() instead of naming effects; adding an effect is one row in effect_registry.cpp.
// Pure data and mathematics: no I/O.
#pragma once
#include <string>
#include <vector>

#include "calibration/effects/effect_terms.hpp"
#include "common/noise_spec.hpp"

namespace calbench {

// The IDs keep their indices (JSON files, sweeps and tests name them); new ones are appended.
enum class EffectId {
  temperature_bias,
  temperature_scale,
  g_sensitivity,
  scale_nonlinearity,
  scale_asymmetry,
  time_offset,
  lever_arm,
  misalignment,
  table_wobble,
  correlated_drift,
  temperature_rate,  // thermal lag: bias ∝ dT/dt (appended: the IDs above keep their indices)
  scale_factor,      // scale differs from the given coefficients (drives with --coeffs only)
  scale_k2,          // even scale term K2·x² (IEEE 952/1431/1293 scale-factor polynomial)
  scale_k3,          // cubic scale term K3·x³
  cross_coupling,    // cross-coupling x_i·x_j with the other axes' inputs (accel K_ip, K_io; gyro)
  cross_axis_rate,   // gyro sensitivity to the square of the rate about another axis
  g2_sensitivity,    // gyro anisoelastic (g²) sensitivity: products of specific-force components
  size_effect,       // accelerometer size effect: each accelerometer's offset along its own axis (rate²)
  proof_mass_offset, // accelerometer offset across its axis: angular-acceleration sensitivity, ω_i·(ω·r)
};

// How an effect's parameters are laid out, which decides its candidate terms, its JSON form and
// its `--inject` keys.
enum class EffectShape {
  triad_axis,   // one parameter per sensor axis: a term per (sensor, axis) of the sensors allowed
  gyro_matrix,  // a row of 3 per gyro axis (output axis × force axis): a term per gyro axis
  axis_rows,    // a row of nparams per axis of each allowed sensor (components named by inject_keys):
                //   a term per (sensor, axis)
  vector,       // one term of nparams parameters on one sensor (or the reference)
  noise,        // no linear parameter: (σ, τ) of the noise model per triad
};

// What a drive estimator does with a term of a coefficient set (fit drive, qc).
enum class DriveCompensation {
  output,            // removed from the raw samples (sensor-side output term)
  time_stamp,        // corrects the time stamps
  with_temperature,  // removed where the samples carry a temperature
  ignored,           // not applicable to a stream (reason in drive_ignored_reason)
  noise_model,       // goes to the filter's noise model, not to the samples
};

// Whether a drive diagnosis looks for it.
enum class DriveDiagnosis {
  always,
  with_temperature,  // only when the recording has a temperature column
  fixed_scale,       // only where M is not refitted (a drive with given coefficients)
  // Not a drive candidate (a car does not excite it at a plausible size, or only in a shape another
  // term has), but weighed as an alternative to what a drive names: a finding it explains as well
  // is not established ("not told apart from …").
  alternative_only,
  never,
};

// Display unit: shown = value(v, sensor) in unit[sensor] (gyro 0, accel 1; the reference uses 0).
struct DisplayUnit {
  double (*value)(double v, int sensor);
  const char* unit[2];
};

// sensor: 0 = gyro, 1 = accel, 2 = reference (the bench); axis 0..2 or −1 = all.
struct Term {
  EffectId effect;
  int sensor = 0;
  int axis = -1;
  int nparams() const;
  bool touches(int sensor_idx, int axis_idx) const;  // sensor_idx 0 gyro / 1 accel
  std::string label() const;                         // e.g. "g_sensitivity gyro x"
  // Add value v of parameter p to the terms.
  void add_param(EffectTerms& e, int p, double v) const;
  double get_param(const EffectTerms& e, int p) const;
};

struct EffectSpec {
  EffectId id;
  const char* key;      // ID, JSON key and `--inject` name
  const char* physics;  // what happens physically (the catalogue table)
  const char* model;    // the model term (the catalogue table)
  EffectShape shape;
  int sensor;           // triad_axis/noise: −1 (the sensors of `sensors`); else the term's sensor (0, 1, 2)
  unsigned sensors;     // triad_axis/noise: bit 0 gyro, bit 1 accel
  int nparams;          // parameters of one term
  // Per-axis sensor output d_i(p, x_i) of a triad_axis effect (x: the true input of the axis).
  double (*axis_output)(double p, double x, double dT, const EffectContext& c);
  // Other sensor-side output (added after the per-axis terms), or nullptr.
  void (*sensor_output)(const EffectTerms& e, const EffectContext& c, Vec3& dgyro, Vec3& daccel);
  // Reference-side output: the bench's true input differs from its nominal reference, and the IMU
  // output by ≈ that difference (linearised; c holds the reference conditions), or nullptr.
  void (*reference_output)(const EffectTerms& e, const EffectContext& c, Vec3& dgyro, Vec3& daccel) = nullptr;
  bool needs_rate_derivative = false;  // its output uses ω̇ (EffectContext::dw): the simulators derive it
  // Truth side of the simulators, exact (not linearised), or nullptr:
  //   truth_time: the instant whose motion a sample stamped t saw (a drive's compensation re-stamps
  //     the sample with it);
  //   truth_table_angle: the bench's inner axis really stands at `angle` and turns at `rate` (in:
  //     the nominal ones);
  //   truth_level_frame: the bench's level frame as the IMU sees it: changes of the specific force
  //     and the rate (C_b_l IMU → level, f_b the nominal specific force, w_ie_b the Earth rate in
  //     IMU axes).
  double (*truth_time)(const EffectTerms& e, double t) = nullptr;
  void (*truth_table_angle)(const EffectTerms& e, double& angle, double& rate) = nullptr;
  void (*truth_level_frame)(const EffectTerms& e, const Mat3& C_b_l, const Vec3& f_b, const Vec3& w_ie_b, Vec3& df,
                            Vec3& dw) = nullptr;
  const char* si_unit[2];     // gyro, accel (the same where the sensor does not matter)
  DisplayUnit bench_display;  // the bench report's sentences
  DisplayUnit drive_display;  // the drive report's sentences (multiplied per value)
  // JSON: value key per sensor (triad_axis), or the one value key; whether the object carries the
  // reference temperature t0_c. `--inject`: the component keys of a vector ("x,y,z"), "value" for one;
  // of an axis_rows effect the names of a row's components (`--inject ...,axis=x,term=xy,value=V`).
  const char* json_value[2];
  bool json_t0;
  const char* inject_keys;
  // axis_rows: the row's components are the two other axes (next, previous: x → y, z), named by
  // their letter; `--inject ...,axis=x,with=y,value=V`.
  bool components_other_axes = false;
  // Bench diagnosis.
  bool bench_candidate;      // false: the bench refits M, so a scale_factor term would be M_ii again
  // −2 ln(prior odds) against the effect, added to its penalty in the search (both diagnoses): a
  // newer effect that the plan may not separate from an established look-alike must explain the
  // recording better by this much to be named instead of it. 0 for the established ones.
  double prior_penalty = 0;
  const char* condition;     // the reference condition that reveals it on the bench
  // Driven by the device temperature (T − T0 or dT/dt): on a warm-up a correlated drift may explain
  // the same slow change, and the diagnosis weighs the two (DiagFinding::versus_drift).
  bool temperature_driven = false;
  // What excites it (plan steps, manoeuvres): said when a recording cannot (nullptr: the condition).
  const char* excited_by = nullptr;
  bool condition_by_column;  // the condition names the dominant column (g-sensitivity: f_x, f_y, f_z)
  bool dominant_component;   // one vector in IMU axes: reported on its dominant component
  int shows_on;              // −1: its own sensor; 1: the accelerometers show it (lever arm, table tilt)
  // Drive diagnosis and compensation.
  DriveDiagnosis drive;
  double drive_prior[2];     // prior σ of the parameters (gyro term, accel term)
  bool own_input;            // its regressor is built from the sensor's own reference input
  bool curvature;            // nonlinear in the input: linearised about the smoothed input
  DriveCompensation compensation;
  const char* drive_ignored_reason;
  // Why a simulated drive cannot carry it (nullptr: it can): `simulate drive` refuses it with this.
  const char* drive_sim_refusal = nullptr;
  // A property of the drive's installation or a change since the factory calibration (time offset,
  // lever arm, scale shift): the simulated factory calibration of a drive's unit does not see it.
  bool drive_installation = false;
  // Its value is a change of the coefficient M_ii (triad_axis): a drive diagnosis's IMPROVED.json
  // carries it in M, not as a term.
  bool folds_into_scale = false;
  // Sentences: {who} = sensor and axis, {condition} = the condition phrase.
  const char* bench_sentence;
  const char* drive_what;
  const char* drive_head;    // nullptr: "{who} error grows with {condition}"
  // A look-alike the recording may not separate it from, and what separates them.
  int lookalike;             // EffectId index or −1
  const char* separation;
  int offset = -1;           // first slot of its values in EffectTerms::values (set by the registry)
};

const std::vector<EffectSpec>& effect_specs();  // in catalogue order (candidate order)
std::vector<EffectSpec> make_effect_specs();      // the rows (effect_specs.cpp); use effect_specs()
const EffectSpec& effect_spec(EffectId e);
const char* effect_name(EffectId e);
int effect_count();  // EffectId values are 0 … effect_count() − 1
bool effect_from_name(const std::string& s, EffectId& e);
bool effect_allows_sensor(const EffectSpec& s, int sensor);
// Its sensors come from `sensors` (triad_axis, axis_rows, noise), not from the one `sensor`.
bool effect_per_sensor(const EffectSpec& s);
// What excites it, for reports: excited_by, else the revealing condition.
const char* effect_excited_by(const EffectSpec& s);
// The stored value of parameter p of the effect on (sensor, axis) (axis −1 for vector and noise
// shapes; noise: p 0 = σ, 1 = τ), or nullptr outside the effect's shape.
double* effect_param(const EffectSpec& s, EffectTerms& e, int sensor, int axis, int p);
double effect_value(const EffectSpec& s, const EffectTerms& e, int sensor, int axis, int p);  // 0 outside
// Typed views of the stored values (throw std::logic_error on a shape or size mismatch): the three
// per-axis values of one sensor (triad_axis), the parameters of a vector effect, and the gyro
// matrix (row: gyro axis, column: force axis).
Eigen::Map<Vec3> effect_triad(EffectTerms& e, EffectId id, int sensor);
Eigen::Map<const Vec3> effect_triad(const EffectTerms& e, EffectId id, int sensor);
template <int N>
Eigen::Map<Eigen::Matrix<double, N, 1>> effect_vector(EffectTerms& e, EffectId id);
template <int N>
Eigen::Map<const Eigen::Matrix<double, N, 1>> effect_vector(const EffectTerms& e, EffectId id);
Eigen::Map<Mat3> effect_matrix(EffectTerms& e, EffectId id);
Eigen::Map<const Mat3> effect_matrix(const EffectTerms& e, EffectId id);
// The name of component p of an axis_rows effect's row on `axis` (g2_sensitivity "xy"; the
// other-axes rows: the other axis's letter).
std::string effect_component_name(const EffectSpec& s, int axis, int p);
// Every value of the effect back to zero.
void effect_clear(const EffectSpec& s, EffectTerms& e);

// The truth side of all effects (the spec hooks, in catalogue order; identity where none is set).
double truth_time(const EffectTerms& e, double t);
void truth_table_angle(const EffectTerms& e, double& angle, double& rate);
void truth_level_frame(const EffectTerms& e, const Mat3& C_b_l, const Vec3& f_b, const Vec3& w_ie_b, Vec3& f, Vec3& w);
bool needs_rate_derivative(const EffectTerms& e);  // some effect set in e uses ω̇
// The time-stamp terms: how late the IMU stamps are (τ: a sample stamped t saw t − τ), and a copy
// of e with only the time-stamp terms.
double time_stamp_offset(const EffectTerms& e);
EffectTerms time_stamp_terms(const EffectTerms& e);

// Reference-side output of all effects (added to dgyro, daccel): the bench reference's errors.
void reference_side_terms(const EffectTerms& e, const EffectContext& c, Vec3& dgyro, Vec3& daccel);

// Is any parameter of the effect set in e (noise: σ > 0)?
bool effect_present(const EffectSpec& s, const EffectTerms& e);
// IDs of the effects set in e, in catalogue order.
std::vector<std::string> effect_ids_present(const EffectTerms& e);

// Every linear candidate (noise-model effects are not here). drive_diagnosis: the caller filters.
std::vector<Term> candidate_terms();
// SI unit of a term's parameters (as reported in findings and IMPROVED.json).
std::string term_unit(const Term& t);

// The effect of shape `noise` (the drift model beyond the data sheet: σ p 0, τ p 1 per triad).
const EffectSpec& noise_effect_spec();
// The noise spec with the triads' drift prior replaced where e carries a noise-model effect.
NoiseSpec noise_with_effects(NoiseSpec n, const EffectTerms& e);

// Which look-alike note applies between a finding and an alternative (nullptr: none).
const char* separation_note(EffectId finding, EffectId alternative);

}  // namespace calbench
