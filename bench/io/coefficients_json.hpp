// coefficients.json (spec: "Sensor error model and coefficients.json"). Reading is strict about
// the keys the spec defines and keeps every other key (extra model terms) untouched in `extra`.
#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>

#include "common/sensor_model.hpp"

namespace calbench {

struct CoefficientSet {
  DeviceId device;
  SensorErrors errors;
  // Top-level keys beyond format/device/gyro/accel, and unknown keys inside gyro/accel
  // (as extra["gyro"][...] / extra["accel"][...]), preserved on write.
  nlohmann::json extra = nlohmann::json::object();
};

CoefficientSet coefficients_from_json(const nlohmann::json& j, const std::string& file);
nlohmann::json coefficients_to_json(const CoefficientSet& c);
CoefficientSet read_coefficients(const std::filesystem::path& file);
void write_coefficients(const std::filesystem::path& file, const CoefficientSet& c);  // atomic

}  // namespace calbench
