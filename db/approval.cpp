#include "db/approval.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "common/input_error.hpp"
#include "common/json_parse.hpp"
#include "common/number_parse.hpp"
#include "common/units.hpp"
#include "db/inmotion_import.hpp"
#include "db/signer.hpp"

namespace calbench::db {
namespace {
using nlohmann::json;
using namespace calbench::units;

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}
const char* axis(int i) { return i == 0 ? "x" : i == 1 ? "y" : "z"; }

void check_triad(const char* name, const TriadErrors& e, const TriadLimits& L, double unit, const char* unit_name,
                 bool allow_unknown, std::vector<std::string>& why) {
  for (int i = 0; i < 3; ++i) {
    if (std::abs(e.bias(i)) > L.max_abs_bias)
      why.push_back(std::string(name) + " bias " + axis(i) + " = " + fmt(e.bias(i) / unit) + " " + unit_name +
                    " exceeds ±" + fmt(L.max_abs_bias / unit) + " " + unit_name);
    if (!std::isfinite(e.sigma_bias(i))) {
      if (!allow_unknown) why.push_back(std::string(name) + " bias " + axis(i) + ": σ unknown (not estimated)");
    } else if (e.sigma_bias(i) > L.max_sigma_bias) {
      why.push_back(std::string(name) + " bias " + axis(i) + ": σ = " + fmt(e.sigma_bias(i) / unit) + " " + unit_name +
                    " exceeds " + fmt(L.max_sigma_bias / unit) + " " + unit_name);
    }
    for (int j = 0; j < 3; ++j) {
      const std::string el = std::string(name) + " M[" + axis(i) + axis(j) + "]";
      const double lim = i == j ? L.max_abs_scale : L.max_abs_skew;
      if (std::abs(e.M(i, j)) > lim)
        why.push_back(el + " = " + fmt(e.M(i, j) / kPpm) + " ppm exceeds ±" + fmt(lim / kPpm) + " ppm (" +
                      (i == j ? "scale" : "skew") + ")");
      if (!std::isfinite(e.sigma_M(i, j))) {
        if (!allow_unknown) why.push_back(el + ": σ unknown (not estimated)");
      } else if (e.sigma_M(i, j) > L.max_sigma_M) {
        why.push_back(el + ": σ = " + fmt(e.sigma_M(i, j) / kPpm) + " ppm exceeds " + fmt(L.max_sigma_M / kPpm) + " ppm");
      }
    }
  }
}

void read_limits(const json& j, const std::string& f, const std::string& name, TriadLimits& L, double unit,
                 const std::string& unit_key) {
  if (!j.is_object()) throw InputError(f, 0, name, "expected an object");
  const std::string kb = "max_abs_bias_" + unit_key, ks = "max_sigma_bias_" + unit_key;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = name + "." + it.key();
    if (!it->is_number()) throw InputError(f, 0, key, std::string("expected a number, got ") + it->type_name());
    const double v = it->get<double>();
    if (!std::isfinite(v) || v < 0) throw InputError(f, 0, key, "expected a finite non-negative number");
    if (it.key() == kb) L.max_abs_bias = v * unit;
    else if (it.key() == ks) L.max_sigma_bias = v * unit;
    else if (it.key() == "max_abs_scale_ppm") L.max_abs_scale = v * kPpm;
    else if (it.key() == "max_abs_skew_ppm") L.max_abs_skew = v * kPpm;
    else if (it.key() == "max_sigma_M_ppm") L.max_sigma_M = v * kPpm;
    else
      throw InputError(f, 0, key, "unknown key (expected " + kb + ", " + ks +
                                      ", max_abs_scale_ppm, max_abs_skew_ppm, max_sigma_M_ppm)");
  }
}
}  // namespace

Thresholds default_thresholds() {
  // ADIS16488A data-sheet class: turn-on gyro bias ~0.2 °/s, accelerometer bias ~16 mg, scale
  // ~0.5 %, axis misalignment ~0.05 %: limits at about 5× those; σ limits are what a good bench
  // run reaches with margin (bias stability 5.1 °/h, 0.1 mg).
  Thresholds t;
  t.gyro = {3600 * kDegPerHour, 25000 * kPpm, 5000 * kPpm, 10 * kDegPerHour, 500 * kPpm};
  t.accel = {80 * kMilliG, 25000 * kPpm, 5000 * kPpm, 2 * kMilliG, 500 * kPpm};
  return t;
}

Thresholds parse_thresholds(const std::string& text, const std::string& f) {
  const json j = parse_json_text(text, f);
  if (!j.is_object()) throw InputError(f, 1, "", "expected a JSON object");
  Thresholds t = default_thresholds();
  t.source = f;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& k = it.key();
    if (k == "gyro") read_limits(*it, f, k, t.gyro, kDegPerHour, "dph");
    else if (k == "accel") read_limits(*it, f, k, t.accel, kMilliG, "mg");
    else if (k == "allow_unknown_sigma" || k == "require_qc") {
      if (!it->is_boolean()) throw InputError(f, 0, k, "expected true or false");
      (k == "require_qc" ? t.require_qc : t.allow_unknown_sigma) = it->get<bool>();
    } else if (k == "required_qc_metrics") {
      if (!it->is_array()) throw InputError(f, 0, k, "expected an array of metric names");
      t.required_qc_metrics.clear();
      for (const auto& m : *it) {
        if (!m.is_string()) throw InputError(f, 0, k, "expected an array of metric names");
        t.required_qc_metrics.push_back(m.get<std::string>());
      }
    } else if (k == "max_outage_median_m") {
      if (!it->is_object()) throw InputError(f, 0, k, "expected an object {\"LENGTH_S\": METRES, ...}, e.g. {\"15\": 10}");
      t.max_outage_median_m.clear();
      for (auto e = it->begin(); e != it->end(); ++e) {
        const std::string key = k + "." + e.key();
        double L = 0;
        if (!parse_finite_number(e.key(), L) || !(L > 0))
          throw InputError(f, 0, key, "expected an outage length in seconds (> 0) as the key");
        if (!e->is_number() || !std::isfinite(e->get<double>()) || e->get<double>() < 0)
          throw InputError(f, 0, key, "expected a finite non-negative number of metres");
        t.max_outage_median_m[L] = e->get<double>();
      }
    } else if (parse_fit_quality_key(k, *it, f, t.quality)) {
      // bench, inmotion, combined: db/approval_quality.cpp
    } else if (k == "model" || k == "comment") {
      // informative
    } else {
      throw InputError(f, 0, k, "unknown key (expected gyro, accel, allow_unknown_sigma, require_qc, required_qc_metrics, "
                                    "max_outage_median_m, bench, inmotion, combined)");
    }
  }
  return t;
}

Thresholds load_thresholds(const std::string& path) {
  return parse_thresholds(read_json_text(path), path);
}

ApprovalCheck check_approval(const CoefficientSetRecord& set, const std::vector<QcResult>& qc, const Thresholds& t,
                             const FitEvidence& ev) {
  ApprovalCheck r = check_verdict(set, qc, ev, t);
  if (set.status != SetStatus::draft)
    r.reasons.insert(r.reasons.begin(), "set " + std::to_string(set.id) + " is " + to_string(set.status) +
                                            ", only draft sets can be approved");
  r.ok = r.reasons.empty();
  return r;
}

ApprovalCheck check_thresholds(const CoefficientSetRecord& set, const std::vector<QcResult>& qc, const Thresholds& t) {
  ApprovalCheck r;
  check_triad("gyro", set.errors.gyro, t.gyro, kDegPerHour, "°/h", t.allow_unknown_sigma, r.reasons);
  check_triad("accel", set.errors.accel, t.accel, kMilliG, "mg", t.allow_unknown_sigma, r.reasons);
  if (t.require_qc && qc.empty())
    r.reasons.push_back("no QC results recorded for this set's run (db store-bench --qc NAME=VALUE:LIMIT; fit multipos "
                        "prints its line; or the thresholds' \"require_qc\": false)");
  for (const auto& q : qc)
    if (!q.pass)
      r.reasons.push_back("QC " + q.metric + " = " + fmt(q.value) + (q.unit.empty() ? "" : " " + q.unit) + " failed" +
                          (q.threshold ? " (threshold " + fmt(*q.threshold) + ")" : "") +
                          (q.criterion.empty() ? "" : ": " + q.criterion) + (q.sample.empty() ? "" : ", " + q.sample));
  for (const auto& [L, lim] : t.max_outage_median_m) {
    const std::string m = outage_metric("in-motion", L, "median_max_m");
    for (const auto& q : qc)
      if (q.metric == m && q.value > lim)
        r.reasons.push_back("QC " + m + " = " + fmt(q.value) + " m exceeds the outage threshold " + fmt(lim) + " m" +
                            (q.sample.empty() ? "" : ", " + q.sample));
  }
  for (const auto& m : t.required_qc_metrics) {
    bool found = false;
    for (const auto& q : qc) found = found || q.metric == m;
    if (!found) r.reasons.push_back("required QC metric '" + m + "' missing");
  }
  r.ok = r.reasons.empty();
  return r;
}

ApprovalCheck check_verdict(const CoefficientSetRecord& set, const std::vector<QcResult>& qc, const FitEvidence& ev,
                            const Thresholds& t) {
  ApprovalCheck r = check_thresholds(set, qc, t);
  for (auto& why : fit_quality_reasons(set, ev, t.quality)) r.reasons.push_back(std::move(why));
  r.ok = r.reasons.empty();
  return r;
}

std::string parent_reason(Store& store, const CoefficientSetRecord& set) {
  if (!set.parent_id) return {};
  const auto p = store.find_set(*set.parent_id);
  if (!p || (p->status != SetStatus::draft && p->status != SetStatus::revoked)) return {};
  return "parent set " + std::to_string(p->id) + " is " + to_string(p->status) +
         (p->status == SetStatus::draft ? ": approve the set it refines first"
                                        : ": a set refined from a revoked set cannot be approved");
}

ApprovalCheck check_standing(Store& store, const CoefficientSetRecord& set, const Thresholds& t) {
  ApprovalCheck r = check_verdict(set, store.qc_of_set(set), fit_evidence(store, set), t);
  if (const std::string why = parent_reason(store, set); !why.empty()) r.reasons.push_back(why);
  r.ok = r.reasons.empty();
  return r;
}

std::vector<std::string> describe_thresholds(const Thresholds& t) {
  std::vector<std::string> out;
  const auto f = [](double v) {
    std::ostringstream s;
    s.precision(6);
    s << v;
    return s.str();
  };
  const auto triad = [&](const char* name, const TriadLimits& L, double unit, const char* un) {
    out.push_back(std::string(name) + ": |bias| ≤ " + f(L.max_abs_bias / unit) + " " + un + ", |scale| ≤ " +
                  f(L.max_abs_scale / kPpm) + " ppm, |skew| ≤ " + f(L.max_abs_skew / kPpm) + " ppm, σ bias ≤ " +
                  f(L.max_sigma_bias / unit) + " " + un + ", σ M ≤ " + f(L.max_sigma_M / kPpm) + " ppm");
  };
  triad("gyro", t.gyro, kDegPerHour, "°/h");
  triad("accel", t.accel, kMilliG, "mg");
  out.push_back(t.allow_unknown_sigma ? "unknown σ (not estimated) allowed" : "every σ known (a null σ refuses approval)");
  out.push_back(t.require_qc ? "QC: at least one result recorded with the set's run; every check passes"
                             : "QC: every recorded check passes (none required)");
  if (!t.max_outage_median_m.empty()) {
    std::string m;
    for (const auto& [L, lim] : t.max_outage_median_m) m += (m.empty() ? "" : ", ") + f(L) + " s ≤ " + f(lim) + " m";
    out.push_back("outage QC (GNSS-only drives), median of the largest horizontal error of the result set: " + m);
  }
  for (auto& line : describe_fit_quality(t.quality)) out.push_back(std::move(line));
  if (!t.required_qc_metrics.empty()) {
    std::string m;
    for (const auto& x : t.required_qc_metrics) m += (m.empty() ? "" : ", ") + x;
    out.push_back("required QC metrics: " + m);
  }
  return out;
}

namespace {
// SQLite: the OS user beside the typed name (PostgreSQL's source already names the login).
std::string signature_suffix(const Store& store) {
  const std::string note = store.authenticated() ? "" : signature_note(store.login(), false);
  return note.empty() ? "" : "; " + note;
}
}  // namespace

namespace {
// A PostgreSQL array literal of texts ({"a","b"}), quotes and backslashes escaped.
std::string pg_text_array(const std::vector<std::string>& v) {
  std::string out = "{";
  for (std::size_t i = 0; i < v.size(); ++i) {
    out += i ? ",\"" : "\"";
    for (char ch : v[i]) {
      if (ch == '"' || ch == '\\') out += '\\';
      out += ch;
    }
    out += '"';
  }
  return out + "}";
}

// The client's part of the verdict (the thresholds file, the named operator, four-eyes as the
// client sees it, the parent rule): every reason it refuses for.
void client_reasons(Store& store, const CoefficientSetRecord& set, bool four_eyes, ApprovalCheck& r) {
  const Actor& who = store.actor();
  if (!who.named()) {
    r.reasons.push_back("approval needs a named operator: --operator NAME or CALBENCH_OPERATOR (the OS user '" +
                        who.user + "' records who ran a command but does not sign)");
  } else if (four_eyes && stored_by_signer(store, set)) {
    const std::string maker = person_of_login(store, set.created_by_login);
    r.reasons.push_back("four-eyes: set " + std::to_string(set.id) + " was stored by '" + creator_name(set) + "'" +
                        (store.authenticated() ? " with login '" + set.created_by_login + "'" +
                                                     (maker.empty() ? "" : " (" + maker + ")") + ", and " + who.user +
                                                     " (login " + store.login() + ") is the same person"
                                               : "") +
                        "; another person must approve it");
  }
  if (const std::string why = parent_reason(store, set); !why.empty()) r.reasons.push_back(why);
  r.ok = r.reasons.empty();
}
}  // namespace

ApprovalCheck approve_checked(Store& store, std::int64_t set_id, const Thresholds& t) {
  store.check_signer();  // an --operator that is not the login's person is refused before anything
  ApprovalCheck r;
  store.connection().write_transaction([&] {
    r = ApprovalCheck{};
    const CoefficientSetRecord set = store.get_set(set_id);
    if (set.status == SetStatus::approved || set.status == SetStatus::provisioned) {
      r.already = true;  // approving again changes nothing, and is not a refusal
      return;
    }
    r = check_approval(set, store.qc_of_set(set), t, fit_evidence(store, set));
    const bool four_eyes = store.setting(kFourEyes) == "on";
    client_reasons(store, set, four_eyes, r);
    if (store.authenticated()) {
      // PostgreSQL: the database runs its part of the verdict and four-eyes by person, and writes
      // the signed row or the refusal with every reason (the client's included).
      auto f = store.connection().prepare("SELECT array_to_json(calbench_approve(?, ?, ?, ?))::text");
      f.bind(1, set_id).bind(2, store.actor().station).bind(3, pg_text_array(r.reasons)).bind(4, "thresholds: " + t.source);
      f.step();
      r.reasons.clear();
      for (const auto& x : nlohmann::json::parse(f.text(0))) r.reasons.push_back(x.get<std::string>());
      r.ok = r.reasons.empty();
      return;
    }
    if (r.ok) {
      const Actor& who = store.actor();
      store.set_status(set_id, SetStatus::approved,
                       "signed by " + who.user + " (" + who.source + signature_suffix(store) + "), stored by " + creator_name(set) +
                           (set.created_by_login.empty() ? "" : " (" + signature_note(set.created_by_login, store.authenticated()) + ")") +
                           (four_eyes ? "" : ", four-eyes off") + "; thresholds: " + t.source);
    } else {
      std::string why;
      for (const auto& x : r.reasons) why += (why.empty() ? "" : "; ") + x;
      store.audit_locked("coefficient_set", set_id, "approve-refused", why);
    }
  });
  return r;
}

}  // namespace calbench::db
