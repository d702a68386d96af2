// The "drift_models" key of MODELS.json (written by `calbench identify --out`) and of a
// coefficients.json it was merged into: identified sensor-drift models, one per column/axis.
// Format: docs/identification.md. Reading validates the parameters; the shaping filter (A, G, H,
// P∞, Φ, Qd) is rebuilt from σ, α, β with calibration/identification/shaping_filter.hpp rather
// than trusted from the file.
#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>
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

}  // namespace calbench
