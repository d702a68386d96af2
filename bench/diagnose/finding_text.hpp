// Parts of a finding shown the same way by the bench and the drive diagnosis:
//  - a correlated_drift finding's correlation time: τ with its 1σ interval from the profile
//    likelihood, an open side marked (the record is too short to bound τ there; what it
//    determines is σ²/τ, the random-walk density);
//  - the candidates the recording does not tell apart from a finding (DiagAlternative);
//  - the terms withdrawn after the search (DiagWithdrawn).
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "calibration/diagnosis/diagnose.hpp"

namespace calbench {

// A number with `prec` significant digits, as the sentences and tables print it.
std::string fmt(double v, int prec = 3);

// "60 s (1σ 45–80 s); random-walk density σ·√(2/τ) 12 °/h/√h (1σ 11 – 13)", an open side
// "not bounded by this record".
std::string drift_tau_text(const DiagFinding& f);
// evidence.tau_s; evidence.tau_s_1sigma/_2sigma and evidence.sigma_1sigma/_2sigma = [lo, hi] (null
// for an open side); evidence.random_walk_density = σ·√(2/τ) (unit/√s: what a record short against
// τ determines) with random_walk_density_1sigma/_2sigma.
void add_drift_tau_evidence(const DiagFinding& f, nlohmann::json& evidence);

// evidence.indistinguishable_from: [{effect, label, value, unit, chi2_worse}], best first.
nlohmann::json alternatives_json(const DiagFinding& f);
// "; NOT told apart on this recording from X (χ² only 3.2 worse)[: why]" per alternative.
std::string alternatives_text(const DiagFinding& f);

// "withdrawn": [{effect, label, delta_chi2_when_accepted, delta_chi2_final}].
nlohmann::json withdrawn_json(const std::vector<DiagWithdrawn>& w);
// "- withdrawn: … (accepted with Δχ² …, but …)" without the newline.
std::string withdrawn_text(const DiagWithdrawn& w);
// The JSON "why" of a withdrawn term.
const char* withdrawn_why_key(WithdrawnWhy w);

// "range exceeded: gyro z output held at +291 / -291 °/s with no noise (a plateau at the highest
// outputs; 100 % of those steps' sub-blocks frozen) where the reference reached 300 °/s:
// saturation, not a polynomial; steps 10, 11 (16 s) left out of the diagnosis".
std::string saturation_sentence(const DiagSaturation& x);
// Issue 36, the smallest inputs (DiagLowInput): the verdict, the bands and what the catalogue names instead.
std::string low_input_sentence(const DiagLowInput& x);

// "drift beyond the class's stability, not established: gyro z's bias moved 19.6 °/h over the
// run, 3.8× …; it follows the recorded temperature (…): temperature or drift, not told apart".
std::string drift_excess_sentence(const DiagDriftExcess& x);
// A bias change beyond 2× the class's stability that its own drift also makes (drift_excess_noted): a note.
std::string drift_note_sentence(const DiagDriftExcess& x);

// A spec's sentence (effect_registry.hpp) with {who} and {condition} filled in.
std::string fill_sentence(const char* tmpl, const std::string& who, const std::string& condition);

}  // namespace calbench
