#include "common/coefficients_codec.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/input_error.hpp"
#include "common/json_fields.hpp"

namespace calbench {
namespace {
TriadErrors triad_from_json(const nlohmann::json& j, const std::string& f, const std::string& name,
                            nlohmann::json& extra) {
  if (!j.is_object()) throw InputError(f, 0, name, "expected an object");
  TriadErrors t;
  t.bias = jvec3(jreq(j, "bias", f, name), f, name + ".bias");
  t.M = jmat3(jreq(j, "M", f, name), f, name + ".M");
  // measured = (I + M)·true + b is inverted by every user of a set: I + M must be a usable scale
  // matrix (a triad whose axes still see their own input). A determinant below 0.1 (an axis scaled
  // by −100 %, two axes parallel) is no calibration of a working sensor.
  if (const double det = (Mat3::Identity() + t.M).determinant(); !(det >= 0.1))
    throw InputError(f, 0, name + ".M",
                     "I + M has determinant " + std::to_string(det) +
                         ": not invertible as a calibration (an axis's sign flipped, a scale of −100 % or axes that coincide); at least 0.1 expected");
  t.sigma_bias = j.contains("sigma_bias") ? jsigma3(j["sigma_bias"], f, name + ".sigma_bias") : Vec3::Constant(kUnknownSigma);
  t.sigma_M = j.contains("sigma_M") ? jsigmamat3(j["sigma_M"], f, name + ".sigma_M") : Mat3::Constant(kUnknownSigma);
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "bias" && it.key() != "M" && it.key() != "sigma_bias" && it.key() != "sigma_M")
      extra[name][it.key()] = it.value();
  return t;
}

Vec3 chi2_json(const nlohmann::json& j, const std::string& f, const std::string& key) {
  const Vec3 v = jvec3(j, f, key);
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(v(i)) || v(i) < 0) throw InputError(f, 0, key, "expected finite non-negative numbers");
  return v;
}

// "fit_quality": {"chi2_per_dof": {"gyro": [3], "accel": [3]}, "steps": [{"step", "kind",
// "gyro_mean_rad_s": [3], "accel_mean_m_s2": [3]}], "largest_systematic": {...}} (the last is
// derived from the steps: written for readers, not read back).
BenchFitQuality fit_quality_from_json(const nlohmann::json& j, const std::string& f) {
  const std::string k = "fit_quality";
  if (!j.is_object()) throw InputError(f, 0, k, "expected an object");
  BenchFitQuality q;
  const auto& c = jreq(j, "chi2_per_dof", f, k);
  q.gyro_chi2_dof = chi2_json(jreq(c, "gyro", f, k + ".chi2_per_dof"), f, k + ".chi2_per_dof.gyro");
  q.accel_chi2_dof = chi2_json(jreq(c, "accel", f, k + ".chi2_per_dof"), f, k + ".chi2_per_dof.accel");
  const auto& steps = jreq(j, "steps", f, k);
  if (!steps.is_array()) throw InputError(f, 0, k + ".steps", "expected an array");
  for (std::size_t n = 0; n < steps.size(); ++n) {
    const std::string sk = k + ".steps[" + std::to_string(n) + "]";
    const auto& e = steps[n];
    if (!e.is_object()) throw InputError(f, 0, sk, "expected an object");
    StepMeanResidual s;
    const auto& step = jreq(e, "step", f, sk);
    if (!step.is_number_integer() || step.get<long long>() < 0 || step.get<long long>() > 1000000)
      throw InputError(f, 0, sk + ".step", "expected a step number (integer ≥ 0)");
    s.step = static_cast<int>(step.get<long long>());
    s.kind = jstr(jreq(e, "kind", f, sk), f, sk + ".kind");
    if (s.kind != kStepStatic && s.kind != kStepRate)
      throw InputError(f, 0, sk + ".kind", "expected \"static\" or \"rate\", got '" + s.kind + "'");
    s.gyro = jvec3(jreq(e, "gyro_mean_rad_s", f, sk), f, sk + ".gyro_mean_rad_s");
    s.accel = jvec3(jreq(e, "accel_mean_m_s2", f, sk), f, sk + ".accel_mean_m_s2");
    if (!s.gyro.allFinite() || !s.accel.allFinite()) throw InputError(f, 0, sk, "expected finite residuals");
    q.steps.push_back(s);
  }
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "chi2_per_dof" && it.key() != "steps" && it.key() != "largest_systematic")
      throw InputError(f, 0, k + "." + it.key(), "unknown key (expected chi2_per_dof, steps, largest_systematic)");
  return q;
}

nlohmann::json fit_quality_to_json(const BenchFitQuality& q) {
  nlohmann::json steps = nlohmann::json::array();
  for (const auto& s : q.steps)
    steps.push_back({{"step", s.step}, {"kind", s.kind}, {"gyro_mean_rad_s", to_json(s.gyro)},
                     {"accel_mean_m_s2", to_json(s.accel)}});
  nlohmann::json largest = nlohmann::json::object();
  for (const bool gyro : {true, false})
    for (const auto& L : largest_residuals(q, gyro))
      largest[L.kind][gyro ? "gyro_rad_s" : "accel_m_s2"] = {
          {"value", L.value}, {"step", L.step}, {"axis", std::string(1, "xyz"[L.axis])}, {"steps", L.steps}};
  return {{"chi2_per_dof", {{"gyro", to_json(q.gyro_chi2_dof)}, {"accel", to_json(q.accel_chi2_dof)}}},
          {"steps", steps},
          {"largest_systematic", largest}};
}

nlohmann::json triad_to_json(const TriadErrors& t, const nlohmann::json& extra) {
  nlohmann::json j = extra.is_object() ? extra : nlohmann::json::object();
  j["bias"] = to_json(t.bias);
  j["M"] = to_json(t.M);
  j["sigma_bias"] = sigma_json(t.sigma_bias);
  j["sigma_M"] = sigma_json(t.sigma_M);
  return j;
}
}  // namespace

DeviceId coefficients_device(const nlohmann::json& j, const std::string& f) {
  if (!j.is_object()) throw InputError(f, 1, "", "expected a JSON object");
  const std::string format = jstr(jreq(j, "format", f, ""), f, "format");
  if (format != kCoefficientsFormat)
    throw InputError(f, 0, "format", "unsupported format '" + format + "' (expected calbench-coefficients/1)");
  DeviceId d;
  const auto& dev = jreq(j, "device", f, "");
  d.model = jstr(jreq(dev, "model", f, "device"), f, "device.model");
  const auto& serial = jreq(dev, "serial", f, "device");
  d.serial = serial.is_number_integer() ? std::to_string(serial.get<long long>()) : jstr(serial, f, "device.serial");
  return d;
}

CoefficientSet coefficients_from_json(const nlohmann::json& j, const std::string& f) {
  CoefficientSet c;
  c.device = coefficients_device(j, f);
  c.errors.gyro = triad_from_json(jreq(j, "gyro", f, ""), f, "gyro", c.extra);
  c.errors.accel = triad_from_json(jreq(j, "accel", f, ""), f, "accel", c.extra);
  if (j.contains("fit_quality")) c.fit_quality = fit_quality_from_json(j["fit_quality"], f);
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "format" && it.key() != "device" && it.key() != "gyro" && it.key() != "accel" &&
        it.key() != "fit_quality")
      c.extra[it.key()] = it.value();
  return c;
}

nlohmann::json coefficients_to_json(const CoefficientSet& c) {
  nlohmann::json j = nlohmann::json::object();
  j["format"] = kCoefficientsFormat;
  j["device"] = {{"model", c.device.model}, {"serial", c.device.serial}};
  const nlohmann::json none = nlohmann::json::object();
  j["gyro"] = triad_to_json(c.errors.gyro, c.extra.contains("gyro") ? c.extra["gyro"] : none);
  j["accel"] = triad_to_json(c.errors.accel, c.extra.contains("accel") ? c.extra["accel"] : none);
  for (auto it = c.extra.begin(); it != c.extra.end(); ++it)
    if (it.key() != "gyro" && it.key() != "accel" && it.key() != "fit_quality") j[it.key()] = it.value();
  if (c.fit_quality) j["fit_quality"] = fit_quality_to_json(*c.fit_quality);
  return j;
}

namespace {
const char* const kAxes = "xyz";
}  // namespace

const std::vector<std::string>& coefficient_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const char* s : {"gyro", "accel"}) {
      for (int i = 0; i < 3; ++i) n.push_back(std::string(s) + ".bias." + kAxes[i]);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) n.push_back(std::string(s) + ".M." + kAxes[i] + kAxes[j]);
    }
    return n;
  }();
  return names;
}

namespace {
// name → (triad, is_bias, i, j); throws std::invalid_argument on an unknown name.
struct Where {
  bool gyro, bias;
  int i, j;
};
Where locate(const std::string& name) {
  const auto& n = coefficient_names();
  const auto it = std::find(n.begin(), n.end(), name);
  if (it == n.end()) throw std::invalid_argument("unknown coefficient name '" + name + "'");
  int k = static_cast<int>(it - n.begin());
  Where w{k < 12, false, 0, 0};
  k %= 12;
  if (k < 3) {
    w.bias = true;
    w.i = k;
  } else {
    w.i = (k - 3) / 3;
    w.j = (k - 3) % 3;
  }
  return w;
}
}  // namespace

double coefficient_value(const SensorErrors& e, const std::string& name) {
  const Where w = locate(name);
  const TriadErrors& t = w.gyro ? e.gyro : e.accel;
  return w.bias ? t.bias(w.i) : t.M(w.i, w.j);
}
double coefficient_sigma(const SensorErrors& e, const std::string& name) {
  const Where w = locate(name);
  const TriadErrors& t = w.gyro ? e.gyro : e.accel;
  return w.bias ? t.sigma_bias(w.i) : t.sigma_M(w.i, w.j);
}

}  // namespace calbench
