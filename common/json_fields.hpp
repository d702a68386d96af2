// Typed reading of JSON values with errors that name the file and the key, and the writing of
// vectors/matrices (σ with null for "unknown"). Used by every JSON schema the station reads
// (bench/io, the coefficients codec, the store), so one value is checked one way everywhere.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "common/sensor_model.hpp"

namespace calbench {

// Typed getters: throw InputError(file, 0, key, …) on a missing key or wrong type.
// `key` is the dotted path used in the message (e.g. "gyro.bias").
const nlohmann::json& jreq(const nlohmann::json& obj, const char* name, const std::string& file, const std::string& key);
double jnum(const nlohmann::json& v, const std::string& file, const std::string& key);
std::string jstr(const nlohmann::json& v, const std::string& file, const std::string& key);
Vec3 jvec3(const nlohmann::json& v, const std::string& file, const std::string& key);
Mat3 jmat3(const nlohmann::json& v, const std::string& file, const std::string& key);
// σ arrays: null entries mean "unknown" (+inf).
Vec3 jsigma3(const nlohmann::json& v, const std::string& file, const std::string& key);
Mat3 jsigmamat3(const nlohmann::json& v, const std::string& file, const std::string& key);

nlohmann::json to_json(const Vec3& v);
nlohmann::json to_json(const Mat3& m);
// Non-finite entries are written as null.
nlohmann::json sigma_json(const Vec3& v);
nlohmann::json sigma_json(const Mat3& m);

}  // namespace calbench
