// The extra keys of coefficients.json that carry catalogue terms (docs/diagnosis.md), and the
// `--inject EFFECT:key=value,...` option of `calbench simulate bench`. Both map to EffectTerms.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "calibration/effects/effect_terms.hpp"

namespace calbench {

// Read the catalogue keys present in a coefficients.json document (top level); others ignored.
// sigma: the 1σ values found (same layout), zero where absent.
EffectTerms effects_from_json(const nlohmann::json& j, const std::string& file, EffectTerms* sigma = nullptr);
// Write the non-zero terms as extra keys into `j` (with σ from `sigma`).
void effects_to_json(const EffectTerms& e, const EffectTerms& sigma, nlohmann::json& j);

// One --inject option, e.g. "g_sensitivity:axis=x,f=y,value=1.6e-4". Throws InputError naming the option.
void apply_inject_option(const std::string& opt, EffectTerms& e);

}  // namespace calbench
