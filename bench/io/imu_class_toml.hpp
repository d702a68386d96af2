// Device-class files (bench/imu_classes/<name>.toml, issue 34): one IMU model's data-sheet figures
// and their source, read into calibration/imu_class.hpp's ImuClass. The format and how to add a
// class: docs/in-motion.md, "Device classes". Bad input is an InputError naming the file, the line
// and the dotted key (exit 2).
#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "calibration/imu_class.hpp"

namespace calbench {

// Parses a class file.
ImuClass load_imu_class(const std::filesystem::path& file);
// The same on text in memory, `file` naming it in messages and in ImuClass::file.
ImuClass parse_imu_class(const std::string& text, const std::string& file);

// The classes shipped in bench/imu_classes (embedded into the executable at build time), in the
// order of their file names.
const std::vector<ImuClass>& builtin_imu_classes();
// The built-in class of that name or alias, or nullptr.
const ImuClass* find_builtin_imu_class(const std::string& model);
// The built-in class of that name or alias; std::out_of_range when there is none.
const ImuClass& builtin_imu_class(const std::string& model);
// "ADIS16465-1 (aliases: ...), ADIS16488A (...), ..." for messages.
std::string known_imu_classes_text();

// The class of a recording: `option` (--device-class: a class file, or the name or an alias of a
// built-in class) when given, else the built-in class `model` (meta.json device.model, matched
// case- and white-space-insensitively on name and aliases). An unknown model without the option
// is an InputError naming `meta_file`'s device.model with the list of known classes.
struct ImuClassChoice {
  ImuClass cls;
  std::string chosen_by;  // "--device-class FILE", "--device-class NAME" or "meta.json device.model 'X'"
};
ImuClassChoice choose_imu_class(const std::string& option, const std::string& model, const std::string& meta_file);

// What RESULT.json and reports record of the class: name, grade, file, source, chosen_by, and
// the figures in data-sheet units.
nlohmann::json imu_class_json(const ImuClassChoice& c);

}  // namespace calbench
