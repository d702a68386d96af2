#include "common/coefficients_codec.hpp"

#include <algorithm>
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
  t.sigma_bias = j.contains("sigma_bias") ? jsigma3(j["sigma_bias"], f, name + ".sigma_bias") : Vec3::Constant(kUnknownSigma);
  t.sigma_M = j.contains("sigma_M") ? jsigmamat3(j["sigma_M"], f, name + ".sigma_M") : Mat3::Constant(kUnknownSigma);
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "bias" && it.key() != "M" && it.key() != "sigma_bias" && it.key() != "sigma_M")
      extra[name][it.key()] = it.value();
  return t;
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
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "format" && it.key() != "device" && it.key() != "gyro" && it.key() != "accel")
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
    if (it.key() != "gyro" && it.key() != "accel") j[it.key()] = it.value();
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
