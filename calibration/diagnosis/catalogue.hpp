// The catalogue of `calbench diagnose` (docs/diagnosis.md): each candidate term names an effect,
// the sensor/axis it acts on and its parameters; its regressors are the derivative of the
// predicted sensor output (predict_extra) with respect to those parameters, so what the
// diagnosis fits is exactly what the predictor and the simulator apply.
#pragma once
#include <string>
#include <vector>

#include "calibration/diagnosis/diag_data.hpp"
#include "calibration/effects/effect_terms.hpp"

namespace calbench {

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
};

const char* effect_name(EffectId e);
int effect_count();  // EffectId values are 0 … effect_count() − 1
bool effect_from_name(const std::string& s, EffectId& e);

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

// Every linear candidate (correlated_drift is handled by the noise model, not here). scale_factor
// is one only where M is not refitted (a drive with given coefficients): the caller filters.
std::vector<Term> candidate_terms();
// SI unit of a term's parameters (as reported in findings and IMPROVED.json).
std::string term_unit(const Term& t);

// Extra output predicted for a sub-block from its reference conditions: sensor-side terms
// plus reference-side terms (time offset, wobble, table tilt), linearised. temp_c NaN → no
// temperature terms.
void predict_extra(const EffectTerms& e, const SubBlock& s, Vec3& dgyro, Vec3& daccel);

// Attitude of the IMU in a static position from the reference (TRIAD on gravity and Earth rate):
// false if not static.
bool static_attitude(const Vec3& w, const Vec3& f, Mat3& C_b_l);

// Attitude of the IMU on the two-axis table from the reference of a static or a rotating
// sub-block: down from the specific force; north from the Earth rate. While the inner axis spins
// (about an IMU axis k), the table geometry keeps north perpendicular to k (the outer axis points
// north, the inner axis is perpendicular to it), so north ∝ k × down with the sign of the Earth
// rate along it, or, with k vertical, the Earth rate perpendicular to k. False if neither works
// (no gravity, or a rate not about an IMU axis).
bool bench_attitude(const Vec3& w, const Vec3& f, Mat3& C_b_l);

}  // namespace calbench
