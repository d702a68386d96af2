// The catalogue of `calbench diagnose` (docs/diagnosis.md): each candidate term (effect_registry.hpp)
// names an effect, the sensor/axis it acts on and its parameters; its regressors are the derivative of the
// predicted sensor output (predict_extra) with respect to those parameters, so what the
// diagnosis fits is exactly what the predictor and the simulator apply.
#pragma once
#include <string>
#include <vector>

#include "calibration/diagnosis/diag_data.hpp"
#include "calibration/effects/bench_attitude.hpp"
#include "calibration/effects/effect_registry.hpp"

namespace calbench {

// EffectId, Term, the names, units and candidate terms: the effect registry
// (calibration/effects/effect_registry.hpp).

// Extra output predicted for a sub-block from its reference conditions: sensor-side terms
// plus reference-side terms (time offset, wobble, table tilt), linearised. temp_c NaN → no
// temperature terms.
void predict_extra(const EffectTerms& e, const SubBlock& s, Vec3& dgyro, Vec3& daccel);

}  // namespace calbench
