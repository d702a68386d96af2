// `calbench diagnose` on a GNSS-only drive (meta.json, imu.csv, gnss.csv; no reference.csv): issue 34
// item 6, docs/diagnosis.md "GNSS-only drives". Without a reference attitude there is no predicted
// MEMS output (drive_data.hpp); the evidence is the GNSS-aided in-motion filter's innovations against
// the fixes. Each candidate effect of the registry that such a drive can show is a hypothesis of
// that filter (gnss_candidates(): an antenna block of `fit drive --estimate`, or the scale allowed to
// move from the given coefficients); the search and its rules are hypothesis_search()
// (calibration/diagnosis/drive_innovations.hpp), the statistics of the innovations before and after
// innovation_stats(). Output: the drive diagnosis's findings schema, IMPROVED.json with the
// catalogue keys (time_offset, lever_arm; scale_factor folded into M).
#pragma once
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "bench/diagnose/drive_run.hpp"

namespace calbench {

// Is `dir` a drive recording without reference.csv but with gnss.csv?
bool drive_is_gnss_only(const std::filesystem::path& dir);

struct GnssHypothesis {
  std::string name;            // "time_offset", "lever_arm", "scale_factor gyro", …
  Term term;                   // the registry term a finding is reported as (scale: axis −1, the triad)
  int nparams = 0;
  bool tested = true;          // false: not a candidate on this drive (why_not says why)
  std::string why_not;
};

struct GnssDiagRun {
  std::string dir, device_class;
  RecordingMeta meta;
  bool coeffs_given = false;
  CoefficientSet current, improved;
  std::vector<GnssHypothesis> hypotheses;
  HypothesisSearchResult search;
  double phi = 1;                           // overdispersion of the final model's innovations
  // Issue 36's rule on the remainder: the final model's innovations read as noise up to φ 1.5; beyond,
  // every finding is "partial" (it raised the likelihood past the threshold, Δχ²/φ ≥ 40, but a
  // model error the candidates do not cover remains, and the filter's σ do not include it).
  static constexpr double kNoisePhi = 1.5;
  bool remainder_is_noise() const { return phi <= kNoisePhi; }
  std::vector<HypothesisStep> overdispersed;  // accepted, then withdrawn: Δχ²/φ below the threshold
  long epochs = 0, rows = 0;   // innovation epochs (position + velocity) and scalar observations
  DiagnoseResult core;         // findings, withdrawn, improved_terms (the drive's JSON schema)
  DriveInnovations innovations;  // before: the base filter; after: the final model's
  // What the base filter's fit measured of the logger and receiver (issue 53: RESULT.json
  // sample_timing, gnss_velocity_latency; modelled in every run) and its adaptive noise scale.
  nlohmann::json logger;
  double cpu_s = 0;
};

GnssDiagRun run_gnss_diagnosis(const std::string& dir, const DriveCoeffs* coeffs, const std::string& device_class);
nlohmann::json gnss_diagnosis_json(const GnssDiagRun& run);
std::string gnss_diagnosis_text(const GnssDiagRun& run);
// One finding's sentence: what, value ± σ in display units, the Δχ² of the innovations (and Δχ²/φ,
// the figure the threshold was applied to, when φ > 1), its status when not established.
std::string gnss_finding_sentence(const DiagFinding& f, double phi);

}  // namespace calbench
