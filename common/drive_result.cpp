#include "common/drive_result.hpp"

#include <algorithm>
#include <cmath>

#include "common/input_error.hpp"
#include "common/json_fields.hpp"

namespace calbench {
namespace {
using nlohmann::json;

constexpr const char* kFormatPrefix = "calbench-inmotion-result/";

// The typed top-level keys; every other key goes to DriveResult::extra.
constexpr const char* kTyped[] = {"format",       "device",           "recording",     "reference_system", "window_s",
                                  "observations", "smoothed",         "coefficients",  "correction",       "mounting_rpy_deg",
                                  "determined_by", "priors",          "consistency",   "qc"};
constexpr const char* kRecordingTyped[] = {"path", "sha256", "sha256_reference", "sha256_meta", "sha256_gnss", "format", "device",
                                           "uri", "digest_sha256"};

bool is_sha256_hex(const std::string& s) {
  return s.size() == 64 && s.find_first_not_of("0123456789abcdefABCDEF") == std::string::npos;
}

template <std::size_t N>
bool one_of(const std::string& k, const char* const (&names)[N]) {
  return std::any_of(std::begin(names), std::end(names), [&](const char* n) { return k == n; });
}

std::optional<std::string> opt_string(const json& o, const char* k, const std::string& f, const std::string& key) {
  const auto it = o.find(k);
  if (it == o.end() || it->is_null()) return std::nullopt;
  return jstr(*it, f, key.empty() ? std::string(k) : key + "." + k);
}

DeviceId device_of(const json& d, const std::string& f, const std::string& key, bool model_required) {
  DeviceId id{"", ""};  // no model stated: none (not DeviceId's default)
  if (!d.is_object()) throw InputError(f, 0, key, std::string("expected an object {model, serial}, got ") + d.type_name());
  id.serial = jstr(jreq(d, "serial", f, key), f, key + ".serial");
  if (model_required || d.contains("model")) id.model = jstr(jreq(d, "model", f, key), f, key + ".model");
  return id;
}

std::optional<double> opt_number(const json& o, const char* k, const std::string& f, const std::string& key) {
  const auto it = o.find(k);
  if (it == o.end() || it->is_null()) return std::nullopt;
  return jnum(*it, f, key + "." + k);
}

std::optional<long> opt_count(const json& o, const char* k, const std::string& f, const std::string& key) {
  const auto v = opt_number(o, k, f, key);
  if (v && (*v < 0 || *v != std::floor(*v) || *v > 1e15))
    throw InputError(f, 0, key + "." + k, "expected a whole number of epochs >= 0");
  return v ? std::optional<long>(static_cast<long>(*v)) : std::nullopt;
}

std::map<std::string, double> numbers_by_name(const json& o, const std::string& f, const std::string& key) {
  std::map<std::string, double> out;
  if (!o.is_object()) throw InputError(f, 0, key, "expected an object");
  for (auto it = o.begin(); it != o.end(); ++it)
    if (!it->is_null()) out[it.key()] = jnum(*it, f, key + "." + it.key());
  return out;
}

const json& array_at(const json& o, const char* k, const std::string& f, const std::string& key) {
  static const json empty = json::array();
  const auto it = o.find(k);
  if (it == o.end()) return empty;
  if (!it->is_array()) throw InputError(f, 0, key + "." + k, "expected an array");
  return *it;
}

// A coefficient block: the spec schema; "format"/"device" may be omitted (then they are those of
// the result) and, when present, must agree with it. Errors name the key under the block.
CoefficientSet coefficient_block(const json& j, const DeviceId& dev, const std::string& f, const std::string& name) {
  if (!j.is_object()) throw InputError(f, 0, name, "expected an object in the coefficients.json form");
  json c = j;
  if (!c.contains("format")) c["format"] = kCoefficientsFormat;
  if (!c.contains("device")) c["device"] = {{"model", dev.model}, {"serial", dev.serial}};
  CoefficientSet s;
  try {
    s = coefficients_from_json(c, f);
  } catch (const InputError& e) {
    throw InputError(f, e.line(), e.field().empty() ? name : name + "." + e.field(), e.message());
  }
  if (s.device.serial != dev.serial)
    throw InputError(f, 0, name + ".device.serial",
                     "serial '" + s.device.serial + "' does not match the result's device '" + dev.serial + "'");
  if (s.device.model != dev.model)
    throw InputError(f, 0, name + ".device.model",
                     "model '" + s.device.model + "' does not match the result's device '" + dev.model + "'");
  return s;
}

DriveMounting mounting_of(const json& j, const std::string& f) {
  const json& m = j["mounting_rpy_deg"];
  DriveMounting out;
  if (m.is_array()) {
    out.value_deg = jvec3(m, f, "mounting_rpy_deg");
  } else if (m.is_object()) {
    const char* vk = m.contains("value") ? "value" : m.contains("rpy") ? "rpy" : "value";
    out.value_deg = jvec3(jreq(m, vk, f, "mounting_rpy_deg"), f, std::string("mounting_rpy_deg.") + vk);
    if (m.contains("sigma")) out.sigma_deg = jsigma3(m["sigma"], f, "mounting_rpy_deg.sigma");
    for (auto it = m.begin(); it != m.end(); ++it)
      if (it.key() != vk && it.key() != "sigma") out.extra[it.key()] = it.value();
  } else {
    throw InputError(f, 0, "mounting_rpy_deg", "expected [roll, pitch, yaw] or {\"value\": [...], \"sigma\": [...]}");
  }
  for (const char* k : {"mounting_rpy_sigma_deg", "sigma_mounting_rpy_deg"})
    if (j.contains(k)) out.sigma_deg = jsigma3(j[k], f, k);
  return out;
}

std::optional<double> opt_sigma(const json& o, const char* k, const std::string& f, const std::string& key) {
  if (!o.contains(k) || o[k].is_null()) return std::nullopt;
  const double v = jnum(o[k], f, key + "." + k);
  if (v < 0) throw InputError(f, 0, key + "." + k, "cannot be negative");
  return v;
}

// One entry of determined_by.coefficients / .mounting. `checked`: the figures must agree with each
// other and with the stage (the rule fit drive applies): a hand-edited stage or σ would otherwise
// reach the report as the drive's finding.
CoefficientStage stage_of(const json& c, const std::string& f, const std::string& key, bool checked) {
  if (!c.is_object()) throw InputError(f, 0, key, "expected an object");
  CoefficientStage st;
  if (!c.contains("stage") || !c["stage"].is_string()) throw InputError(f, 0, key + ".stage", "expected a string");
  st.stage = c["stage"].get<std::string>();
  if (st.stage != "bench" && st.stage != "drive" && st.stage != "both" && st.stage != "prior")
    throw InputError(f, 0, key + ".stage", "'" + st.stage + "' is not bench, drive, both or prior");
  st.parent_sigma = opt_sigma(c, "parent_sigma", f, key);
  st.prior_sigma = opt_sigma(c, "prior_sigma", f, key);
  st.posterior_sigma = opt_sigma(c, "posterior_sigma", f, key);
  st.ratio = opt_sigma(c, "ratio", f, key);
  st.drive_share = opt_sigma(c, "drive_share", f, key);
  if (st.drive_share && (*st.drive_share > 1 + 1e-9 || *st.drive_share < -1e-9))
    throw InputError(f, 0, key + ".drive_share", "expected 0 … 1");
  if (!checked) return st;
  if (st.prior_sigma && st.posterior_sigma) {
    if (*st.posterior_sigma > *st.prior_sigma * (1 + 1e-3))
      throw InputError(f, 0, key + ".posterior_sigma", "larger than prior_sigma: a Kalman update cannot widen a constant");
    if (st.drive_share && *st.prior_sigma > 0) {
      const double q = *st.posterior_sigma / *st.prior_sigma, share = 1 - q * q;
      if (std::abs(share - *st.drive_share) > 1e-3)
        throw InputError(f, 0, key + ".drive_share", "does not equal 1 - (posterior_sigma/prior_sigma)^2");
    }
  }
  if (st.drive_share) {
    const double sh = *st.drive_share;
    const bool ok = st.stage == "drive" ? sh > 0.8 - 1e-9 : st.stage == "both" ? sh >= 0.2 - 1e-9 && sh <= 0.8 + 1e-9 : sh < 0.2 + 1e-9;
    if (!ok) throw InputError(f, 0, key + ".stage", "'" + st.stage + "' does not follow from drive_share " + std::to_string(sh));
  }
  return st;
}

json stage_json(const CoefficientStage& s) {
  const auto opt = [](const std::optional<double>& v) { return v ? json(*v) : json(nullptr); };
  return {{"parent_sigma", opt(s.parent_sigma)}, {"prior_sigma", opt(s.prior_sigma)}, {"posterior_sigma", opt(s.posterior_sigma)},
          {"ratio", opt(s.ratio)},               {"drive_share", opt(s.drive_share)}, {"stage", s.stage}};
}

json determined_by_json(const DeterminedBy& d) {
  json c = json::object(), m = json::object();
  json count = {{"bench", 0}, {"drive", 0}, {"both", 0}, {"prior", 0}};
  for (const auto& [name, s] : d.coefficients) {
    c[name] = stage_json(s);
    count[s.stage] = count[s.stage].get<int>() + 1;
  }
  for (const auto& [name, s] : d.mounting) m[name] = stage_json(s);
  json j = {{"rule", d.rule}, {"count", count}, {"coefficients", c}};
  if (!d.mounting.empty()) j["mounting"] = m;
  return j;
}

}  // namespace

// "consistency" (object form: observation → figures); the older array form carries no figures read.
std::map<std::string, NisConsistency> nis_consistency_from_json(const json& c, const std::string& f) {
  std::map<std::string, NisConsistency> out;
  if (!c.is_object()) return out;
  for (auto it = c.begin(); it != c.end(); ++it) {
    const std::string key = "consistency." + it.key();
    if (!it->is_object()) throw InputError(f, 0, key, "expected an object");
    NisConsistency n;
    n.equation = opt_string(*it, "equation", f, key);
    n.epochs = opt_count(*it, "epochs", f, key);
    n.rejected = opt_count(*it, "rejected", f, key);
    n.forced = opt_count(*it, "forced", f, key);
    n.mean_nis = opt_number(*it, "mean_nis", f, key);
    n.expected_nis = opt_number(*it, "expected_nis", f, key);
    n.fraction_within_95pct = opt_number(*it, "fraction_within_95pct", f, key);
    out[it.key()] = n;
  }
  return out;
}

namespace {
std::vector<double> numbers_or_null(const json& a, const std::string& f, const std::string& key) {
  if (!a.is_array()) throw InputError(f, 0, key, "expected an array");
  std::vector<double> out;
  for (std::size_t i = 0; i < a.size(); ++i)
    out.push_back(a[i].is_null() ? std::nan("") : jnum(a[i], f, key + "[" + std::to_string(i) + "]"));
  return out;
}
}  // namespace

namespace {
bool jbool(const json& v, const std::string& f, const std::string& key) {
  if (!v.is_boolean()) throw InputError(f, 0, key, "expected true or false");
  return v.get<bool>();
}
}  // namespace

void read_typed_sections(DriveResult& r, const std::string& f) {
  r.nis = nis_consistency_from_json(r.consistency, f);
  r.cpe = cpe_qc_from_json(r.qc, f);
  r.outages.reset();
  if (r.qc.is_object() && r.qc.contains("outages")) r.outages = outage_qc_from_json(r.qc["outages"], f);
  const json& x = r.extra;
  r.lever_arm.reset();
  if (const auto l = x.find("lever_arm_m"); l != x.end() && !l->is_null()) {
    const std::string k = "lever_arm_m";
    LeverArmEstimate e;
    e.value = jvec3(jreq(*l, "value", f, k), f, k + ".value");
    e.sigma = jvec3(jreq(*l, "sigma", f, k), f, k + ".sigma");
    e.nominal = jvec3(jreq(*l, "nominal", f, k), f, k + ".nominal");
    e.correction = jvec3(jreq(*l, "correction", f, k), f, k + ".correction");
    e.prior = jnum(jreq(*l, "prior", f, k), f, k + ".prior");
    const json& o = jreq(*l, "observable", f, k);
    if (!o.is_array() || o.size() != 3) throw InputError(f, 0, k + ".observable", "expected an array of 3 booleans");
    for (std::size_t i = 0; i < 3; ++i) e.observable[i] = jbool(o[i], f, k + ".observable[" + std::to_string(i) + "]");
    r.lever_arm = e;
  }
  r.time_offset.reset();
  if (const auto t = x.find("time_offset_s"); t != x.end() && !t->is_null()) {
    const std::string k = "time_offset_s";
    TimeOffsetEstimate e;
    e.value = jnum(jreq(*t, "value", f, k), f, k + ".value");
    e.sigma = jnum(jreq(*t, "sigma", f, k), f, k + ".sigma");
    e.prior = jnum(jreq(*t, "prior", f, k), f, k + ".prior");
    e.observable = jbool(jreq(*t, "observable", f, k), f, k + ".observable");
    r.time_offset = e;
  }
  r.adaptive_noise.reset();
  if (const auto a = x.find("adaptive_noise"); a != x.end() && !a->is_null()) {
    const std::string k = "adaptive_noise";
    AdaptiveNoiseSummary e;  // older results may lack a figure: none scaled
    e.scale_max = opt_number(*a, "scale_max", f, k).value_or(1);
    e.scale_end = opt_number(*a, "scale_end", f, k).value_or(1);
    const double n = opt_number(*a, "increases", f, k).value_or(0);
    if (n < 0 || n != std::floor(n)) throw InputError(f, 0, k + ".increases", "expected a whole number >= 0");
    e.increases = static_cast<long>(n);
    r.adaptive_noise = e;
  }
  r.effects.reset();
  if (const auto fx = x.find("effects"); fx != x.end() && !fx->is_null()) {
    const std::string k = "effects";
    EffectsUse e;
    const json& ap = array_at(*fx, "applied", f, k);
    for (std::size_t i = 0; i < ap.size(); ++i) e.applied.push_back(jstr(ap[i], f, k + ".applied[" + std::to_string(i) + "]"));
    const json& ig = array_at(*fx, "ignored", f, k);
    for (std::size_t i = 0; i < ig.size(); ++i) {
      const std::string ik = k + ".ignored[" + std::to_string(i) + "]";
      e.ignored.emplace_back(jstr(jreq(ig[i], "key", f, ik), f, ik + ".key"), jstr(jreq(ig[i], "reason", f, ik), f, ik + ".reason"));
    }
    e.time_offset_s = opt_number(*fx, "time_offset_s", f, k);
    r.effects = e;
  }
}

CpeQc cpe_qc_from_json(const json& qc, const std::string& f) {
  CpeQc q;
  if (!qc.is_object()) return q;
  q.from_s = opt_number(qc, "from_s", f, "qc");
  q.horizon_s = opt_number(qc, "horizon_s", f, "qc");
  q.sample = opt_string(qc, "sample", f, "qc");
  const json& sets = array_at(qc, "sets", f, "qc");
  for (std::size_t i = 0; i < sets.size(); ++i) {
    const std::string sk = "qc.sets[" + std::to_string(i) + "]";
    if (!sets[i].is_object()) throw InputError(f, 0, sk, "expected an object");
    CpeSet s;
    s.name = opt_string(sets[i], "name", f, sk);
    s.final_cpe_m = opt_number(sets[i], "final_cpe_m", f, sk);
    s.max_cpe_m = opt_number(sets[i], "max_cpe_m", f, sk);
    if (const auto at = sets[i].find("cpe_m_at"); at != sets[i].end()) {
      if (!at->is_object()) throw InputError(f, 0, sk + ".cpe_m_at", "expected an object");
      for (auto it = at->begin(); it != at->end(); ++it)
        s.cpe_m_at[it.key()] = it->is_null() ? std::nan("") : jnum(*it, f, sk + ".cpe_m_at." + it.key());
    }
    if (const auto ser = sets[i].find("cpe_series"); ser != sets[i].end()) {
      if (!ser->is_object()) throw InputError(f, 0, sk + ".cpe_series", "expected an object");
      if (ser->contains("t_s")) s.series_t_s = numbers_or_null((*ser)["t_s"], f, sk + ".cpe_series.t_s");
      if (ser->contains("cpe_m")) s.series_cpe_m = numbers_or_null((*ser)["cpe_m"], f, sk + ".cpe_series.cpe_m");
    }
    q.sets.push_back(std::move(s));
  }
  if (const auto ser = qc.find("series"); ser != qc.end() && ser->is_object() && ser->contains("t_s")) {
    for (auto it = ser->begin(); it != ser->end(); ++it) {
      std::vector<double> v = numbers_or_null(*it, f, "qc.series." + it.key());
      if (it.key() == "t_s") q.series_t_s = std::move(v);
      else q.series[it.key()] = std::move(v);
    }
  }
  return q;
}

OutageQc outage_qc_from_json(const json& o, const std::string& f) {
  const std::string key = "qc.outages";
  if (!o.is_object()) throw InputError(f, 0, key, "expected an object");
  OutageQc q;
  q.sample = opt_string(o, "sample", f, key);
  q.aided_by = opt_string(o, "aided_by", f, key);
  q.error = opt_string(o, "error", f, key);
  q.fix_sigma_h_m = opt_number(o, "fix_sigma_h_m", f, key);
  const json& np = array_at(o, "not_placed", f, key);
  for (std::size_t i = 0; i < np.size(); ++i) {
    const std::string k = key + ".not_placed[" + std::to_string(i) + "]";
    if (!np[i].is_object()) throw InputError(f, 0, k, "expected an object");
    q.not_placed.push_back(opt_string(np[i], "reason", f, k).value_or(""));
  }
  const json& sets = array_at(o, "sets", f, key);
  for (std::size_t i = 0; i < sets.size(); ++i) {
    const std::string sk = key + ".sets[" + std::to_string(i) + "]";
    if (!sets[i].is_object()) throw InputError(f, 0, sk, "expected an object");
    OutageSetFigures s;
    s.name = jstr(jreq(sets[i], "name", f, sk), f, sk + ".name");
    if (!sets[i].contains("per_length") || !sets[i]["per_length"].is_array())
      throw InputError(f, 0, sk + ".per_length", "expected an array");
    const json& pl = sets[i]["per_length"];
    for (std::size_t k = 0; k < pl.size(); ++k) {
      const std::string pk = sk + ".per_length[" + std::to_string(k) + "]";
      if (!pl[k].is_object() || !pl[k].contains("length_s")) throw InputError(f, 0, pk, "expected an object with length_s");
      OutageLengthFigures l;
      l.length_s = jnum(pl[k]["length_s"], f, pk + ".length_s");
      l.count = opt_number(pl[k], "count", f, pk);
      l.median_max_m = opt_number(pl[k], "median_max_m", f, pk);
      l.max_max_m = opt_number(pl[k], "max_max_m", f, pk);
      l.median_end_m = opt_number(pl[k], "median_end_m", f, pk);
      l.max_end_m = opt_number(pl[k], "max_end_m", f, pk);
      s.per_length.push_back(l);
    }
    q.sets.push_back(std::move(s));
  }
  const json& list = array_at(o, "outages", f, key);
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string ok = key + ".outages[" + std::to_string(i) + "]";
    if (!list[i].is_object()) throw InputError(f, 0, ok, "expected an object");
    OutageRunFigures e;
    e.start_s = opt_number(list[i], "start_s", f, ok);
    e.length_s = opt_number(list[i], "length_s", f, ok);
    e.fixes = opt_number(list[i], "fixes", f, ok);
    if (list[i].contains("max_m")) e.max_m = numbers_by_name(list[i]["max_m"], f, ok + ".max_m");
    if (list[i].contains("end_m")) e.end_m = numbers_by_name(list[i]["end_m"], f, ok + ".end_m");
    q.outages.push_back(std::move(e));
  }
  return q;
}


bool is_drive_result(const json& j) {
  if (!j.is_object()) return false;
  const auto f = j.find("format");
  if (f != j.end() && f->is_string()) return f->get<std::string>().rfind(kFormatPrefix, 0) == 0;
  return f == j.end() && j.contains("coefficients");
}

std::optional<DeterminedBy> determined_by_from_json(const json& j, const std::string& f) {
  if (!j.is_object() || !j.contains("determined_by") || j["determined_by"].is_null()) return std::nullopt;
  const json& d = j["determined_by"];
  if (!d.is_object()) throw InputError(f, 0, "determined_by", "expected an object {\"rule\", \"coefficients\"}");
  DeterminedBy out;
  if (d.contains("rule")) out.rule = jstr(d["rule"], f, "determined_by.rule");
  if (!d.contains("coefficients") || !d["coefficients"].is_object())
    throw InputError(f, 0, "determined_by.coefficients", "expected an object keyed by coefficient name");
  const auto& names = coefficient_names();
  for (auto it = d["coefficients"].begin(); it != d["coefficients"].end(); ++it) {
    const std::string key = "determined_by.coefficients." + it.key();
    if (std::find(names.begin(), names.end(), it.key()) == names.end())
      throw InputError(f, 0, key, "unknown coefficient (expected gyro.bias.x … accel.M.zz)");
    out.coefficients[it.key()] = stage_of(*it, f, key, true);
  }
  if (d.contains("mounting") && !d["mounting"].is_null()) {
    if (!d["mounting"].is_object()) throw InputError(f, 0, "determined_by.mounting", "expected an object keyed by axis");
    for (auto it = d["mounting"].begin(); it != d["mounting"].end(); ++it)
      out.mounting[it.key()] = stage_of(*it, f, "determined_by.mounting." + it.key(), false);
  }
  return out;
}

DriveResult drive_result_from_json(const json& j, const std::string& f) {
  if (!j.is_object()) throw InputError(f, 1, "", "expected a JSON object");
  DriveResult r;
  if (j.contains("format")) {
    r.format = jstr(j["format"], f, "format");
    if (r.format != kDriveResultFormat)
      throw InputError(f, 0, "format",
                       "unsupported RESULT.json format '" + r.format + "' (expected " + kDriveResultFormat + ")");
  }
  // device: {model, serial}, or (older results) the serial alone
  if (!j.contains("device")) throw InputError(f, 0, "device", "missing key");
  if (j["device"].is_string()) r.device = DeviceId{"", j["device"].get<std::string>()};
  else r.device = device_of(j["device"], f, "device", false);
  if (r.device.serial.empty()) throw InputError(f, 0, "device.serial", "empty serial number");
  // recording
  const json& rec = jreq(j, "recording", f, "");
  if (!rec.is_object()) throw InputError(f, 0, "recording", "expected an object");
  r.recording.path = jstr(jreq(rec, "path", f, "recording"), f, "recording.path");
  r.recording.sha256 = jstr(jreq(rec, "sha256", f, "recording"), f, "recording.sha256");
  // The unit that drove: a result of another unit's drive is never filed under this one.
  if (rec.contains("device") && rec["device"].is_object()) {
    r.recording.device = device_of(rec["device"], f, "recording.device", false);
    const std::string& rs = r.recording.device->serial;
    if (!rs.empty() && rs != r.device.serial)
      throw InputError(f, 0, "recording.device.serial",
                       "the drive was recorded by unit '" + rs + "', the result is filed under unit '" + r.device.serial + "'");
  }
  if (!is_sha256_hex(r.recording.sha256))
    throw InputError(f, 0, "recording.sha256", "expected 64 hexadecimal digits");
  r.recording.sha256_reference = opt_string(rec, "sha256_reference", f, "recording");
  r.recording.sha256_meta = opt_string(rec, "sha256_meta", f, "recording");
  r.recording.sha256_gnss = opt_string(rec, "sha256_gnss", f, "recording");
  r.recording.format = opt_string(rec, "format", f, "recording");
  r.recording.uri = opt_string(rec, "uri", f, "recording");
  if (r.recording.uri && r.recording.uri->rfind("file://", 0) != 0)
    throw InputError(f, 0, "recording.uri", "expected file://HOST/absolute/path, got '" + *r.recording.uri + "'");
  r.recording.digest = opt_string(rec, "digest_sha256", f, "recording");
  if (r.recording.digest && !is_sha256_hex(*r.recording.digest))
    throw InputError(f, 0, "recording.digest_sha256", "expected 64 hexadecimal digits");
  for (auto it = rec.begin(); it != rec.end(); ++it)
    if (!one_of(it.key(), kRecordingTyped) || (it.key() == "device" && !r.recording.device)) r.recording.extra[it.key()] = it.value();
  // the reference system: a text (older results: "reference", or recording.reference, any JSON)
  for (const json* ref : {j.contains("reference_system") ? &j["reference_system"] : nullptr,
                          j.contains("reference") ? &j["reference"] : nullptr,
                          rec.contains("reference") ? &rec["reference"] : nullptr})
    if (ref && r.reference_system.empty()) r.reference_system = ref->is_string() ? ref->get<std::string>() : ref->dump();
  if (j.contains("window_s") && !j["window_s"].is_null()) {
    const json& w = j["window_s"];
    if (!w.is_array() || w.size() != 2) throw InputError(f, 0, "window_s", "expected [T0, T1] in seconds");
    r.window_s = std::make_pair(jnum(w[0], f, "window_s[0]"), jnum(w[1], f, "window_s[1]"));
  }
  r.observations = opt_string(j, "observations", f, "");
  if (j.contains("smoothed") && !j["smoothed"].is_null()) {
    if (!j["smoothed"].is_boolean()) throw InputError(f, 0, "smoothed", "expected true or false");
    r.smoothed = j["smoothed"].get<bool>();
  }
  r.coefficients = coefficient_block(jreq(j, "coefficients", f, ""), r.device, f, "coefficients");
  if (j.contains("correction") && !j["correction"].is_null())
    r.correction = coefficient_block(j["correction"], r.device, f, "correction");
  if (j.contains("mounting_rpy_deg") && !j["mounting_rpy_deg"].is_null()) r.mounting = mounting_of(j, f);
  r.determined_by = determined_by_from_json(j, f);
  if (j.contains("priors") && !j["priors"].is_null()) {
    if (!j["priors"].is_object()) throw InputError(f, 0, "priors", "expected an object");
    r.priors = j["priors"];
    if (const auto m = r.priors.find("mode"); m != r.priors.end() && m->is_string()) r.priors_mode = m->get<std::string>();
    if (const auto c = r.priors.find("device_class"); c != r.priors.end() && c->is_string())
      r.priors_device_class = c->get<std::string>();
  }
  if (j.contains("consistency")) {
    if (!j["consistency"].is_object() && !j["consistency"].is_array())
      throw InputError(f, 0, "consistency", "expected an object");
    r.consistency = j["consistency"];
  }
  if (j.contains("qc") && !j["qc"].is_null()) {
    if (!j["qc"].is_object() && !j["qc"].is_array()) throw InputError(f, 0, "qc", "expected an object or an array");
    r.qc = j["qc"];
  }
  for (auto it = j.begin(); it != j.end(); ++it)
    if (!one_of(it.key(), kTyped)) r.extra[it.key()] = it.value();
  read_typed_sections(r, f);
  return r;
}

json drive_result_to_json(const DriveResult& r) {
  json j = r.extra.is_object() ? r.extra : json::object();
  if (!r.format.empty()) j["format"] = r.format;
  j["device"] = {{"model", r.device.model}, {"serial", r.device.serial}};
  json rec = r.recording.extra.is_object() ? r.recording.extra : json::object();
  rec["path"] = r.recording.path;
  rec["sha256"] = r.recording.sha256;
  rec["sha256_reference"] = r.recording.sha256_reference ? json(*r.recording.sha256_reference) : json(nullptr);
  if (r.recording.sha256_meta) rec["sha256_meta"] = *r.recording.sha256_meta;
  if (r.recording.sha256_gnss) rec["sha256_gnss"] = *r.recording.sha256_gnss;
  if (r.recording.format) rec["format"] = *r.recording.format;
  if (r.recording.device) rec["device"] = {{"model", r.recording.device->model}, {"serial", r.recording.device->serial}};
  // A result written now says where its recording is (older results read without it are never rewritten).
  if (!r.recording.uri || !r.recording.digest)
    throw InputError("RESULT.json", 0, !r.recording.uri ? "recording.uri" : "recording.digest_sha256",
                     "a result is written with its recording's URI and digest (issue 35 item 8)");
  rec["uri"] = *r.recording.uri;
  rec["digest_sha256"] = *r.recording.digest;
  j["recording"] = rec;
  if (!r.reference_system.empty()) j["reference_system"] = r.reference_system;
  if (r.window_s) j["window_s"] = {r.window_s->first, r.window_s->second};
  if (r.observations) j["observations"] = *r.observations;
  if (r.smoothed) j["smoothed"] = *r.smoothed;
  j["coefficients"] = coefficients_to_json(r.coefficients);
  if (r.correction) j["correction"] = coefficients_to_json(*r.correction);
  if (r.mounting) {
    json m = r.mounting->extra.is_object() ? r.mounting->extra : json::object();
    m["value"] = to_json(r.mounting->value_deg);
    m["sigma"] = sigma_json(r.mounting->sigma_deg);
    j["mounting_rpy_deg"] = m;
  }
  if (r.determined_by) j["determined_by"] = determined_by_json(*r.determined_by);
  if (!r.priors.is_null()) j["priors"] = r.priors;
  if (!r.consistency.is_null()) j["consistency"] = r.consistency;
  if (!r.qc.is_null()) j["qc"] = r.qc;
  return j;
}

}  // namespace calbench
