#include "bench/diagnose/effects_json.hpp"

#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "calibration/effects/effect_registry.hpp"
#include "common/number_parse.hpp"

namespace calbench {

namespace {

nlohmann::json arr2(const Eigen::Vector2d& v) { return nlohmann::json::array({v(0), v(1)}); }
Eigen::Vector2d jvec2(const nlohmann::json& v, const std::string& f, const std::string& key) {
  if (!v.is_array() || v.size() != 2) throw InputError(f, 0, key, "expected an array of 2 numbers");
  return {jnum(v[0], f, key + "[0]"), jnum(v[1], f, key + "[1]")};
}
Vec3 opt3(const nlohmann::json& o, const char* k, const std::string& f, const std::string& pre) {
  return o.contains(k) ? jvec3(o[k], f, pre + "." + k) : Vec3::Zero();
}
Vec3 optsig3(const nlohmann::json& o, const char* k, const std::string& f, const std::string& pre) {
  return o.contains(k) ? jsigma3(o[k], f, pre + "." + k) : Vec3::Zero();
}

const char* const kSigmaKey[2] = {"gyro_sigma", "accel_sigma"};
const char* const kSensorName[2] = {"gyro", "accel"};

// Values of a vector-shaped effect (its parameters on its sensor) as Eigen vectors of n.
Eigen::VectorXd get_vec(const EffectSpec& x, const EffectTerms& e) {
  Eigen::VectorXd v(x.nparams);
  for (int p = 0; p < x.nparams; ++p) v(p) = effect_value(x, e, x.sensor, -1, p);
  return v;
}
void set_vec(const EffectSpec& x, EffectTerms& e, const Eigen::VectorXd& v) {
  for (int p = 0; p < x.nparams; ++p) *effect_param(x, e, x.sensor, -1, p) = v(p);
}
Vec3 get_axes(const EffectSpec& x, const EffectTerms& e, int sensor) {
  return {effect_value(x, e, sensor, 0, 0), effect_value(x, e, sensor, 1, 0), effect_value(x, e, sensor, 2, 0)};
}
void set_axes(const EffectSpec& x, EffectTerms& e, int sensor, const Vec3& v) {
  for (int a = 0; a < 3; ++a) *effect_param(x, e, sensor, a, 0) = v(a);
}
Mat3 get_mat(const EffectSpec& x, const EffectTerms& e) {
  Mat3 m;
  for (int a = 0; a < 3; ++a)
    for (int p = 0; p < 3; ++p) m(a, p) = effect_value(x, e, x.sensor, a, p);
  return m;
}
void set_mat(const EffectSpec& x, EffectTerms& e, const Mat3& m) {
  for (int a = 0; a < 3; ++a)
    for (int p = 0; p < 3; ++p) *effect_param(x, e, x.sensor, a, p) = m(a, p);
}

// The rows of an axis_rows effect on one sensor: 3 × nparams, as nested arrays.
nlohmann::json get_rows(const EffectSpec& x, const EffectTerms& e, int sensor, bool sigma) {
  nlohmann::json r = nlohmann::json::array();
  for (int a = 0; a < 3; ++a) {
    nlohmann::json row = nlohmann::json::array();
    for (int p = 0; p < x.nparams; ++p) {
      const double v = effect_value(x, e, sensor, a, p);
      if (sigma && !(std::isfinite(v) && v >= 0)) row.push_back(nullptr);
      else row.push_back(v);
    }
    r.push_back(row);
  }
  return r;
}
void set_rows(const EffectSpec& x, EffectTerms& e, int sensor, const nlohmann::json& v, const std::string& f,
              const std::string& key, bool sigma) {
  const std::string shape = "expected 3 rows of " + std::to_string(x.nparams) + " numbers";
  if (!v.is_array() || v.size() != 3) throw InputError(f, 0, key, shape);
  for (int a = 0; a < 3; ++a) {
    const nlohmann::json& row = v[static_cast<std::size_t>(a)];
    if (!row.is_array() || static_cast<int>(row.size()) != x.nparams) throw InputError(f, 0, key, shape);
    for (int p = 0; p < x.nparams; ++p) {
      const std::string k = key + "[" + std::to_string(a) + "][" + std::to_string(p) + "]";
      const nlohmann::json& c = row[static_cast<std::size_t>(p)];
      if (sigma && c.is_null()) *effect_param(x, e, sensor, a, p) = std::numeric_limits<double>::infinity();
      else *effect_param(x, e, sensor, a, p) = jnum(c, f, k);
    }
  }
}
// The column names of an axis_rows effect ("xx", …; the other-axes rows: "next", "previous").
nlohmann::json row_columns(const EffectSpec& x) {
  nlohmann::json c = nlohmann::json::array();
  for (int p = 0; p < x.nparams; ++p)
    c.push_back(x.components_other_axes ? (p == 0 ? "next axis (x: y, y: z, z: x)" : "previous axis (x: z, y: x, z: y)")
                                        : effect_component_name(x, 0, p));
  return c;
}

// The JSON form of one effect, by the shape of its parameters (docs/diagnosis.md).
void read_effect(const EffectSpec& x, const nlohmann::json& o, const std::string& f, EffectTerms& e, EffectTerms& s) {
  const std::string key = x.key;
  const std::string vk = x.json_value[0] ? x.json_value[0] : "";
  switch (x.shape) {
    case EffectShape::triad_axis:
      if (x.json_t0 && o.contains("t0_c")) e.t0_c = jnum(o["t0_c"], f, key + ".t0_c");
      for (int k = 0; k < 2; ++k)
        if (effect_allows_sensor(x, k)) {
          set_axes(x, e, k, opt3(o, x.json_value[k], f, key));
          set_axes(x, s, k, optsig3(o, kSigmaKey[k], f, key));
        }
      break;
    case EffectShape::axis_rows:
      for (int k = 0; k < 2; ++k)
        if (effect_allows_sensor(x, k)) {
          if (o.contains(x.json_value[k])) set_rows(x, e, k, o[x.json_value[k]], f, key + "." + x.json_value[k], false);
          if (o.contains(kSigmaKey[k])) set_rows(x, s, k, o[kSigmaKey[k]], f, key + "." + kSigmaKey[k], true);
        }
      break;
    case EffectShape::gyro_matrix:
      set_mat(x, e, jmat3(jreq(o, vk.c_str(), f, key), f, key + "." + vk));
      if (o.contains("sigma")) set_mat(x, s, jsigmamat3(o["sigma"], f, key + ".sigma"));
      break;
    case EffectShape::vector:
      if (x.nparams == 1) {
        *effect_param(x, e, x.sensor, -1, 0) = jnum(jreq(o, vk.c_str(), f, key), f, key + "." + vk);
        if (o.contains("sigma") && !o["sigma"].is_null()) *effect_param(x, s, x.sensor, -1, 0) = jnum(o["sigma"], f, key + ".sigma");
      } else if (x.nparams == 2) {
        set_vec(x, e, jvec2(jreq(o, vk.c_str(), f, key), f, key + "." + vk));
        if (o.contains("sigma")) set_vec(x, s, jvec2(o["sigma"], f, key + ".sigma"));
      } else {
        set_vec(x, e, jvec3(jreq(o, vk.c_str(), f, key), f, key + "." + vk));
        set_vec(x, s, optsig3(o, "sigma", f, key));
      }
      break;
    case EffectShape::noise:
      for (int k = 0; k < 2; ++k) {
        if (!effect_allows_sensor(x, k)) continue;
        const std::string sk = x.json_value[k], tk = std::string(kSensorName[k]) + "_tau_s";
        if (o.contains(sk)) *effect_param(x, e, k, -1, 0) = jnum(o[sk], f, key + "." + sk);
        if (o.contains(tk)) *effect_param(x, e, k, -1, 1) = jnum(o[tk], f, key + "." + tk);
      }
      break;
  }
}

nlohmann::json write_effect(const EffectSpec& x, const EffectTerms& e, const EffectTerms& s) {
  nlohmann::json o = nlohmann::json::object();
  const std::string vk = x.json_value[0] ? x.json_value[0] : "";
  switch (x.shape) {
    case EffectShape::triad_axis:
      if (x.json_t0) o["t0_c"] = e.t0_c;
      for (int k = 0; k < 2; ++k)
        if (effect_allows_sensor(x, k)) {
          o[x.json_value[k]] = to_json(get_axes(x, e, k));
          o[kSigmaKey[k]] = sigma_json(get_axes(x, s, k));
        }
      break;
    case EffectShape::gyro_matrix: o = {{vk, to_json(get_mat(x, e))}, {"sigma", sigma_json(get_mat(x, s))}}; break;
    case EffectShape::axis_rows:
      o["columns"] = row_columns(x);
      for (int k = 0; k < 2; ++k)
        if (effect_allows_sensor(x, k)) {
          o[x.json_value[k]] = get_rows(x, e, k, false);
          o[kSigmaKey[k]] = get_rows(x, s, k, true);
        }
      break;
    case EffectShape::vector:
      if (x.nparams == 1) o = {{vk, effect_value(x, e, x.sensor, -1, 0)}, {"sigma", effect_value(x, s, x.sensor, -1, 0)}};
      else if (x.nparams == 2) o = {{vk, arr2(Eigen::Vector2d(get_vec(x, e)))}, {"sigma", arr2(Eigen::Vector2d(get_vec(x, s)))}};
      else o = {{vk, to_json(Vec3(get_vec(x, e)))}, {"sigma", sigma_json(Vec3(get_vec(x, s)))}};
      break;
    case EffectShape::noise:
      for (int k = 0; k < 2; ++k)
        if (effect_allows_sensor(x, k) && effect_value(x, e, k, -1, 0) > 0) {
          o[x.json_value[k]] = effect_value(x, e, k, -1, 0);
          o[std::string(kSensorName[k]) + "_tau_s"] = effect_value(x, e, k, -1, 1);
        }
      o["note"] = "in-run drift beyond the data-sheet prior; identify it with `calbench identify`";
      break;
  }
  return o;
}

}  // namespace

const std::vector<std::string>& effect_json_keys() {
  // Each catalogue effect's key is its ID.
  static const std::vector<std::string> k = [] {
    std::vector<std::string> v;
    for (int e = 0; e < effect_count(); ++e) v.push_back(effect_name(static_cast<EffectId>(e)));
    return v;
  }();
  return k;
}

EffectTerms effects_from_json(const nlohmann::json& j, const std::string& f, EffectTerms* sigma) {
  EffectTerms e, s;
  if (!j.is_object()) return e;
  for (const EffectSpec& x : effect_specs())
    if (j.contains(x.key)) read_effect(x, j[x.key], f, e, s);
  if (sigma) *sigma = s;
  return e;
}

void effects_to_json(const EffectTerms& e, const EffectTerms& s, nlohmann::json& j) {
  for (const EffectSpec& x : effect_specs())
    if (effect_present(x, e)) j[x.key] = write_effect(x, e, s);
}

void apply_inject_option(const std::string& opt, EffectTerms& e) {
  const std::string where = "--inject " + opt;
  const auto colon = opt.find(':');
  const std::string name = opt.substr(0, colon);
  std::map<std::string, std::string> kv;
  if (colon != std::string::npos) {
    std::stringstream ss(opt.substr(colon + 1));
    std::string item;
    while (std::getline(ss, item, ',')) {
      const auto eq = item.find('=');
      if (eq == std::string::npos) throw InputError(where, 0, item, "expected key=value");
      kv[item.substr(0, eq)] = item.substr(eq + 1);
    }
  }
  std::map<std::string, bool> used;
  auto num = [&](const std::string& k) {
    if (!kv.count(k)) throw InputError(where, 0, k, "missing key");
    used[k] = true;
    double v = 0;
    if (!parse_finite_number(kv[k], v)) throw InputError(where, 0, k, "not a number: '" + kv[k] + "'");
    return v;
  };
  auto num_or = [&](const std::string& k, double d) { return kv.count(k) ? num(k) : d; };
  auto axis = [&](const std::string& k) {
    if (!kv.count(k)) throw InputError(where, 0, k, "missing key (x, y or z)");
    used[k] = true;
    const std::string v = kv[k];
    if (v == "x") return 0;
    if (v == "y") return 1;
    if (v == "z") return 2;
    throw InputError(where, 0, k, "expected x, y or z, got '" + v + "'");
  };
  EffectId id;
  if (!effect_from_name(name, id)) {
    std::string names;
    for (int k = 0; k < effect_count(); ++k) names += std::string(k ? ", " : "") + effect_name(static_cast<EffectId>(k));
    throw InputError(where, 0, "effect", "unknown effect '" + name + "' (" + names + ")");
  }
  const EffectSpec& x = effect_spec(id);
  // The sensor of a per-triad effect: required where both are allowed.
  auto sensor = [&]() {
    const bool both = effect_allows_sensor(x, 0) && effect_allows_sensor(x, 1);
    if (!kv.count("sensor")) {
      if (!both) return effect_allows_sensor(x, 0) ? 0 : 1;
      throw InputError(where, 0, "sensor", "missing key (gyro or accel)");
    }
    used["sensor"] = true;
    for (int k = 0; k < 2; ++k)
      if (kv["sensor"] == kSensorName[k] && effect_allows_sensor(x, k)) return k;
    throw InputError(where, 0, "sensor",
                     std::string("expected ") + (both ? "gyro or accel" : effect_allows_sensor(x, 0) ? "gyro" : "accel") +
                         ", got '" + kv["sensor"] + "'");
  };
  switch (x.shape) {
    case EffectShape::triad_axis: {
      const int k = sensor();
      const double v = num("value");
      *effect_param(x, e, k, axis("axis"), 0) += v;
      break;
    }
    case EffectShape::gyro_matrix: {
      const int i = axis("axis"), k = axis("f");
      *effect_param(x, e, x.sensor, i, k) += num("value");
      break;
    }
    case EffectShape::axis_rows: {
      const int k = sensor(), i = axis("axis");
      const std::string ck = x.components_other_axes ? "with" : "term";
      if (!kv.count(ck)) throw InputError(where, 0, ck, "missing key");
      used[ck] = true;
      int p = -1;
      std::string names;
      for (int q = 0; q < x.nparams; ++q) {
        names += (q ? ", " : "") + effect_component_name(x, i, q);
        if (kv[ck] == effect_component_name(x, i, q)) p = q;
      }
      if (p < 0) throw InputError(where, 0, ck, "expected one of " + names + " for axis " + kv["axis"] + ", got '" + kv[ck] + "'");
      *effect_param(x, e, k, i, p) += num("value");
      break;
    }
    case EffectShape::vector: {
      std::stringstream ss(x.inject_keys);
      std::string k;
      for (int p = 0; std::getline(ss, k, ','); ++p)
        *effect_param(x, e, x.sensor, -1, p) += x.nparams == 1 ? num(k) : num_or(k, 0);
      break;
    }
    case EffectShape::noise: {
      const int k = sensor();
      double& sigma = *effect_param(x, e, k, -1, 0);
      double& tau = *effect_param(x, e, k, -1, 1);
      sigma = num("sigma");
      tau = num_or("tau", 300.0);
      if (sigma <= 0 || tau <= 0) throw InputError(where, 0, "sigma", "sigma and tau must be positive");
      break;
    }
  }
  for (const auto& [k, v] : kv)
    if (!used.count(k)) throw InputError(where, 0, k, "unknown key for " + name);
}

EffectTerms simulation_effects(const nlohmann::json& truth_extra, const std::string& truth_file,
                               const std::string& effects_file, const std::vector<std::string>& inject) {
  EffectTerms effects = effects_from_json(truth_extra, truth_file);
  if (!effects_file.empty()) {
    const EffectTerms more = effects_from_json(read_json_file(effects_file), effects_file);
    nlohmann::json tmp = nlohmann::json::object();
    effects_to_json(more, EffectTerms{}, tmp);
    if (tmp.empty()) throw InputError(effects_file, 0, "", "no catalogue key (docs/diagnosis.md) in this file");
    effects = more;  // the file replaces terms carried by the truth
  }
  for (const auto& o : inject) apply_inject_option(o, effects);
  return effects;
}

void replace_effect_keys(const EffectTerms& e, nlohmann::json& j) {
  for (const auto& k : effect_json_keys()) j.erase(k);
  effects_to_json(e, EffectTerms{}, j);
}

namespace {

std::string md(const std::string& t) {  // a Markdown table cell
  std::string o;
  for (char c : t) {
    if (c == '|') o += '\\';
    o += c;
  }
  return o;
}

std::string sensors_text(const EffectSpec& x) {
  if (effect_per_sensor(x))
    return effect_allows_sensor(x, 0) && effect_allows_sensor(x, 1) ? "gyro, accel" : effect_allows_sensor(x, 0) ? "gyro" : "accel";
  return x.sensor == 2 ? "reference" : kSensorName[x.sensor];
}

std::string unit_text(const EffectSpec& x) {
  std::string u;
  for (int k = 0; k < 2; ++k) {
    if (!effect_allows_sensor(x, k) && effect_per_sensor(x)) continue;
    const std::string one = std::string(x.si_unit[k]) + " (shown in " + x.bench_display.unit[k] + ")";
    if (!u.empty() && u.find(one) != std::string::npos) continue;
    u += (u.empty() ? "" : "; ") + one;
  }
  return u;
}

std::string si_units(const EffectSpec& x) {
  std::string u;
  for (int k = 0; k < 2; ++k)
    if ((effect_allows_sensor(x, k) || !effect_per_sensor(x)) &&
        u.find(x.si_unit[k]) == std::string::npos)
      u += (u.empty() ? "" : " (gyro), ") + std::string(x.si_unit[k]) + (u.empty() ? "" : " (accel)");
  return u;
}

std::string json_text(const EffectSpec& x) {
  std::string o = std::string("`\"") + x.key + "\": {";
  switch (x.shape) {
    case EffectShape::triad_axis:
      if (x.json_t0) o += "\"t0_c\", ";
      for (int k = 0, n = 0; k < 2; ++k)
        if (effect_allows_sensor(x, k))
          o += std::string(n++ ? ", " : "") + "\"" + x.json_value[k] + "\": [3], \"" + kSigmaKey[k] + "\": [3]";
      break;
    case EffectShape::gyro_matrix: o += std::string("\"") + x.json_value[0] + "\": 3×3, \"sigma\": 3×3"; break;
    case EffectShape::axis_rows: {
      const std::string n = "3×" + std::to_string(x.nparams);
      o += "\"columns\"";
      for (int k = 0; k < 2; ++k)
        if (effect_allows_sensor(x, k))
          o += std::string(", \"") + x.json_value[k] + "\": " + n + ", \"" + kSigmaKey[k] + "\": " + n;
      break;
    }
    case EffectShape::vector:
      o += std::string("\"") + x.json_value[0] + "\"" +
           (x.nparams > 1 ? ": [" + std::to_string(x.nparams) + "], \"sigma\": [" + std::to_string(x.nparams) + "]" : ", \"sigma\"");
      break;
    case EffectShape::noise:
      for (int k = 0, n = 0; k < 2; ++k)
        if (effect_allows_sensor(x, k))
          o += std::string(n++ ? ", " : "") + "\"" + x.json_value[k] + "\", \"" + kSensorName[k] + "_tau_s\"";
      break;
  }
  return o + "}`";
}

std::string inject_text(const EffectSpec& x) {
  const bool both = effect_allows_sensor(x, 0) && effect_allows_sensor(x, 1);
  const std::string sensor = both ? "sensor=gyro|accel," : std::string("[sensor=") + (effect_allows_sensor(x, 0) ? "gyro" : "accel") + ",]";
  switch (x.shape) {
    case EffectShape::triad_axis: return "`" + sensor + "axis=x|y|z,value=V`";
    case EffectShape::gyro_matrix: return "`axis=` (gyro axis), `f=` (force axis), `value=`";
    case EffectShape::axis_rows: {
      if (x.components_other_axes) return "`" + sensor + "axis=x|y|z,with=` (another axis), `value=`";
      std::string names;
      for (int p = 0; p < x.nparams; ++p) names += (p ? "|" : "") + effect_component_name(x, 0, p);
      return "`" + sensor + "axis=x|y|z,term=" + names + ",value=V`";
    }
    case EffectShape::vector: {
      std::string k = x.inject_keys, o;
      std::stringstream ss(k);
      for (std::string p; std::getline(ss, p, ',');) o += (o.empty() ? "" : ",") + p + "=";
      return "`" + o + "`";
    }
    case EffectShape::noise: return "`" + sensor + "sigma=,tau=` (τ default 300 s)";
  }
  return "";
}

const char* drive_text(const EffectSpec& x) {
  switch (x.drive) {
    case DriveDiagnosis::always: return "yes";
    case DriveDiagnosis::with_temperature: return "with a temperature column";
    case DriveDiagnosis::fixed_scale: return "with given coefficients (M fixed)";
    case DriveDiagnosis::alternative_only: return "no; weighed as an alternative to what is named";
    case DriveDiagnosis::never: return x.shape == EffectShape::noise ? "yes (noise model)" : "no";
  }
  return "";
}

}  // namespace

std::string effect_catalogue_markdown() {
  std::string o =
      "| effect ID | physics | model term | sensors | SI unit (shown in) | revealed on the bench by | excited by | on drives | extra JSON key |\n"
      "|---|---|---|---|---|---|---|---|---|\n";
  for (const EffectSpec& x : effect_specs())
    o += "| `" + std::string(x.key) + "` | " + md(x.physics) + " | " + md(x.model) + " | " + sensors_text(x) + " | " +
         md(unit_text(x)) + " | " + md(x.condition) + (x.bench_candidate || x.shape == EffectShape::noise ? "" : " (not a bench candidate: M is refitted)") +
         " | " + md(effect_excited_by(x)) + " | " + drive_text(x) + " | " + md(json_text(x)) + " |\n";
  o += "\n| effect | `--inject` keys | unit |\n|---|---|---|\n";
  for (const EffectSpec& x : effect_specs())
    o += "| `" + std::string(x.key) + "` | " + md(inject_text(x)) + " | " + md(si_units(x)) + " |\n";
  return o;
}

nlohmann::json effect_catalogue_json() {
  nlohmann::json a = nlohmann::json::array();
  for (const EffectSpec& x : effect_specs())
    a.push_back({{"id", x.key},
                 {"index", static_cast<int>(x.id)},
                 {"physics", x.physics},
                 {"model", x.model},
                 {"sensors", sensors_text(x)},
                 {"parameters_per_term", x.nparams},
                 {"si_unit", {x.si_unit[0], x.si_unit[1]}},
                 {"display_unit", {x.bench_display.unit[0], x.bench_display.unit[1]}},
                 {"bench_condition", x.condition},
                 {"bench_candidate", x.bench_candidate},
                 {"excited_by", effect_excited_by(x)},
                 {"plausible_size", {x.drive_prior[0], x.drive_prior[1]}},
                 {"drives", drive_text(x)},
                 {"drive_prior_sigma", {x.drive_prior[0], x.drive_prior[1]}},
                 {"json", json_text(x)},
                 {"inject", inject_text(x)}});
  return a;
}

}  // namespace calbench
