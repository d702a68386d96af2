// The one codec of the in-motion RESULT.json (`calbench fit drive --out`; contract in
// docs/in-motion.md "RESULT.json contract"), used by its writer (bench/drive/fit_drive.cpp) and its
// readers: `fit drive --coeffs RESULT.json`, `qc --coeffs RESULT.json`, `diagnose --coeffs`,
// `db import-inmotion` (db/inmotion_import.cpp) and the device report (bench/report/inmotion_section.cpp).
//
// Typed: what the readers use (device, recording and its digests, reference system, window,
// observations, the coefficient sets, the mounting, which stage determined each coefficient, the
// innovation consistency by observation, the outage QC). Kept as written: the free-form sections of
// the writer ("consistency" and "qc" are written as given, their typed reading beside them;
// "priors", and every other top-level key in `extra`), so a read/write passes them through unchanged. Reading accepts
// the older forms the store has always taken (device as a serial string, mounting as [r, p, y] or
// with "rpy", its σ under "mounting_rpy_sigma_deg", coefficient blocks without format/device, the
// reference under "reference" or recording.reference). File I/O is the caller's; the codec works on
// parsed JSON and throws InputError(file, line, key, …) naming the key on anything malformed.
#pragma once
#include <array>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/coefficients_codec.hpp"
#include "common/sensor_model.hpp"

namespace calbench {

inline constexpr const char* kDriveResultFormat = "calbench-inmotion-result/1";

// "determined_by": which calibration stage determined each parameter, from the drive's share of the
// information 1 − (σ_post/σ_prior)². σ in SI; nullopt = null (e.g. parent_sigma without a parent set).
struct CoefficientStage {
  std::string stage;  // "bench" | "drive" | "both" | "prior"
  std::optional<double> parent_sigma, prior_sigma, posterior_sigma, ratio, drive_share;
};
struct DeterminedBy {
  std::string rule;
  std::map<std::string, CoefficientStage> coefficients;  // names of coefficient_names(); may be partial
  std::map<std::string, CoefficientStage> mounting;      // mount.x, mount.y, mount.z
  // Written: "count" of the coefficients' stages (bench, drive, both, prior), computed from them.
};

struct DriveRecording {
  std::string path, sha256;  // sha256: of imu.csv (or recording.h5), 64 hexadecimal digits
  std::optional<std::string> sha256_reference;  // null: no reference.csv
  std::optional<std::string> sha256_meta, sha256_gnss;
  std::optional<std::string> format;  // "hdf5": the digests are of recording.h5
  std::optional<DeviceId> device;     // the unit that drove (must be the result's unit)
  // Where the recording is, for a central store (issue 35 item 8; docs/database.md "recording
  // locations"): file://HOST/absolute/path and the SHA-256 of all its files, as for bench runs.
  // Required on write (drive_result_to_json refuses a result without them); nullopt when reading
  // an older result that has none.
  std::optional<std::string> uri, digest;
  nlohmann::json extra = nlohmann::json::object();  // other keys, kept
};

struct DriveMounting {
  Vec3 value_deg = Vec3::Zero();                      // roll, pitch, yaw
  Vec3 sigma_deg = Vec3::Constant(kUnknownSigma);     // +inf: not stated
  nlohmann::json extra = nlohmann::json::object();    // "nominal", "lever_arm_m", …
};

// One observation's innovation consistency in "consistency" (fit drive: position, velocity, attitude,
// nhc, zupt, zero_rate): the counts and the time-average NIS. Absent figures: nullopt.
struct NisConsistency {
  std::optional<std::string> equation;                 // where the observation's equation is
  std::optional<long> epochs, rejected, forced;        // epochs used, rejected by the gate, forced
  std::optional<double> mean_nis, expected_nis;        // expected: the observation's degrees of freedom
  std::optional<double> fraction_within_95pct;         // of the used epochs, NIS under the 95 % bound
};

// "qc.outages" (fit drive on a GNSS-only drive, docs/in-motion.md "Outage QC"): simulated GNSS
// outages navigated inertial-only with each set; errors in m against the fixes.
struct OutageLengthFigures {  // one set at one outage length
  double length_s = 0;
  std::optional<double> count, median_max_m, max_max_m, median_end_m, max_end_m;
};
struct OutageSetFigures {
  std::string name;
  std::vector<OutageLengthFigures> per_length;
};
struct OutageRunFigures {  // one outage
  std::optional<double> start_s, length_s, fixes;
  std::map<std::string, double> max_m, end_m;  // by set name
};
struct OutageQc {
  std::optional<std::string> sample, aided_by, error;
  std::optional<double> fix_sigma_h_m;        // the fixes' median stated horizontal σ
  std::vector<std::string> not_placed;        // the reason of each requested outage not placed ("" not stated)
  std::vector<OutageSetFigures> sets;
  std::vector<OutageRunFigures> outages;
};

// "qc" of fit drive's ΔS QC (docs/in-motion.md "QC"): each set navigated inertial-only from from_s
// for horizon_s; ΔS in m. Numbers written as null read as NaN.
struct CpeSet {
  std::optional<std::string> name;
  std::optional<double> final_cpe_m, max_cpe_m;
  std::map<std::string, double> cpe_m_at;  // ΔS at the marks, by the mark as written ("10", "30", …)
  std::vector<double> series_t_s, series_cpe_m;  // "cpe_series" (issue 16); empty when absent
};
struct CpeQc {
  std::optional<double> from_s, horizon_s;
  std::optional<std::string> sample;
  std::vector<CpeSet> sets;
  std::optional<std::vector<double>> series_t_s;            // older results: "series": {"t_s", NAME: […]}
  std::map<std::string, std::vector<double>> series;        // by set name
};

// The antenna blocks of `fit drive --estimate lever,time` ("lever_arm_m", "time_offset_s"): the
// estimate, its σ and prior σ; observable when σ < prior / 2.
struct LeverArmEstimate {
  Vec3 value = Vec3::Zero(), sigma = Vec3::Zero(), nominal = Vec3::Zero();  // m, reference body axes
  Vec3 correction = Vec3::Zero();  // the estimated state, value - nominal as written
  double prior = 0;
  std::array<bool, 3> observable{};
};
struct TimeOffsetEstimate {
  double value = 0, sigma = 0, prior = 0;  // s
  bool observable = false;
};
// "adaptive_noise": how far the navigation noise variance was scaled up.
struct AdaptiveNoiseSummary {
  double scale_max = 1, scale_end = 1;
  long increases = 0;
};

// "effects": the catalogue terms the fit applied (names of the effect catalogue), those it ignored
// with why, and the time-stamp offset τ it applied (s; absent when none).
struct EffectsUse {
  std::vector<std::string> applied;
  std::vector<std::pair<std::string, std::string>> ignored;  // key, reason
  std::optional<double> time_offset_s;
};

struct DriveResult {
  std::string format;  // kDriveResultFormat; empty in older results without the key
  DeviceId device;     // model may be empty in older results
  DriveRecording recording;
  std::string reference_system;                      // empty: not stated
  std::optional<std::pair<double, double>> window_s;  // the fit window
  std::optional<std::string> observations;
  std::optional<bool> smoothed;
  CoefficientSet coefficients;               // totals relative to the raw sensor output (+ catalogue keys)
  std::optional<CoefficientSet> correction;  // relative to the input set
  std::optional<DriveMounting> mounting;     // "mounting_rpy_deg"
  std::optional<DeterminedBy> determined_by;
  nlohmann::json priors;       // object or null (absent); "mode" and "device_class" read below
  std::string priors_mode, priors_device_class;  // read from priors (empty when not stated); not written
  nlohmann::json consistency;  // object or array, or null (absent); written as is
  std::map<std::string, NisConsistency> nis;  // read from consistency (object form), by observation
  nlohmann::json qc;           // object or array, or null (absent); written as is
  std::optional<OutageQc> outages;  // read from qc.outages
  CpeQc cpe;                        // read from qc (object form); empty otherwise
  std::optional<LeverArmEstimate> lever_arm;          // read from extra "lever_arm_m"
  std::optional<TimeOffsetEstimate> time_offset;      // read from extra "time_offset_s"
  std::optional<AdaptiveNoiseSummary> adaptive_noise;  // read from extra "adaptive_noise"
  std::optional<EffectsUse> effects;                   // read from extra "effects"
  nlohmann::json extra = nlohmann::json::object();  // every other top-level key, as written
};

// True when a parsed file is a RESULT.json (its format says so, or it has no format and carries
// "coefficients") rather than a coefficients.json.
bool is_drive_result(const nlohmann::json& j);

DriveResult drive_result_from_json(const nlohmann::json& j, const std::string& file);
nlohmann::json drive_result_to_json(const DriveResult& r);

// The typed readings of the sections kept as written (nis, cpe, outages, lever_arm, time_offset,
// adaptive_noise, effects) from r.consistency, r.qc and r.extra: drive_result_from_json calls it, and the
// writer after building those sections.
void read_typed_sections(DriveResult& r, const std::string& file);

// "consistency" and "qc.outages" alone, as drive_result_from_json reads them.
std::map<std::string, NisConsistency> nis_consistency_from_json(const nlohmann::json& consistency, const std::string& file);
OutageQc outage_qc_from_json(const nlohmann::json& outages, const std::string& file);
CpeQc cpe_qc_from_json(const nlohmann::json& qc, const std::string& file);

// "determined_by" alone (nullopt when absent or null), as drive_result_from_json reads it.
std::optional<DeterminedBy> determined_by_from_json(const nlohmann::json& result, const std::string& file);

}  // namespace calbench
