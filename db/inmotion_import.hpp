// Import of an in-motion calibration result (RESULT.json of `calbench fit drive`, issue 5):
//   {"device": {"model", "serial"}, "recording": {"path", "sha256"},
//    "coefficients": {spec schema with σ: total errors relative to the raw sensor output},
//    "correction":   {spec schema: the in-motion estimate relative to the input set} (optional),
//    "mounting_rpy_deg": [r, p, y] or {"value": [...], "sigma": [...]}  (+ "mounting_rpy_sigma_deg"),
//    "consistency": {...}, "qc": {...}, "reference_system"/"reference": "..." (optional)}
// The result is stored against the device named in it (which must already be in the database) as
// one in-motion run, its QC results and one coefficient set:
//  - source "combined" with the bench (or other) parent set P when "coefficients" equals
//    compose(P, "correction") — P given with --parent, or found among the device's sets;
//  - source "in-motion" (no parent) when the fit ran on raw data ("correction" = "coefficients",
//    or no "correction").
// Any problem (malformed file, unknown device, mismatched serials, a parent that does not compose
// to the stated coefficients) throws InputError and writes nothing.
#pragma once
#include <optional>
#include <string>

#include "db/store.hpp"

namespace calbench::db {

struct InMotionResult {
  DeviceInfo device;
  std::string recording_path, recording_sha256, reference_system;
  ParsedCoefficients coefficients;
  std::optional<ParsedCoefficients> correction;
  std::array<double, 3> mounting_rpy_deg{}, mounting_sigma_deg{};  // σ +inf when not given
  bool has_mounting = false;
  std::string consistency_json = "{}", qc_json = "{}", result_json;
  std::vector<QcResult> qc;  // metrics extracted from "qc"
};

// Parse and validate RESULT.json text; `file` names it in errors.
InMotionResult parse_inmotion_result(const std::string& text, const std::string& file);

struct ImportOutcome {
  std::int64_t run_id = 0, set_id = 0;
  int version = 0;
  SetSource source = SetSource::in_motion;
  std::optional<std::int64_t> parent_id;
  std::string note;
};

// Largest difference between two error models (values only), relative to 1 + |value|.
double max_difference(const SensorErrors& a, const SensorErrors& b);

ImportOutcome import_inmotion(Store& store, const InMotionResult& r, const std::string& file,
                              std::optional<std::int64_t> parent = std::nullopt);

}  // namespace calbench::db
