// Approval of a coefficient set: configurable QC thresholds, checked before draft → approved.
// Config file (JSON, units in the key names; every key optional, defaults for the ADIS16488A):
//   {"gyro":  {"max_abs_bias_dph": 3600, "max_abs_scale_ppm": 25000, "max_abs_skew_ppm": 5000,
//              "max_sigma_bias_dph": 10, "max_sigma_M_ppm": 500},
//    "accel": {"max_abs_bias_mg": 80, "max_abs_scale_ppm": 25000, "max_abs_skew_ppm": 5000,
//              "max_sigma_bias_mg": 2, "max_sigma_M_ppm": 500},
//    "allow_unknown_sigma": false, "require_qc": true, "required_qc_metrics": [],
//    "max_outage_median_m": {"15": 10, "30": 30, "60": 100},  (outage QC, GNSS-only drives; none by default)
//    "bench": {...}, "inmotion": {...}, "combined": {...}}     (the fit's quality: db/approval_quality.hpp)
// See docs/database.md.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "db/approval_quality.hpp"
#include "db/store.hpp"

namespace calbench::db {

struct TriadLimits {
  double max_abs_bias = 0;   // SI (rad/s or m/s²)
  double max_abs_scale = 0;  // dimensionless
  double max_abs_skew = 0;
  double max_sigma_bias = 0;
  double max_sigma_M = 0;
};

struct Thresholds {
  TriadLimits gyro, accel;
  bool allow_unknown_sigma = false;  // a σ of null (not estimated) refuses approval unless true
  bool require_qc = true;            // at least one QC result recorded with the set's run
  std::vector<std::string> required_qc_metrics;  // these metrics must be present (and pass)
  // Outage QC of a GNSS-only drive: per outage length (s), the largest median of the per-outage
  // maximum horizontal error (m) of the result set (metric outages.in-motion.Ls.median_max_m).
  // Checked where the run has the metric; none by default.
  std::map<double, double> max_outage_median_m;
  // The fit's quality (db/approval_quality.hpp): "bench", "inmotion" and "combined" in the file.
  FitQualityLimits quality = default_fit_quality_limits();
  std::string source = "built-in ADIS16488A defaults";
};

Thresholds default_thresholds();
// Parse a thresholds config (JSON text); unknown keys are errors (typos must not loosen a check).
Thresholds parse_thresholds(const std::string& text, const std::string& file);
Thresholds load_thresholds(const std::string& path);  // reads the file; InputError on problems

struct ApprovalCheck {
  bool ok = true;
  bool already = false;              // the set was approved (or provisioned) before: nothing changed
  std::vector<std::string> reasons;  // why not (empty when ok)
};
// check_verdict() and the status (only a draft can be approved).
ApprovalCheck check_approval(const CoefficientSetRecord& set, const std::vector<QcResult>& qc, const Thresholds& t,
                             const FitEvidence& ev = {});
// Every check of check_approval() except the status (that only a draft can be approved): whether
// a set, approved or not, meets the thresholds `t` (the device report's verdict).
ApprovalCheck check_thresholds(const CoefficientSetRecord& set, const std::vector<QcResult>& qc, const Thresholds& t);
// The verdict on a set whatever its status: check_thresholds() and the fit's quality
// (fit_quality_reasons of db/approval_quality.hpp on `ev`). The one verdict of approve_checked(),
// check_standing() (the device report) and the preview `fit drive` ends with.
ApprovalCheck check_verdict(const CoefficientSetRecord& set, const std::vector<QcResult>& qc, const FitEvidence& ev,
                            const Thresholds& t);
// Why a set cannot be approved because of its parent (a combined set refines an approved set: the
// parent must not be draft or revoked), or "" when the parent is fine or there is none.
std::string parent_reason(Store& store, const CoefficientSetRecord& set);
// Every check of approve_checked() except the status and the signature: the thresholds, the QC
// results of the set's run and the parent rule (the device report's verdict).
ApprovalCheck check_standing(Store& store, const CoefficientSetRecord& set, const Thresholds& t);
// The thresholds as readable lines in display units ("gyro |bias| <= 3600 °/h", ...).
std::vector<std::string> describe_thresholds(const Thresholds& t);

// Check and, when every check passes, approve (draft → approved), in one transaction. The store's
// actor signs: it must be a named operator (Actor::named) and, unless the database's four_eyes
// setting is "off", not the operator who stored the set. A refusal is recorded in the audit log
// with its reasons; the set stays draft.
ApprovalCheck approve_checked(Store& store, std::int64_t set_id, const Thresholds& t);

}  // namespace calbench::db
