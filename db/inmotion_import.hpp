// Import of an in-motion calibration result (RESULT.json of `calbench fit drive`, issue 5), read
// through its one codec (common/drive_result.hpp: the keys, their types and the older forms the
// store has always taken are checked there): device, recording, the coefficient sets, the
// mounting, "consistency", "qc", "determined_by"; the whole text kept as result_json.
// QC metrics from "qc": numbers, {"value", "threshold", "pass"} objects, and the numeric figures of
// "sets" entries (sets.NAME.final_cpe_m, unit m), each marked with qc.sample (in-/out-of-sample).
// The figures are informative (no threshold) except the result set's final ΔS ("in-motion"), which
// must not exceed that of the set the fit started from ("input", or "none" on raw data); the same
// for the outage QC of a GNSS-only drive ("outages": outage_metric() below).
// The result is stored against the device named in it (which must already be in the database) as
// one in-motion run, its QC results and one coefficient set:
//  - source "combined" with the bench (or other) parent set P when "coefficients" equals
//    compose(P, "correction") — P given with --parent, or found among the device's sets;
//  - source "in-motion" (no parent) when the fit ran on raw data ("correction" = "coefficients",
//    or no "correction").
// Any problem (malformed file, unknown device, mismatched serials, a parent that does not compose
// to the stated coefficients) throws InputError and writes nothing.
#pragma once
#include <map>
#include <optional>
#include <string>

#include "common/drive_result.hpp"
#include "db/store.hpp"

namespace calbench::db {

// RESULT.json "determined_by" (fit drive, issue 16): which calibration stage determined each of the
// 24 coefficients (DeterminedBy, CoefficientStage of common/drive_result.hpp, read by its codec).
// nullopt when the result has no "determined_by" (results before issue 16); InputError naming the
// key when it is malformed.
std::optional<DeterminedBy> parse_determined_by(const std::string& result_json, const std::string& file);

struct InMotionResult {
  DeviceInfo device;
  std::string recording_path, recording_sha256, reference_system;
  // file://HOST/absolute/path and SHA-256 of all its files ("" in results written before them);
  // stored inside result_json (kept as given), read back by Store::inmotion_run.
  std::string recording_uri, recording_digest;
  ParsedCoefficients coefficients;
  std::optional<ParsedCoefficients> correction;
  std::array<double, 3> mounting_rpy_deg{}, mounting_sigma_deg{};  // σ +inf when not given
  bool has_mounting = false;
  std::string consistency_json = "{}", qc_json = "{}", result_json;
  std::vector<QcResult> qc;  // metrics extracted from "qc"
  std::optional<DeterminedBy> determined_by;
};

// The name of an outage-QC metric (qc.outages of a GNSS-only drive): outages.SET.15s.FIELD, e.g.
// outages.in-motion.15s.median_max_m (FIELD median_max_m, max_max_m, median_end_m, max_end_m).
// The result set's median_max_m of each length must not exceed the input set's (or raw data's).
std::string outage_metric(const std::string& set, double length_s, const std::string& field);

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
