// `calbench diagnose` on a GNSS-only drive: where the innovations grow by motion condition, the
// logger's measured terms tested against them, and what remains (issue 53 item 5; JSON and text).
#include <cmath>
#include <cstdio>
#include <sstream>

#include "bench/diagnose/finding_text.hpp"
#include "bench/diagnose/gnss_run.hpp"
#include "calibration/diagnosis/diagnose.hpp"
#include "calibration/inmotion/obs_names.hpp"
#include "common/units.hpp"

namespace calbench {

namespace {



// Display unit of a condition's range: speed m/s, turn rate °/s, acceleration m/s².
double display(const ConditionBreakdown& c, double v) { return c.condition == "turn rate" ? v / units::kDeg : v; }
const char* unit(const ConditionBreakdown& c) {
  return c.condition == "speed" ? "m/s" : c.condition == "turn rate" ? "°/s" : c.condition == "acceleration" ? "m/s²" : "";
}

nlohmann::json breakdown_json(const std::vector<ConditionBreakdown>& v) {
  nlohmann::json a = nlohmann::json::array();
  for (const ConditionBreakdown& c : v) {
    nlohmann::json bins = nlohmann::json::array();
    for (const ConditionBin& b : c.bins) {
      nlohmann::json x = {{"label", b.label}, {"epochs", b.epochs}, {"nis_per_dof", b.nis_per_dof}};
      if (c.condition != "motion") x["range"] = {display(c, b.lo), display(c, b.hi)};
      bins.push_back(x);
    }
    nlohmann::json x = {{"condition", c.condition}, {"bins", bins}, {"grows", c.grows}};
    if (*unit(c)) x["unit"] = unit(c);
    if (c.grown >= 0)
      x["growth"] = {{"bin", c.bins[static_cast<std::size_t>(c.grown)].label},
                     {"against", c.bins[static_cast<std::size_t>(c.reference)].label}, {"ratio", c.ratio}, {"z", c.z}};
    a.push_back(x);
  }
  return a;
}

// "moving 1.1 (230), standstill 0.41 (40), start of motion 2.3 (25); speed (m/s) 0.20–0.90: 1.0,
// 0.90–1.20: 1.2, 1.20–1.60: 1.4; …" (NIS/dof, epochs in parentheses; the ranges fixed-point).
std::string breakdown_line(const std::vector<ConditionBreakdown>& v) {
  std::ostringstream o;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const ConditionBreakdown& c = v[i];
    o << (i ? "; " : "");
    if (c.condition == "motion") {
      for (std::size_t k = 0; k < c.bins.size(); ++k)
        o << (k ? ", " : "") << c.bins[k].label << " " << fmt(c.bins[k].nis_per_dof, 2) << " (" << c.bins[k].epochs << ")";
      continue;
    }
    const int decimals = c.condition == "turn rate" ? 1 : 2;
    char buf[64];
    o << c.condition << " (" << unit(c) << ")";
    for (std::size_t k = 0; k < c.bins.size(); ++k) {
      std::snprintf(buf, sizeof buf, "%s %.*f–%.*f: ", k ? "," : "", decimals, display(c, c.bins[k].lo), decimals, display(c, c.bins[k].hi));
      o << buf << fmt(c.bins[k].nis_per_dof, 2);
    }
  }
  return o.str();
}

std::string grows_text(const std::vector<ConditionBreakdown>& v) {
  const std::string g = growing_conditions_text(v);
  return g.empty() ? "no condition grows" : "grows with " + g;
}

}  // namespace

nlohmann::json gnss_conditions_json(const GnssDiagRun& run) {
  nlohmann::json j;
  j["method"] = "mean NIS/dof of the epochs by motion condition: standstill (speed < 0.3 m/s), start of motion (first 5 s), "
                "moving; speed, turn rate and horizontal acceleration in terciles of the moving epochs; a condition grows when "
                "its bin is >= 1.5x the reference bin and >= 3 standard errors (effective samples for the lag-1 correlation)";
  for (int k = 0; k < 2; ++k) {
    nlohmann::json t = {{"base", breakdown_json(run.conditions.base[k])}, {"final_model", breakdown_json(run.conditions.final_model[k])}};
    if (run.conditions.logger_compared) t["without_logger_terms"] = breakdown_json(run.conditions.without_logger[k]);
    j[inmotion::obs_type_name(k)] = t;
  }
  nlohmann::json tests = nlohmann::json::array();
  for (const GnssLoggerTest& t : run.logger_tests)
    tests.push_back({{"name", t.name}, {"value", t.value}, {"value_ms", t.value_ms}, {"epochs_compared", t.epochs_compared},
                     {"delta_chi2", t.dchi2}, {"overdispersion_phi", run.conditions.phi_base},
                     {"delta_chi2_over_phi", t.dchi2_over_phi}, {"confirmed", t.confirmed}});
  j["logger_tests"] = tests;
  if (run.conditions.logger_compared)
    j["without_logger_terms_adaptive_scale"] = {{"max", run.conditions.without_scale_max}, {"end", run.conditions.without_scale_end}};
  return j;
}

std::string gnss_conditions_text(const GnssDiagRun& run) {
  const GnssConditions& c = run.conditions;
  std::ostringstream o;
  o << "where the innovations grow (NIS/dof by motion condition, epochs in parentheses; the base filter):\n";
  for (int k = 0; k < 2; ++k)
    o << "  " << inmotion::obs_type_name(k) << ": " << breakdown_line(c.base[k]) << " — " << grows_text(c.base[k]) << "\n";
  if (c.logger_compared)
    o << "  without the logger's measured terms: position " << grows_text(c.without_logger[0]) << "; velocity "
      << grows_text(c.without_logger[1]) << "; there the navigation-noise variance rose to x" << fmt(c.without_scale_max, 3)
      << " (x" << fmt(c.without_scale_end, 3) << " at the end)" << (c.without_scale_max > 10 ? " and absorbed much of the misfit" : "")
      << "\n";
  if (!run.logger_tests.empty()) {
    o << "logger physics tested against that (Δχ² of the base filter against the same filter without the term, /φ "
      << fmt(c.phi_base, 3) << "; confirmed at ≥ " << fmt(DriveDiagnoseOptions{}.min_delta_chi2) << "):\n";
    for (const GnssLoggerTest& t : run.logger_tests)
      o << (t.confirmed ? "* " : "- ") << t.name << " " << t.value << ": Δχ² " << fmt(t.dchi2) << ", Δχ²/φ " << fmt(t.dchi2_over_phi)
        << " over the " << t.epochs_compared << " epochs both runs have — "
        << (t.confirmed ? "confirmed by the innovations" : t.dchi2 < 0 ? "the innovations fit better without it" : "not confirmed by the innovations")
        << "\n";
  } else {
    o << "logger physics: the stamps are regular and the fix velocity is taken at its stamp: nothing of the logger to test\n";
  }
  const std::string rest[2] = {growing_conditions_text(c.final_model[0]), growing_conditions_text(c.final_model[1])};
  if (rest[0].empty() && rest[1].empty()) o << "what remains (final model): no condition grows\n";
  else
    o << "what remains (final model): " << (rest[0].empty() ? "" : "position grows with " + rest[0])
      << (rest[0].empty() || rest[1].empty() ? "" : "; ") << (rest[1].empty() ? "" : "velocity grows with " + rest[1])
      << " — unexplained by the candidates tested\n";
  return o.str();
}

}  // namespace calbench
