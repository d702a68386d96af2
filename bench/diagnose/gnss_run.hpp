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
#include "calibration/diagnosis/innovation_conditions.hpp"

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

// A term of the logger or receiver that fit drive measured (sample timing, fix velocity latency),
// tested by the innovations: the base filter against the same filter without it.
struct GnssLoggerTest {
  std::string name, value;  // "sample timing", "(stamp scatter σ 1.99 ms; …)"
  double value_ms = 0;      // the stamps' σ, or the velocity's latency
  long epochs_compared = 0; // innovation epochs both runs have (the Δχ² is over these)
  double dchi2 = 0, dchi2_over_phi = 0;
  bool confirmed = false;   // Δχ²/φ ≥ the finding threshold
};

// Where the innovations grow by motion condition (innovation_conditions.hpp), per observation type
// (position, velocity): the base filter, the final model, and the base filter without the logger's
// terms (logger_compared: some term was measured).
struct GnssConditions {
  std::vector<ConditionBreakdown> base[2], final_model[2], without_logger[2];
  bool logger_compared = false;
  double phi_base = 1;
  // The adaptive noise scale the filter without the logger's terms reached, and ended at.
  double without_scale_max = 1, without_scale_end = 1;
};

struct GnssDiagRun {
  std::string dir, device_class;
  RecordingMeta meta;
  bool coeffs_given = false;
  CoefficientSet current, improved;
  std::vector<GnssHypothesis> hypotheses;
  HypothesisSearchResult search;
  double phi = 1;                           // overdispersion of the final model's innovations (after the withdrawals)
  // Issue 36's rule on the remainder: the final model's innovations read as noise up to φ 1.5; beyond,
  // every finding is "partial" (it raised the likelihood past the threshold, Δχ²/φ ≥ 40, but a
  // model error the candidates do not cover remains, and the filter's σ do not include it).
  static constexpr double kNoisePhi = 1.5;
  bool remainder_is_noise() const { return phi <= kNoisePhi; }
  std::vector<HypothesisStep> overdispersed;  // accepted, then withdrawn: Δχ²/φ below the threshold
  std::vector<double> overdispersed_phi;      // the φ each was judged against (of the model that held it)
  long epochs = 0, rows = 0;   // innovation epochs (position + velocity) and scalar observations
  DiagnoseResult core;         // findings, withdrawn, improved_terms (the drive's JSON schema)
  DriveInnovations innovations;  // before: the base filter; after: the final model's
  // What the base filter's fit measured of the logger and receiver (issue 53: RESULT.json
  // sample_timing, gnss_velocity_latency; modelled in every run) and its adaptive noise scale.
  nlohmann::json logger;
  std::vector<GnssLoggerTest> logger_tests;
  GnssConditions conditions;
  double cpu_s = 0;
};

GnssDiagRun run_gnss_diagnosis(const std::string& dir, const DriveCoeffs* coeffs, const std::string& device_class);
nlohmann::json gnss_diagnosis_json(const GnssDiagRun& run);
std::string gnss_diagnosis_text(const GnssDiagRun& run);
// Where the innovations grow by motion condition, the logger's terms tested, what remains
// (gnss_conditions.cpp).
nlohmann::json gnss_conditions_json(const GnssDiagRun& run);
std::string gnss_conditions_text(const GnssDiagRun& run);
// One finding's sentence: what, value ± σ in display units, the Δχ² of the innovations (and Δχ²/φ,
// the figure the threshold was applied to, when φ > 1), its status when not established.
std::string gnss_finding_sentence(const DiagFinding& f, double phi);

}  // namespace calbench
