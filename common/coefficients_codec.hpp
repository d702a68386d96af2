// The one codec of coefficients.json (spec: "Sensor error model and coefficients.json"), used by
// the bench (files), the store (payloads in the database) and the in-motion import. Reading is
// strict about the keys the spec defines and keeps every other key (extra model terms, the effect
// catalogue's keys) untouched in `extra`, so they pass through a read/write unchanged. File I/O is
// the caller's (bench/io/coefficients_json.hpp); the codec works on parsed JSON.
#pragma once
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "common/fit_quality.hpp"
#include "common/sensor_model.hpp"

namespace calbench {

inline constexpr const char* kCoefficientsFormat = "calbench-coefficients/1";

struct CoefficientSet {
  DeviceId device;
  SensorErrors errors;
  // Top-level keys beyond format/device/gyro/accel/fit_quality, and unknown keys inside gyro/accel
  // (as extra["gyro"][...] / extra["accel"][...]), preserved on write.
  nlohmann::json extra = nlohmann::json::object();
  // "fit_quality" of a bench fit (χ²/dof per axis, mean residual per step; common/fit_quality.hpp),
  // read strictly; absent in sets from other sources and older fits.
  std::optional<BenchFitQuality> fit_quality;
};

// "format" and "device" only: lets a caller check the device before the coefficients (the store
// refuses a payload for another device before it looks at the numbers).
DeviceId coefficients_device(const nlohmann::json& j, const std::string& file);
// The whole set; InputError(file, line, key, …) naming the key on anything malformed.
CoefficientSet coefficients_from_json(const nlohmann::json& j, const std::string& file);
nlohmann::json coefficients_to_json(const CoefficientSet& c);

// Names of the 24 indexed coefficients (the store's coefficient_values, the fleet, the reports), in
// a fixed order: gyro.bias.{x,y,z}, gyro.M.{xx..zz}, accel.bias.{x,y,z}, accel.M.{xx..zz}.
const std::vector<std::string>& coefficient_names();
// value/σ of a named coefficient of a set of errors; std::invalid_argument on an unknown name.
double coefficient_value(const SensorErrors& e, const std::string& name);
double coefficient_sigma(const SensorErrors& e, const std::string& name);

}  // namespace calbench
