// Helpers to read JSON documents with errors that name the file and the key.
#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "common/sensor_model.hpp"

namespace calbench {

// Parse a JSON file; syntax errors become InputError with the line and column.
nlohmann::json read_json_file(const std::filesystem::path& file);
// Atomic write: temporary file in the same folder, fsync, rename.
// An output file can be written there: not a folder, its folder exists and takes new files (InputError
// naming it).
// Commands call it before long work so that a typo costs nothing.
void check_output_path(const std::filesystem::path& file);
// An output folder can be made or written there: not a file, and the nearest existing folder on its
// path takes new entries (InputError naming it otherwise).
void check_output_folder(const std::filesystem::path& dir);
void write_text_atomic(const std::filesystem::path& file, const std::string& text);

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
