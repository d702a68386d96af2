#include "db/inmotion_import.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>

#include "common/coefficients_codec.hpp"
#include "common/drive_result.hpp"
#include "common/input_error.hpp"
#include "common/json_fields.hpp"
#include "common/json_parse.hpp"

namespace calbench::db {
namespace {
using nlohmann::json;

// A coefficient block of the result as the store keeps it: the codec's set (its device already
// checked against the result's), re-serialised with its extra keys; the store's own rule on top: a
// set names its model.
ParsedCoefficients stored_block(const CoefficientSet& c, const std::string& f, const std::string& name) {
  if (c.device.model.empty()) throw InputError(f, 0, name + ".device.model", "expected a non-empty string");
  ParsedCoefficients p;
  p.device.model = c.device.model;
  p.device.serial = c.device.serial;
  p.errors = c.errors;
  p.canonical_json = coefficients_to_json(c).dump(2);
  return p;
}

// Which data the figures of a "qc" block were computed on, from its "sample" text
// ("out-of-sample (after the fit window)", "in-sample (no data after the fit window)", "not run").
std::string sample_class(const std::string& t) {
  for (const char* s : {kOutOfSample, kInSample, kSampleNotApplicable})
    if (t.rfind(s, 0) == 0) return s;
  return "";
}
std::string sample_of(const json& o, const std::string& f, const std::string& key, const std::string& dflt) {
  if (!o.is_object() || !o.contains("sample")) return dflt;
  if (!o["sample"].is_string()) throw InputError(f, 0, key + ".sample", "expected a string");
  return sample_class(o["sample"].get<std::string>());
}

QcResult metric_from_object(const std::string& name, const json& o, const std::string& f, const std::string& key,
                            const std::string& sample) {
  QcResult q;
  q.metric = name;
  q.value = jnum(o["value"], f, key + ".value");
  q.sample = sample_of(o, f, key, sample);
  if (o.contains("threshold") && !o["threshold"].is_null()) q.threshold = jnum(o["threshold"], f, key + ".threshold");
  const char* pk = o.contains("pass") ? "pass" : o.contains("passed") ? "passed" : nullptr;
  if (pk) {
    if (!o[pk].is_boolean()) throw InputError(f, 0, key + "." + pk, "expected true or false");
    q.pass = o[pk].get<bool>();
    q.criterion = "pass as stated in the result";
  } else if (q.threshold) {
    q.pass = std::abs(q.value) <= *q.threshold;
    q.criterion = "|value| ≤ threshold";
  }
  if (o.contains("unit") && o["unit"].is_string()) q.unit = o["unit"].get<std::string>();
  return q;
}

// Names of the QC sets of `fit drive` (docs/in-motion.md): the set the fit started from and the result.
constexpr const char* kQcBaselines[] = {"input", "none"};
constexpr const char* kQcResultSet = "in-motion";

// A set is never worse than the one it started from: the result's final ΔS gets the baseline's
// final ΔS as its threshold. Everything else stays informative.
void never_worse_than_baseline(std::vector<QcResult>& out, std::size_t first, const std::string& prefix) {
  const QcResult* base = nullptr;
  const char* base_name = nullptr;
  QcResult* result = nullptr;
  for (std::size_t i = first; i < out.size(); ++i) {
    for (const char* b : kQcBaselines)
      if (out[i].metric == prefix + b + ".final_cpe_m") {
        base = &out[i];
        base_name = b;
      }
    if (out[i].metric == prefix + kQcResultSet + ".final_cpe_m") result = &out[i];
  }
  if (!base || !result) return;
  result->threshold = base->value;
  result->pass = result->value <= base->value;
  result->criterion = std::string("never worse than the set the fit started from: value ≤ final ΔS of set '") +
                      base_name + "'";
}

// qc.outages (fit drive on a GNSS-only drive, docs/in-motion.md "Outage QC"): per set and outage
// length the median and the largest of the per-outage maxima and end errors, as
// outages.SET.Ls.FIELD (unit m, the outages' sample). One check: the result set's median maximum
// error of each length is never worse than that of the set the fit started from.
void outage_metrics(const OutageQc& o, const std::string& qc_sample, std::vector<QcResult>& out) {
  const std::string sample = o.sample ? sample_class(*o.sample) : qc_sample;
  // length (as in the metric name) → set name → median_max_m
  std::map<std::string, std::map<std::string, std::size_t>> median_at;
  for (const OutageSetFigures& s : o.sets)
    for (const OutageLengthFigures& p : s.per_length) {
      const std::string len = outage_metric("", p.length_s, "");
      const std::pair<const char*, std::optional<double>> fields[] = {
          {"median_max_m", p.median_max_m}, {"max_max_m", p.max_max_m}, {"median_end_m", p.median_end_m}, {"max_end_m", p.max_end_m}};
      for (const auto& [fk, v] : fields) {
        if (!v) continue;
        if (std::string(fk) == "median_max_m") median_at[len][s.name] = out.size();
        out.push_back(QcResult{outage_metric(s.name, p.length_s, fk), *v, std::nullopt, true, "m", sample, ""});
      }
    }
  // The errors are measured against the fixes: a difference within their noise (3σ of the stated
  // horizontal σ, fix_sigma_h_m) is not a worse set.
  const double noise = o.fix_sigma_h_m ? 3 * *o.fix_sigma_h_m : 0;
  for (auto& [len, by_set] : median_at) {
    auto r = by_set.find(kQcResultSet);
    if (r == by_set.end()) continue;
    for (const char* b : kQcBaselines) {
      auto base = by_set.find(b);
      if (base == by_set.end()) continue;
      QcResult& q = out[r->second];
      q.threshold = out[base->second].value + noise;
      q.pass = q.value <= *q.threshold;
      char tol[64];
      std::snprintf(tol, sizeof tol, " + %g m (3 sigma of the fixes)", noise);
      q.criterion = std::string("never worse than the set the fit started from: value <= the median largest outage error of set '") +
                    b + "'" + (noise > 0 ? tol : "");
      break;
    }
  }
}

std::vector<QcResult> qc_metrics(const json& qc, const std::optional<OutageQc>& outages, const std::string& f) {
  std::vector<QcResult> out;
  const std::string sample = sample_of(qc, f, "qc", "");
  auto from_array = [&](const json& arr, const std::string& key, const std::string& prefix) {
    const std::size_t first = out.size();
    for (std::size_t i = 0; i < arr.size(); ++i) {
      const json& e = arr[i];
      const std::string k = key + "[" + std::to_string(i) + "]";
      if (!e.is_object()) throw InputError(f, 0, k, "expected an object");
      std::string name;
      for (const char* nk : {"metric", "name"})
        if (e.contains(nk) && e[nk].is_string()) name = e[nk].get<std::string>();
      if (name.empty()) throw InputError(f, 0, k, "missing \"metric\" or \"name\"");
      if (e.contains("value")) {
        out.push_back(metric_from_object(prefix + name, e, f, k, sample));
      } else {  // e.g. {"name": "input", "final_cpe_m": 12.3, "max_cpe_m": 20.1}: figures of one set
        const std::string set_sample = sample_of(e, f, k, sample);
        for (auto it = e.begin(); it != e.end(); ++it) {
          if (!it->is_number()) continue;
          const std::string& fk = it.key();
          const bool metres = fk.size() > 2 && fk.compare(fk.size() - 2, 2, "_m") == 0;
          out.push_back(QcResult{prefix + name + "." + fk, jnum(*it, f, k + "." + fk), std::nullopt, true,
                                 metres ? "m" : "", set_sample, ""});
        }
      }
    }
    never_worse_than_baseline(out, first, prefix);
  };
  if (qc.is_array()) {
    from_array(qc, "qc", "");
    return out;
  }
  if (!qc.is_object()) throw InputError(f, 0, "qc", "expected an object or an array");
  for (auto it = qc.begin(); it != qc.end(); ++it) {
    const std::string key = "qc." + it.key();
    if (it.key() == "from_s" || it.key() == "horizon_s") continue;  // when and how long: context, not figures
    if (it.key() == "outages") {
      outage_metrics(*outages, sample, out);
      continue;
    }
    if (it->is_number()) {
      out.push_back(QcResult{it.key(), jnum(*it, f, key), std::nullopt, true, "", sample, ""});
    } else if (it->is_boolean()) {
      out.push_back(QcResult{it.key(), it->get<bool>() ? 1.0 : 0.0, std::nullopt, it->get<bool>(), "", sample,
                             "pass as stated in the result"});
    } else if (it->is_object() && it->contains("value")) {
      out.push_back(metric_from_object(it.key(), *it, f, key, sample));
    } else if (it->is_array() && !it->empty() && (*it)[0].is_object()) {
      from_array(*it, key, it.key() + ".");
    }
  }
  return out;
}

}  // namespace

std::string outage_metric(const std::string& set, double length_s, const std::string& field) {
  char len[32];
  std::snprintf(len, sizeof len, "%gs", length_s);
  return "outages." + set + "." + len + "." + field;
}

InMotionResult parse_inmotion_result(const std::string& text, const std::string& f) {
  const json j = parse_json_text(text, f);
  const DriveResult d = drive_result_from_json(j, f);  // the one codec: every key checked there
  InMotionResult r;
  r.device.serial = d.device.serial;
  r.device.model = d.device.model;
  r.recording_path = d.recording.path;
  r.recording_sha256 = d.recording.sha256;
  r.recording_uri = d.recording.uri.value_or("");
  r.recording_digest = d.recording.digest.value_or("");
  r.reference_system = d.reference_system;
  r.coefficients = stored_block(d.coefficients, f, "coefficients");
  if (d.correction) r.correction = stored_block(*d.correction, f, "correction");
  r.mounting_sigma_deg = {kUnknownSigma, kUnknownSigma, kUnknownSigma};
  if (d.mounting) {
    r.has_mounting = true;
    for (int i = 0; i < 3; ++i) {
      r.mounting_rpy_deg[static_cast<std::size_t>(i)] = d.mounting->value_deg(i);
      r.mounting_sigma_deg[static_cast<std::size_t>(i)] = d.mounting->sigma_deg(i);
    }
  }
  if (!d.consistency.is_null()) r.consistency_json = d.consistency.dump();
  if (!d.qc.is_null()) {
    r.qc = qc_metrics(d.qc, d.outages, f);
    r.qc_json = d.qc.dump();
  }
  r.determined_by = d.determined_by;
  r.result_json = j.dump();  // as given
  return r;
}

std::optional<DeterminedBy> parse_determined_by(const std::string& result_json, const std::string& file) {
  return determined_by_from_json(parse_json_text(result_json, file), file);
}

double max_difference(const SensorErrors& a, const SensorErrors& b) {
  double d = 0;
  for (const auto& name : coefficient_names()) {
    const double x = coefficient_value(a, name), y = coefficient_value(b, name);
    d = std::max(d, std::abs(x - y) / (1.0 + std::max(std::abs(x), std::abs(y))));
  }
  return d;
}

ImportOutcome import_inmotion(Store& store, const InMotionResult& r, const std::string& f,
                              std::optional<std::int64_t> parent) {
  constexpr double kTol = 1e-9;  // composition agreement (17-digit JSON, double arithmetic)
  ImportOutcome out;
  // Drawn once, before the transaction: a re-run after a lost reply to its COMMIT recognises the
  // run it stored (and does not call it "already imported").
  const std::string uid = new_uid();
  store.connection().write_transaction([&] {
    out = ImportOutcome{};
    const auto dev = store.find_device(r.device.serial);
    if (!dev)
      throw InputError(f, 0, "device.serial",
                       "unknown device '" + r.device.serial + "' (not in " + store.connection().path() +
                           "; store its bench calibration first)");
    if (dev->model != r.device.model)
      throw InputError(f, 0, "device.model",
                       "device " + r.device.serial + " is a " + dev->model + ", the result says " + r.device.model);
    // Which stored set did the fit start from?
    {  // The same result twice would store a second, identical set.
      auto q = store.connection().prepare(
          "SELECT r.id, COALESCE(r.uid, ''), s.id, s.version, s.source, s.parent_id FROM inmotion_runs r "
          "LEFT JOIN coefficient_sets s ON s.inmotion_run_id = r.id WHERE r.device_id = ? AND r.result_json = ?");
      q.bind(1, dev->id).bind(2, r.result_json);
      if (q.step()) {
        if (q.text(1) == uid) {  // this very import, committed before its reply was lost
          out.run_id = q.int64(0);
          out.set_id = q.int64(2);
          out.version = static_cast<int>(q.int64(3));
          out.source = source_from_string(q.text(4));
          out.parent_id = q.opt_int64(5);
          return;
        }
        throw std::runtime_error(f + ": already imported (in-motion run " + std::to_string(q.int64(0)) +
                                 "): nothing stored");
      }
    }
    if (parent) {
      const auto p = store.find_set(*parent);
      if (!p) throw InputError(f, 0, "parent", "no coefficient set " + std::to_string(*parent) + " in the database");
      if (p->device_id != dev->id)
        throw InputError(f, 0, "parent", "set " + std::to_string(*parent) + " is not a set of device " + r.device.serial);
      if (!r.correction)
        throw InputError(f, 0, "correction", "missing: needed to combine the result with parent set " +
                                                 std::to_string(*parent));
      const double d = max_difference(compose(p->errors, r.correction->errors), r.coefficients.errors);
      if (d > kTol)
        throw InputError(f, 0, "coefficients",
                         "not the composition of parent set " + std::to_string(*parent) +
                             " with \"correction\" (largest difference " + std::to_string(d) + ")");
      out.parent_id = *parent;
    } else if (r.correction && max_difference(r.correction->errors, r.coefficients.errors) > kTol) {
      auto sets = store.sets_of(dev->id);
      for (auto it = sets.rbegin(); it != sets.rend(); ++it) {
        if (it->status == SetStatus::revoked) continue;
        if (max_difference(compose(it->errors, r.correction->errors), r.coefficients.errors) <= kTol) {
          out.parent_id = it->id;
          break;
        }
      }
      if (!out.parent_id)
        out.note = "the fit started from a coefficient set that is not in the database; stored as in-motion "
                   "without a parent";
    }
    out.source = out.parent_id ? SetSource::combined : SetSource::in_motion;

    auto st = store.connection().prepare(
        "INSERT INTO inmotion_runs(device_id, recording_path, recording_sha256, reference_system, mounting_roll_deg, "
        "mounting_pitch_deg, mounting_yaw_deg, mounting_roll_sigma_deg, mounting_pitch_sigma_deg, "
        "mounting_yaw_sigma_deg, consistency_json, qc_json, result_json, created_at, uid) "
        "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, " + std::string(store.connection().now_sql()) + ", ?) RETURNING id");
    st.bind(1, dev->id).bind(2, r.recording_path).bind(3, r.recording_sha256).bind(4, r.reference_system);
    for (int i = 0; i < 3; ++i) {
      const auto k = static_cast<std::size_t>(i);
      if (r.has_mounting) st.bind(5 + i, r.mounting_rpy_deg[k]);
      else st.bind_null(5 + i);
      st.bind(8 + i, r.mounting_sigma_deg[k]);  // +inf → NULL
    }
    st.bind(11, r.consistency_json).bind(12, r.qc_json).bind(13, r.result_json).bind(14, uid);
    st.step();
    out.run_id = st.int64(0);
    store.audit_locked("inmotion_run", out.run_id, "create", "import " + f);
    store.insert_qc_locked(r.qc, std::nullopt, out.run_id);
    out.set_id = store.insert_set_locked(dev->id, out.source, r.coefficients.canonical_json, r.coefficients.errors,
                                         out.parent_id, std::nullopt, out.run_id, &out.version, uid + "/set");
  });
  return out;
}

}  // namespace calbench::db
