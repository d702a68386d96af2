#include "bench/diagnose/finding_text.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace calbench {
namespace {

std::string fmt(double v) {
  std::ostringstream o;
  o << std::setprecision(3) << v;
  return o.str();
}

nlohmann::json bound(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

}  // namespace

std::string drift_tau_text(const DiagFinding& f) {
  const DriftInterval& i = f.noise_interval;
  const std::string lo = std::isfinite(i.tau_lo) ? fmt(i.tau_lo) + " s" : "not bounded by this record";
  const std::string hi = std::isfinite(i.tau_hi) ? fmt(i.tau_hi) + " s" : "not bounded by this record";
  return fmt(f.noise_tau_s) + " s (1σ " + lo + " – " + hi + ")";
}

void add_drift_tau_evidence(const DiagFinding& f, nlohmann::json& evidence) {
  const DriftInterval& i = f.noise_interval;
  evidence["tau_s"] = f.noise_tau_s;
  evidence["tau_s_1sigma"] = nlohmann::json::array({bound(i.tau_lo), bound(i.tau_hi)});
  evidence["sigma_1sigma"] = nlohmann::json::array({bound(i.sigma_lo), bound(i.sigma_hi)});
  if (!f.value.empty() && f.noise_tau_s > 0) evidence["random_walk_density"] = f.value[0] * std::sqrt(2.0 / f.noise_tau_s);
}

nlohmann::json alternatives_json(const DiagFinding& f) {
  nlohmann::json alts = nlohmann::json::array();
  for (const auto& a : f.alternatives) {
    nlohmann::json av = a.value.size() == 1 ? nlohmann::json(a.value[0]) : nlohmann::json(a.value);
    alts.push_back({{"effect", effect_name(a.term.effect)},
                    {"label", a.term.label()},
                    {"value", av},
                    {"unit", a.unit},
                    {"chi2_worse", a.chi2_worse}});
  }
  return alts;
}

std::string alternatives_text(const DiagFinding& f) {
  std::string o;
  for (const auto& a : f.alternatives) {
    // A term with more parameters can fit a little better in its place and still lose on the
    // penalised score that chose the finding.
    o += "; NOT told apart on this recording from " + a.term.label() +
         (a.chi2_worse >= 0 ? " (χ² only " + fmt(a.chi2_worse) + " worse)"
                            : " (χ² " + fmt(-a.chi2_worse) + " better, but with more parameters)");
    const bool temperature_pair = (a.term.effect == EffectId::temperature_rate && f.term.effect == EffectId::temperature_bias) ||
                                  (a.term.effect == EffectId::temperature_bias && f.term.effect == EffectId::temperature_rate);
    if (temperature_pair)
      o += ": on a warm-up alone a bias ∝ T and one ∝ dT/dt look alike; a plan that heats and cools over the "
           "same range (thermal_updown) tells them apart";
  }
  return o;
}

nlohmann::json withdrawn_json(const std::vector<DiagWithdrawn>& ws) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& w : ws)
    out.push_back({{"effect", effect_name(w.term.effect)},
                   {"label", w.term.label()},
                   {"delta_chi2_when_accepted", w.delta_chi2_when_accepted},
                   {"delta_chi2_final", w.delta_chi2_final}});
  return out;
}

std::string withdrawn_text(const DiagWithdrawn& w) {
  std::string o = "- withdrawn: " + w.term.label() + " (accepted with Δχ² " + fmt(w.delta_chi2_when_accepted);
  if (w.term.effect == EffectId::correlated_drift)
    return o + ", but the catalogue terms explain the recording better without it: penalised −2 ln L " +
           fmt(w.delta_chi2_final) + ")";
  return o + ", but in the final model it explains only Δχ² " + fmt(w.delta_chi2_final) + ")";
}

}  // namespace calbench
