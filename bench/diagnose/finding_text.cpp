#include "bench/diagnose/finding_text.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "bench/diagnose/diagnose_text.hpp"
#include "calibration/gauss_markov_window.hpp"
#include "common/units.hpp"

namespace calbench {
namespace {

nlohmann::json bound(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

}  // namespace

std::string fmt(double v, int prec) {
  std::ostringstream o;
  o << std::setprecision(prec) << v;
  return o.str();
}

std::string drift_tau_text(const DiagFinding& f) {
  const DriftInterval& i = f.noise_interval;
  const std::string lo = std::isfinite(i.tau_lo) ? fmt(i.tau_lo) + " s" : "not bounded by this record";
  const std::string hi = std::isfinite(i.tau_hi) ? fmt(i.tau_hi) + " s" : "not bounded by this record";
  std::string out = fmt(f.noise_tau_s) + " s (1σ " + lo + " – " + hi + ")";
  // The random-walk density, in °/h/√h or mg/√h (per √s × √3600 s/√h).
  if (!f.value.empty() && f.noise_tau_s > 0) {
    const double to_unit = (f.term.sensor == 0 ? 1.0 / units::kDegPerHour : 1.0 / units::kMilliG) * 60.0;
    const std::string unit = f.term.sensor == 0 ? " °/h/√h" : " mg/√h";
    const double k = gm_random_walk_density(f.value[0], f.noise_tau_s) * to_unit;
    const std::string khi = std::isfinite(i.rw_hi) ? fmt(i.rw_hi * to_unit) : "not bounded";
    out += "; random-walk density σ·√(2/τ) " + fmt(k) + unit + " (1σ " +
           (std::isfinite(i.rw_lo) ? fmt(i.rw_lo * to_unit) : "not bounded") + " – " + khi + ")";
  }
  return out;
}

void add_drift_tau_evidence(const DiagFinding& f, nlohmann::json& evidence) {
  const DriftInterval& i = f.noise_interval;
  auto pair = [](double lo, double hi) { return nlohmann::json::array({bound(lo), bound(hi)}); };
  evidence["tau_s"] = f.noise_tau_s;
  evidence["tau_s_1sigma"] = pair(i.tau_lo, i.tau_hi);
  evidence["tau_s_2sigma"] = pair(i.tau_lo2, i.tau_hi2);
  evidence["sigma_1sigma"] = pair(i.sigma_lo, i.sigma_hi);
  evidence["sigma_2sigma"] = pair(i.sigma_lo2, i.sigma_hi2);
  if (!f.value.empty() && f.noise_tau_s > 0) evidence["random_walk_density"] = gm_random_walk_density(f.value[0], f.noise_tau_s);
  evidence["random_walk_density_1sigma"] = pair(i.rw_lo, i.rw_hi);
  evidence["random_walk_density_2sigma"] = pair(i.rw_lo2, i.rw_hi2);
}

nlohmann::json alternatives_json(const DiagFinding& f) {
  nlohmann::json alts = nlohmann::json::array();
  for (const auto& a : f.alternatives) {
    nlohmann::json av = a.value.size() == 1 ? nlohmann::json(a.value[0]) : nlohmann::json(a.value);
    alts.push_back({{"effect", effect_name(a.term.effect)},
                    {"label", a.term.label()},
                    {"value", av},
                    {"unit", a.unit},
                    {"chi2_worse", a.chi2_worse},
                    {"regressor_correlation", a.regressor_correlation}});
  }
  return alts;
}

std::string alternatives_text(const DiagFinding& f) {
  std::string o;
  for (const auto& a : f.alternatives) {
    // A term with more parameters, or a smaller prior (EffectSpec::prior_penalty), can fit a
    // little better in its place and still lose on the penalised score that chose the finding.
    o += "; NOT told apart on this recording from " + a.term.label() +
         (a.chi2_worse >= 0 ? " (χ² only " + fmt(a.chi2_worse) + " worse)"
                            : " (χ² " + fmt(-a.chi2_worse) + " better, but with a larger penalty: more parameters or a smaller prior)");
    if (a.chi2_worse >= 0 && a.regressor_correlation >= 0.9) o += ", regressors correlated " + fmt(a.regressor_correlation, 3) + " here";
    if (const char* note = separation_note(f.term.effect, a.term.effect)) {
      o += std::string(": ") + note;
    } else {
      // No pair note: what excites each of the two.
      const EffectSpec &x = effect_spec(f.term.effect), &y = effect_spec(a.term.effect);
      if (x.id != y.id)
        o += std::string("; what separates them: ") + x.key + " needs " + effect_excited_by(x) + ", " +
             y.key + " " + effect_excited_by(y);
      else
        o += "; the same effect on another axis: a plan that excites each axis alone tells them apart";
    }
  }
  return o;
}

nlohmann::json withdrawn_json(const std::vector<DiagWithdrawn>& ws) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& w : ws) {
    out.push_back({{"effect", effect_name(w.term.effect)},
                   {"label", w.term.label()},
                   {"delta_chi2_when_accepted", w.delta_chi2_when_accepted},
                   {"delta_chi2_final", w.delta_chi2_final},
                   {"why", withdrawn_why_key(w.why)}});
    if (w.why == WithdrawnWhy::follows_condition) {
      out.back()["follows"] = {{"condition", w.condition}, {"axis", std::string(1, "xyz"[w.axis])}, {"r", w.condition_r}};
      if (w.condition_dchi2 > 0) {
        out.back()["follows"]["gls_delta_chi2"] = w.condition_dchi2;
        out.back()["follows"]["drift_gain"] = w.drift_gain;
      } else {
        out.back()["follows"]["fisher_z"] = w.condition_z;
      }
    }
  }
  return out;
}

const char* withdrawn_why_key(WithdrawnWhy w) {
  switch (w) {
    case WithdrawnWhy::weak: return "weak_in_final_model";
    case WithdrawnWhy::drift_recheck: return "better_without_drift";
    case WithdrawnWhy::overdispersed: return "carried_by_unexplained_remainder";
    case WithdrawnWhy::leaves_unexplained: return "drift_leaves_axis_unexplained";
    case WithdrawnWhy::follows_condition: return "drift_follows_condition";
  }
  return "";
}

std::string withdrawn_text(const DiagWithdrawn& w) {
  std::string o = "- withdrawn: " + w.term.label() + " (accepted with Δχ² " + fmt(w.delta_chi2_when_accepted);
  switch (w.why) {
    case WithdrawnWhy::drift_recheck:
      return o + ", but the catalogue terms explain the recording better without it: penalised −2 ln L " +
             fmt(w.delta_chi2_final) + ")";
    case WithdrawnWhy::leaves_unexplained:
      return o + ", but an axis of the triad stays unexplained with it: the drift stood in for structure outside "
                 "the catalogue)";
    case WithdrawnWhy::follows_condition:
      if (w.condition_dchi2 > 0)
        return o + ", but under the class's drift a bias following " + w.condition + " explains as much on " +
               std::string(w.term.sensor == 0 ? "gyro " : "accel ") + "xyz"[w.axis] + " (GLS Δχ² " + fmt(w.condition_dchi2) +
               "; the triad's together reach the drift's gain " + fmt(w.drift_gain) +
               "): the drift stood in for structure outside the catalogue)";
      return o + ", but its path on " + std::string(w.term.sensor == 0 ? "gyro " : "accel ") + "xyz"[w.axis] +
             " follows " + w.condition + " (r " + fmt(w.condition_r, 2) + ", Fisher z " + fmt(w.condition_z, 2) +
             "): a random wander is not tied to the motion; the drift stood in for structure outside the catalogue)";
    case WithdrawnWhy::overdispersed:
      return o + ", but counted against the unexplained remainder of its axis (Δχ²/φ) it explains only " +
             fmt(w.delta_chi2_final) + ")";
    case WithdrawnWhy::weak: break;
  }
  return o + ", but in the final model it explains only Δχ² " + fmt(w.delta_chi2_final) + ")";
}

std::string fill_sentence(const char* tmpl, const std::string& who, const std::string& condition) {
  std::string s = tmpl;
  for (const auto& [k, v] : {std::pair<std::string, std::string>{"{who}", who}, {"{condition}", condition}})
    for (auto at = s.find(k); at != std::string::npos; at = s.find(k, at + v.size())) s.replace(at, k.size(), v);
  return s;
}

std::string saturation_sentence(const DiagSaturation& x) {
  const bool gyro = x.sensor == 0;
  const double k = gyro ? 1.0 / units::kDeg : 1.0 / units::kG0;
  const char* unit = gyro ? " °/s" : " g";
  std::string levels;
  if (std::isfinite(x.level_pos)) levels += "+" + fmt(x.level_pos * k, 4);
  if (std::isfinite(x.level_neg)) levels += (levels.empty() ? "" : " / ") + fmt(x.level_neg * k, 4);
  std::string steps;
  for (int s : x.steps) steps += (steps.empty() ? "" : ", ") + std::to_string(s);
  return std::string("range exceeded: ") + (gyro ? "gyro " : "accel ") + "xyz"[x.axis] + " output held at " + levels + unit +
         " with no noise (a plateau at the highest outputs; " + fmt(100 * x.frozen_fraction, 3) +
         " % of those steps' sub-blocks frozen) where the reference reached " + fmt(x.reference_max * k, 4) + unit +
         ": saturation, not a polynomial; step" + (x.steps.size() > 1 ? "s " : " ") + steps + " (" + fmt(x.excluded_s, 3) +
         " s) left out of the diagnosis";
}

std::string low_input_sentence(const DiagLowInput& x) {
  const double k = 1.0 / units::kDeg;
  // Axes with the same band share it: "x, y, z: inputs up to … not sensed, from … sensed".
  std::vector<std::pair<std::string, std::string>> groups;  // band → axes
  std::string axes;
  for (const auto& a : x.axes) {
    const std::string ax(1, "xyz"[a.axis]);
    axes += (axes.empty() ? "" : ", ") + ax;
    // The best of the widths tried: the largest input it takes as not sensed, the smallest as sensed.
    const std::string band = "taken as not sensed up to " + fmt(a.below_max * k, 3) + " °/s" +
                             (a.above_min > 0 ? ", as sensed from " + fmt(a.above_min * k, 3) + " °/s" : "");
    auto it = std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == band; });
    if (it == groups.end()) groups.emplace_back(band, ax);
    else it->second += ", " + ax;
  }
  std::string bands;
  for (const auto& [band, who] : groups)
    bands += (bands.empty() ? "" : "; ") + (groups.size() > 1 ? who + ": " : std::string()) + band;
  // What the catalogue's model did with the record as is: "named A, B and left gyro z unexplained".
  std::string names, left;
  for (const auto& c : x.competing) names += (names.empty() ? "" : ", ") + c;
  for (int a : x.catalogue_unexplained) left += (left.empty() ? "gyro " : ", ") + std::string(1, "xyz"[a]);
  std::string named = names.empty() ? "" : "named " + names;
  if (!left.empty()) named += (named.empty() ? "" : " and ") + std::string("left ") + left + " unexplained";
  const std::string who = "gyro " + axes + ": ";
  const std::string what = "the output does not follow the smallest rate inputs (" + bands +
                           "; the best of widths Ω·1.25 to Ω·20): a dead band or threshold, outside the catalogue";
  const std::string by = fmt(std::abs(x.delta_score), 3);
  const std::string signed_by = fmt(x.delta_score, 3);
  if (std::string(x.verdict) == "not sensed")
    return who + what + "; the record with those inputs taken as not sensed fits better than the catalogue's model by Δ(−2 ln L) " +
           by + " (one parameter per axis charged), and the rest of the diagnosis, figures included, is of that record" +
           (named.empty() ? "" : "; the catalogue alone would have " + named);
  if (std::string(x.verdict) == "cannot tell")
    return who + "the reading that " + what + ", fits within " + fmt(DiagnoseOptions{}.ambiguity_chi2) + " of the catalogue's model (Δ(−2 ln L) " + signed_by +
           ", > 0: the reading fits better): not told apart" +
           (names.empty() ? "" : " (the catalogue's model " + named + "; those findings are not told apart from it)");
  return who + "the smallest inputs are sensed (the record with them taken as not sensed fits worse by Δ(−2 ln L) " + by + ")";
}

namespace {
// The temperature bias term's clause of a drift sentence (empty when it was not tried or gained nothing).
std::string drift_temperature_clause(const DiagDriftExcess& x, double k, const std::string& unit) {
  if (!x.has_temperature || x.temperature_dchi2 <= 0) return "";
  return "; the temperature bias term gives " + fmt(x.temperature_coef * k) + " ± " + fmt(x.temperature_coef_sigma * k, 2) + unit +
         " per °C, " + fmt(x.temperature_change_total() * k) + unit + " over the " + fmt(x.temperature_change) +
         " °C of the run (Δχ² " + fmt(x.temperature_dchi2, 2) + ", not established)";
}
}  // namespace

std::string drift_note_sentence(const DiagDriftExcess& x) {
  using diagnose_out::kAxis, diagnose_out::kSensor;
  const double k = diagnose_out::disp(1.0, x.sensor);
  const std::string unit = std::string(" ") + diagnose_out::disp_unit(x.sensor);
  std::string o = std::string("note, not a finding: ") + kSensor[x.sensor] + " " + kAxis[x.axis] + "'s bias moved " +
                  fmt(x.change * k) + unit + " over the run (" + fmt(x.change / x.stability, 2) +
                  "× the class's in-run bias stability, " + fmt(x.stability * k) + unit + ")";
  o += "; the class's own drift moves it that far on this recording in " +
       (x.null_exceed_count == 0 ? std::string("none") : std::to_string(x.null_exceed_count)) + " of " +
       std::to_string(kDriftExcessDraws) + " draws (" + fmt(100 * x.null_exceed(), 2) + " %; " + fmt(x.null_mean * k) + " ± " +
       fmt(x.null_sd * k, 2) + unit + ")";
  o += drift_temperature_clause(x, k, unit);
  if (x.follows_temperature)
    return o + "; the path follows the recorded temperature (r " + fmt(x.temperature_r, 2) +
           "): temperature or drift, not told apart";
  if (drift_note_temperature(x))
    return o + "; the path does not follow the temperature closely (r " + fmt(x.temperature_r, 2) +
           "), the temperature term fits it all the same: temperature or drift, not told apart";
  return o + ": the class's drift or an effect a drift imitates, not told apart";
}

std::string drift_excess_sentence(const DiagDriftExcess& x) {
  using diagnose_out::kAxis, diagnose_out::kSensor;
  const double k = diagnose_out::disp(1.0, x.sensor);
  const std::string unit = std::string(" ") + diagnose_out::disp_unit(x.sensor);
  std::string o = std::string("drift beyond the class's stability, not established: ") + kSensor[x.sensor] + " " + kAxis[x.axis] +
                  "'s bias moved " + fmt(x.change * k) + unit + " over the run, " + fmt(x.change / x.stability, 2) +
                  "× the class's in-run bias stability (" + fmt(x.stability * k) + unit + ") and " + fmt(x.z, 2) +
                  " standard deviations above what the class's noise gives on this recording (" + fmt(x.null_mean * k) + " ± " +
                  fmt(x.null_sd * k, 2) + unit + "); by likelihood " +
                  (x.gain > 0 ? "a drift of that axis alone " + fmt(x.sigma / x.stability, 2) + "× the class's (τ " + fmt(x.tau_s) +
                                    " s) fits better by Δ(−2 ln L) " + fmt(x.gain) + ", below the evidence a finding needs"
                              : std::string("no larger drift fits better: the record is too short to tell"));
  o += drift_temperature_clause(x, k, unit);
  if (x.temperature_or_drift())
    return o + "; the path follows the recorded temperature (r " + fmt(x.temperature_r, 2) +
           "): temperature or drift, not told apart";
  return o + (x.has_temperature ? "; it does not follow the recorded temperature (r " + fmt(x.temperature_r, 2) + ")" : std::string()) +
         ": a drift beyond the data sheet, or an effect outside the catalogue that a drift imitates, not told apart";
}

}  // namespace calbench
