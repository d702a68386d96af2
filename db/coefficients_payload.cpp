// Validation and indexing of coefficients.json payloads (spec schema) inside the store.
// (The store cannot use bench/io, which links it; this is the small strict subset it needs.)
#include <cmath>
#include <nlohmann/json.hpp>

#include "common/input_error.hpp"
#include "common/json_parse.hpp"
#include "db/store.hpp"

namespace calbench::db {
namespace {
using nlohmann::json;

const char* const kAxes = "xyz";

double num(const json& v, const std::string& f, const std::string& key) {
  if (!v.is_number()) throw InputError(f, 0, key, std::string("expected a number, got ") + v.type_name());
  const double d = v.get<double>();
  if (!std::isfinite(d)) throw InputError(f, 0, key, "NaN or infinity is not allowed");
  return d;
}
double sig(const json& v, const std::string& f, const std::string& key) {
  if (v.is_null()) return kUnknownSigma;
  const double d = num(v, f, key);
  if (d < 0) throw InputError(f, 0, key, "a σ cannot be negative");
  return d;
}
const json& req(const json& o, const char* k, const std::string& f, const std::string& prefix) {
  const std::string key = prefix.empty() ? std::string(k) : prefix + "." + k;
  if (!o.is_object()) throw InputError(f, 0, prefix, "expected an object");
  auto it = o.find(k);
  if (it == o.end()) throw InputError(f, 0, key, "missing key");
  return *it;
}
Vec3 vec3(const json& v, const std::string& f, const std::string& key, bool sigma) {
  if (!v.is_array() || v.size() != 3) throw InputError(f, 0, key, "expected an array of 3 numbers");
  Vec3 out;
  for (int i = 0; i < 3; ++i) {
    const std::string k = key + "[" + std::to_string(i) + "]";
    out(i) = sigma ? sig(v[i], f, k) : num(v[i], f, k);
  }
  return out;
}
Mat3 mat3(const json& v, const std::string& f, const std::string& key, bool sigma) {
  if (!v.is_array() || v.size() != 3) throw InputError(f, 0, key, "expected a 3×3 array of numbers");
  Mat3 out;
  for (int i = 0; i < 3; ++i) {
    const std::string ki = key + "[" + std::to_string(i) + "]";
    if (!v[i].is_array() || v[i].size() != 3) throw InputError(f, 0, ki, "expected an array of 3 numbers");
    for (int j = 0; j < 3; ++j) {
      const std::string k = ki + "[" + std::to_string(j) + "]";
      out(i, j) = sigma ? sig(v[i][j], f, k) : num(v[i][j], f, k);
    }
  }
  return out;
}
TriadErrors triad(const json& j, const std::string& f, const std::string& name) {
  if (!j.is_object()) throw InputError(f, 0, name, "expected an object");
  TriadErrors t;
  t.bias = vec3(req(j, "bias", f, name), f, name + ".bias", false);
  t.M = mat3(req(j, "M", f, name), f, name + ".M", false);
  t.sigma_bias = j.contains("sigma_bias") ? vec3(j["sigma_bias"], f, name + ".sigma_bias", true)
                                          : Vec3::Constant(kUnknownSigma);
  t.sigma_M = j.contains("sigma_M") ? mat3(j["sigma_M"], f, name + ".sigma_M", true) : Mat3::Constant(kUnknownSigma);
  return t;
}
json vec_json(const Vec3& v, bool sigma) {
  json a = json::array();
  for (int i = 0; i < 3; ++i) a.push_back(sigma && !std::isfinite(v(i)) ? json(nullptr) : json(v(i)));
  return a;
}
json mat_json(const Mat3& m, bool sigma) {
  json a = json::array();
  for (int i = 0; i < 3; ++i) a.push_back(vec_json(m.row(i).transpose(), sigma));
  return a;
}
void put_triad(json& j, const TriadErrors& t) {
  if (!j.is_object()) j = json::object();
  j["bias"] = vec_json(t.bias, false);
  j["M"] = mat_json(t.M, false);
  j["sigma_bias"] = vec_json(t.sigma_bias, true);
  j["sigma_M"] = mat_json(t.sigma_M, true);
}
}  // namespace

ParsedCoefficients parse_coefficients(const std::string& text, const std::string& f, const std::string& expect_serial) {
  const json j = parse_json_text(text, f);
  if (!j.is_object()) throw InputError(f, 1, "", "expected a JSON object");
  const json& fmt = req(j, "format", f, "");
  if (!fmt.is_string() || fmt.get<std::string>() != "calbench-coefficients/1")
    throw InputError(f, 0, "format", "expected \"calbench-coefficients/1\"");
  ParsedCoefficients p;
  const json& dev = req(j, "device", f, "");
  const json& model = req(dev, "model", f, "device");
  if (!model.is_string() || model.get<std::string>().empty())
    throw InputError(f, 0, "device.model", "expected a non-empty string");
  p.device.model = model.get<std::string>();
  const json& serial = req(dev, "serial", f, "device");
  if (serial.is_number_integer()) p.device.serial = std::to_string(serial.get<long long>());
  else if (serial.is_string()) p.device.serial = serial.get<std::string>();
  else throw InputError(f, 0, "device.serial", std::string("expected a string, got ") + serial.type_name());
  if (p.device.serial.empty()) throw InputError(f, 0, "device.serial", "empty serial number");
  if (!expect_serial.empty() && p.device.serial != expect_serial)
    throw InputError(f, 0, "device.serial",
                     "serial '" + p.device.serial + "' does not match the device '" + expect_serial + "'");
  p.errors.gyro = triad(req(j, "gyro", f, ""), f, "gyro");
  p.errors.accel = triad(req(j, "accel", f, ""), f, "accel");
  p.canonical_json = j.dump(2);
  return p;
}

std::string coefficients_json_text(const DeviceInfo& device, const SensorErrors& errors, const std::string& extra_json) {
  json j = json::object();
  if (!extra_json.empty()) {
    json x = json::parse(extra_json);
    if (x.is_object()) j = x;
  }
  j["format"] = "calbench-coefficients/1";
  j["device"] = {{"model", device.model}, {"serial", device.serial}};
  put_triad(j["gyro"], errors.gyro);
  put_triad(j["accel"], errors.accel);
  return j.dump(2);
}

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

}  // namespace calbench::db
