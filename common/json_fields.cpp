#include "common/json_fields.hpp"

#include <cmath>

#include "common/input_error.hpp"

namespace calbench {

const nlohmann::json& jreq(const nlohmann::json& obj, const char* name, const std::string& file, const std::string& key) {
  if (!obj.is_object()) throw InputError(file, 0, key.empty() ? std::string(name) : key, "expected an object");
  const auto it = obj.find(name);
  const std::string full = key.empty() ? std::string(name) : key + "." + name;
  if (it == obj.end()) throw InputError(file, 0, full, "missing key");
  return *it;
}

double jnum(const nlohmann::json& v, const std::string& file, const std::string& key) {
  if (!v.is_number()) throw InputError(file, 0, key, "expected a number, got " + std::string(v.type_name()));
  const double d = v.get<double>();
  if (!std::isfinite(d)) throw InputError(file, 0, key, "NaN or infinity is not allowed");
  return d;
}

std::string jstr(const nlohmann::json& v, const std::string& file, const std::string& key) {
  if (!v.is_string()) throw InputError(file, 0, key, "expected a string, got " + std::string(v.type_name()));
  return v.get<std::string>();
}

Vec3 jvec3(const nlohmann::json& v, const std::string& file, const std::string& key) {
  if (!v.is_array() || v.size() != 3) throw InputError(file, 0, key, "expected an array of 3 numbers");
  Vec3 out;
  for (int i = 0; i < 3; ++i) out(i) = jnum(v[i], file, key + "[" + std::to_string(i) + "]");
  return out;
}

Mat3 jmat3(const nlohmann::json& v, const std::string& file, const std::string& key) {
  if (!v.is_array() || v.size() != 3) throw InputError(file, 0, key, "expected a 3×3 array of numbers");
  Mat3 out;
  for (int i = 0; i < 3; ++i) out.row(i) = jvec3(v[i], file, key + "[" + std::to_string(i) + "]").transpose();
  return out;
}

Vec3 jsigma3(const nlohmann::json& v, const std::string& file, const std::string& key) {
  if (!v.is_array() || v.size() != 3) throw InputError(file, 0, key, "expected an array of 3 numbers or nulls");
  Vec3 out;
  for (int i = 0; i < 3; ++i) {
    const std::string k = key + "[" + std::to_string(i) + "]";
    out(i) = v[i].is_null() ? kUnknownSigma : jnum(v[i], file, k);
    if (out(i) < 0) throw InputError(file, 0, k, "a standard deviation cannot be negative");
  }
  return out;
}

Mat3 jsigmamat3(const nlohmann::json& v, const std::string& file, const std::string& key) {
  if (!v.is_array() || v.size() != 3) throw InputError(file, 0, key, "expected a 3×3 array of numbers or nulls");
  Mat3 out;
  for (int i = 0; i < 3; ++i) out.row(i) = jsigma3(v[i], file, key + "[" + std::to_string(i) + "]").transpose();
  return out;
}

nlohmann::json to_json(const Vec3& v) { return nlohmann::json::array({v(0), v(1), v(2)}); }
nlohmann::json to_json(const Mat3& m) {
  auto a = nlohmann::json::array();
  for (int i = 0; i < 3; ++i) a.push_back(to_json(Vec3(m.row(i).transpose())));
  return a;
}
nlohmann::json sigma_json(const Vec3& v) {
  auto a = nlohmann::json::array();
  for (int i = 0; i < 3; ++i) a.push_back(std::isfinite(v(i)) ? nlohmann::json(v(i)) : nlohmann::json(nullptr));
  return a;
}
nlohmann::json sigma_json(const Mat3& m) {
  auto a = nlohmann::json::array();
  for (int i = 0; i < 3; ++i) a.push_back(sigma_json(Vec3(m.row(i).transpose())));
  return a;
}

}  // namespace calbench
