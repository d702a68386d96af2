// The catalogue of `calbench diagnose` (docs/diagnosis.md): each candidate term (effect_registry.hpp)
// names an effect, the sensor/axis it acts on and its parameters; its regressors are the derivative of the
// predicted sensor output (predict_extra) with respect to those parameters, so what the
// diagnosis fits is exactly what the predictor and the simulator apply.
#pragma once
#include <string>
#include <vector>

#include "calibration/diagnosis/diag_data.hpp"
#include "calibration/effects/effect_registry.hpp"

namespace calbench {

// EffectId, Term, the names, units and candidate terms: the effect registry
// (calibration/effects/effect_registry.hpp).

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
