// The extra keys of coefficients.json that carry catalogue terms (docs/diagnosis.md), and the
// `--inject EFFECT:key=value,...` option of `calbench simulate bench`. Both map to EffectTerms.
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "calibration/effects/effect_terms.hpp"

namespace calbench {

// Every catalogue key a coefficients.json can carry (docs/diagnosis.md): the effect IDs.
const std::vector<std::string>& effect_json_keys();

// Read the catalogue keys present in a coefficients.json document (top level); others ignored.
// sigma: the 1σ values found (same layout), zero where absent.
EffectTerms effects_from_json(const nlohmann::json& j, const std::string& file, EffectTerms* sigma = nullptr);
// Write the non-zero terms as extra keys into `j` (with σ from `sigma`).
void effects_to_json(const EffectTerms& e, const EffectTerms& sigma, nlohmann::json& j);

// One --inject option, e.g. "g_sensitivity:axis=x,f=y,value=1.6e-4". Throws InputError naming the option.
void apply_inject_option(const std::string& opt, EffectTerms& e);

// The terms a simulation injects: the truth file's own catalogue keys, replaced by those of an
// effects file when one is given (it must hold at least one), then each --inject option.
EffectTerms simulation_effects(const nlohmann::json& truth_extra, const std::string& truth_file,
                               const std::string& effects_file, const std::vector<std::string>& inject);
// Replace every catalogue key of `j` by the non-zero terms of `e` (written without σ).
void replace_effect_keys(const EffectTerms& e, nlohmann::json& j);

// The catalogue as documentation, from the registry (`calbench diagnose --list-effects`,
// scripts/gen-docs): the catalogue table and the --inject keys table (Markdown, separated by one
// empty line), or one JSON object per effect.
std::string effect_catalogue_markdown();
nlohmann::json effect_catalogue_json();

}  // namespace calbench
