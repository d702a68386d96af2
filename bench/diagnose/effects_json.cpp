#include "bench/diagnose/effects_json.hpp"

#include <map>
#include <sstream>

#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "calibration/diagnosis/catalogue.hpp"

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

// The per-axis terms of a triad, as data: JSON key, the gyro and accel value keys, whether the
// key carries the reference temperature, and the member they fill. Sigma keys are gyro_sigma,
// accel_sigma.
struct TriadKey {
  const char* key;
  const char* gyro;
  const char* accel;
  bool t0;
  Vec3 TriadEffectTerms::*member;
};
constexpr TriadKey kTriadKeys[] = {
    {"temperature_bias", "gyro_rad_s_per_K", "accel_m_s2_per_K", true, &TriadEffectTerms::temp_bias},
    {"temperature_scale", "gyro_per_K", "accel_per_K", true, &TriadEffectTerms::temp_scale},
    {"temperature_rate", "gyro_rad_s_per_K_per_s", "accel_m_s2_per_K_per_s", false, &TriadEffectTerms::temp_rate},
    {"scale_nonlinearity", "gyro_per_rad_s", "accel_per_m_s2", false, &TriadEffectTerms::nonlinearity},
    {"scale_asymmetry", "gyro", "accel", false, &TriadEffectTerms::asymmetry},
    // A change of M_ii (a simulation's injected shift since the calibration, or terms handed over
    // by hand); the diagnosis folds what it finds into M instead.
    {"scale_factor", "gyro", "accel", false, &TriadEffectTerms::scale},
};

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
  for (const TriadKey& t : kTriadKeys) {
    if (!j.contains(t.key)) continue;
    const auto& o = j[t.key];
    if (t.t0 && o.contains("t0_c")) e.t0_c = jnum(o["t0_c"], f, std::string(t.key) + ".t0_c");
    e.gyro.*t.member = opt3(o, t.gyro, f, t.key);
    e.accel.*t.member = opt3(o, t.accel, f, t.key);
    s.gyro.*t.member = optsig3(o, "gyro_sigma", f, t.key);
    s.accel.*t.member = optsig3(o, "accel_sigma", f, t.key);
  }
  if (j.contains("g_sensitivity")) {
    const auto& o = j["g_sensitivity"];
    e.g_sensitivity = jmat3(jreq(o, "gyro_rad_s_per_m_s2", f, "g_sensitivity"), f, "g_sensitivity.gyro_rad_s_per_m_s2");
    if (o.contains("sigma")) s.g_sensitivity = jsigmamat3(o["sigma"], f, "g_sensitivity.sigma");
  }
  if (j.contains("time_offset")) {
    const auto& o = j["time_offset"];
    e.time_offset_s = jnum(jreq(o, "s", f, "time_offset"), f, "time_offset.s");
    if (o.contains("sigma") && !o["sigma"].is_null()) s.time_offset_s = jnum(o["sigma"], f, "time_offset.sigma");
  }
  if (j.contains("lever_arm")) {
    const auto& o = j["lever_arm"];
    e.lever_arm_m = jvec3(jreq(o, "m", f, "lever_arm"), f, "lever_arm.m");
    s.lever_arm_m = optsig3(o, "sigma", f, "lever_arm");
  }
  if (j.contains("misalignment")) {
    const auto& o = j["misalignment"];
    e.table_tilt_rad = jvec2(jreq(o, "table_tilt_rad", f, "misalignment"), f, "misalignment.table_tilt_rad");
    if (o.contains("sigma")) s.table_tilt_rad = jvec2(o["sigma"], f, "misalignment.sigma");
  }
  if (j.contains("table_wobble")) {
    const auto& o = j["table_wobble"];
    e.wobble_rad = jvec2(jreq(o, "encoder_rad", f, "table_wobble"), f, "table_wobble.encoder_rad");
    if (o.contains("sigma")) s.wobble_rad = jvec2(o["sigma"], f, "table_wobble.sigma");
  }
  if (j.contains("correlated_drift")) {
    const auto& o = j["correlated_drift"];
    if (o.contains("gyro_sigma_rad_s")) e.gyro.drift_sigma = jnum(o["gyro_sigma_rad_s"], f, "correlated_drift.gyro_sigma_rad_s");
    if (o.contains("gyro_tau_s")) e.gyro.drift_tau_s = jnum(o["gyro_tau_s"], f, "correlated_drift.gyro_tau_s");
    if (o.contains("accel_sigma_m_s2"))
      e.accel.drift_sigma = jnum(o["accel_sigma_m_s2"], f, "correlated_drift.accel_sigma_m_s2");
    if (o.contains("accel_tau_s")) e.accel.drift_tau_s = jnum(o["accel_tau_s"], f, "correlated_drift.accel_tau_s");
  }
  if (sigma) *sigma = s;
  return e;
}

void effects_to_json(const EffectTerms& e, const EffectTerms& s, nlohmann::json& j) {
  auto nz = [](const Vec3& v) { return !v.isZero(0); };
  for (const TriadKey& t : kTriadKeys) {
    if (!nz(e.gyro.*t.member) && !nz(e.accel.*t.member)) continue;
    nlohmann::json o = nlohmann::json::object();
    if (t.t0) o["t0_c"] = e.t0_c;
    o[t.gyro] = to_json(e.gyro.*t.member);
    o["gyro_sigma"] = sigma_json(s.gyro.*t.member);
    o[t.accel] = to_json(e.accel.*t.member);
    o["accel_sigma"] = sigma_json(s.accel.*t.member);
    j[t.key] = o;
  }
  if (!e.g_sensitivity.isZero(0))
    j["g_sensitivity"] = {{"gyro_rad_s_per_m_s2", to_json(e.g_sensitivity)}, {"sigma", sigma_json(s.g_sensitivity)}};
  if (e.time_offset_s != 0) j["time_offset"] = {{"s", e.time_offset_s}, {"sigma", s.time_offset_s}};
  if (nz(e.lever_arm_m)) j["lever_arm"] = {{"m", to_json(e.lever_arm_m)}, {"sigma", sigma_json(s.lever_arm_m)}};
  if (!e.table_tilt_rad.isZero(0))
    j["misalignment"] = {{"table_tilt_rad", arr2(e.table_tilt_rad)}, {"sigma", arr2(s.table_tilt_rad)}};
  if (!e.wobble_rad.isZero(0))
    j["table_wobble"] = {{"encoder_rad", arr2(e.wobble_rad)}, {"sigma", arr2(s.wobble_rad)}};
  if (e.gyro.drift_sigma > 0 || e.accel.drift_sigma > 0) {
    nlohmann::json o = nlohmann::json::object();
    if (e.gyro.drift_sigma > 0) {
      o["gyro_sigma_rad_s"] = e.gyro.drift_sigma;
      o["gyro_tau_s"] = e.gyro.drift_tau_s;
    }
    if (e.accel.drift_sigma > 0) {
      o["accel_sigma_m_s2"] = e.accel.drift_sigma;
      o["accel_tau_s"] = e.accel.drift_tau_s;
    }
    o["note"] = "in-run drift beyond the data-sheet prior; identify it with `calbench identify`";
    j["correlated_drift"] = o;
  }
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
    try {
      std::size_t pos = 0;
      const double v = std::stod(kv[k], &pos);
      if (pos != kv[k].size() || !std::isfinite(v)) throw std::invalid_argument("");
      return v;
    } catch (const std::exception&) {
      throw InputError(where, 0, k, "not a number: '" + kv[k] + "'");
    }
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
  auto triad = [&]() -> TriadEffectTerms& {
    if (!kv.count("sensor")) throw InputError(where, 0, "sensor", "missing key (gyro or accel)");
    used["sensor"] = true;
    if (kv["sensor"] == "gyro") return e.gyro;
    if (kv["sensor"] == "accel") return e.accel;
    throw InputError(where, 0, "sensor", "expected gyro or accel, got '" + kv["sensor"] + "'");
  };
  if (name == "temperature_bias") {
    auto& t = triad();
    t.temp_bias(axis("axis")) += num("value");
  } else if (name == "temperature_scale") {
    auto& t = triad();
    t.temp_scale(axis("axis")) += num("value");
  } else if (name == "temperature_rate") {
    auto& t = triad();
    t.temp_rate(axis("axis")) += num("value");
  } else if (name == "scale_nonlinearity") {
    auto& t = triad();
    t.nonlinearity(axis("axis")) += num("value");
  } else if (name == "scale_asymmetry") {
    auto& t = triad();
    t.asymmetry(axis("axis")) += num("value");
  } else if (name == "scale_factor") {
    auto& t = triad();
    t.scale(axis("axis")) += num("value");
  } else if (name == "g_sensitivity") {
    const int i = axis("axis"), k = axis("f");
    e.g_sensitivity(i, k) += num("value");
  } else if (name == "time_offset") {
    e.time_offset_s += num("value");
  } else if (name == "lever_arm") {
    e.lever_arm_m += Vec3(num_or("x", 0), num_or("y", 0), num_or("z", 0));
  } else if (name == "misalignment") {
    e.table_tilt_rad += Eigen::Vector2d(num_or("north", 0), num_or("east", 0));
  } else if (name == "table_wobble") {
    e.wobble_rad += Eigen::Vector2d(num_or("sin", 0), num_or("cos", 0));
  } else if (name == "correlated_drift") {
    auto& t = triad();
    t.drift_sigma = num("sigma");
    t.drift_tau_s = num_or("tau", 300.0);
    if (t.drift_sigma <= 0 || t.drift_tau_s <= 0) throw InputError(where, 0, "sigma", "sigma and tau must be positive");
  } else {
    throw InputError(where, 0, "effect",
                     "unknown effect '" + name +
                         "' (temperature_bias, temperature_scale, temperature_rate, g_sensitivity, scale_nonlinearity, scale_asymmetry, "
                         "time_offset, lever_arm, misalignment, table_wobble, correlated_drift, scale_factor)");
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

}  // namespace calbench
