// The "drift_models" key of MODELS.json (written by `calbench identify --out`) and of a
// coefficients.json it was merged into: identified sensor-drift models, one per column/axis.
// Format: docs/identification.md. Reading validates the parameters; the shaping filter (A, G, H,
// P∞, Φ, Qd) is rebuilt from σ, α, β with calibration/identification/shaping_filter.hpp rather
// than trusted from the file.
#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "calibration/identification/shaping_filter.hpp"

namespace calbench {

struct DriftModelEntry {
  std::string key;                      // column name, e.g. "gx_rad_s"
  identification::DriftModel model;     // σ (signal units), α (1/s), β (rad/s)
  std::string sensor;                   // "gyro" | "accel" | "" (unknown)
  int axis = -1;                        // 0, 1, 2 or −1
  std::string unit;                     // signal unit, e.g. "rad/s"
};

// One entry as written by `calbench identify` (shaping filter included, discretised at dt).
nlohmann::json drift_model_json(const identification::DriftModel& m, double dt, const std::string& sensor,
                                int axis, const std::string& unit);
// Entries of j["drift_models"] (j is MODELS.json or a coefficients.json); InputError naming the
// file and the key on a missing key, a wrong type or an invalid parameter.
std::vector<DriftModelEntry> drift_models_from_json(const nlohmann::json& j, const std::string& file);
std::vector<DriftModelEntry> read_drift_models(const std::filesystem::path& file);
// The entry for a sensor ("gyro"/"accel") and axis, if present.
std::optional<DriftModelEntry> find_drift_model(const std::vector<DriftModelEntry>& v, const std::string& sensor,
                                                int axis);

// Sensor and axis a column name stands for: the recording columns gx_rad_s … az_m_s2 and the
// in-motion series columns gyro_{total,bias,drift}_{x,y,z}_dph, accel_{total,bias,drift}_{x,y,z}_mg.
// unit_per_si: the column's unit per SI unit (1 for *_rad_s / *_m_s2; °/h and mg for the series).
struct ColumnSensor {
  std::string sensor;  // "gyro" | "accel"
  int axis = -1;
  std::string unit;    // the column's unit: "rad/s", "m/s^2", "deg/h", "mg"
  double si_per_unit = 1;  // SI value = column value × si_per_unit
};
std::optional<ColumnSensor> column_sensor(const std::string& name);

// The models of MODELS.json assigned to the six sensor axes for the in-motion filter, in SI
// (σ in rad/s or m/s²). Sensor and axis come from the entry's "sensor"/"axis" or else from its key
// (column_sensor); the unit from "unit" ("rad/s", "m/s^2", "deg/h", "mg") or, when it is absent
// or "signal" (older identify output for series columns), from the key's suffix. InputError
// naming the key for a model whose axis cannot be told, a unit that does not fit the sensor, or
// two models for one axis.
struct AxisDriftModels {
  std::array<std::optional<DriftModelEntry>, 3> gyro, accel;  // σ converted to SI, unit "rad/s" / "m/s^2"
};
AxisDriftModels assign_drift_models(const std::vector<DriftModelEntry>& v, const std::string& file);

}  // namespace calbench
