// Outage QC of a GNSS-only drive (docs/in-motion.md, "Outage QC"): the paper's ΔS (eq 39) for
// drives without a reference INS. Simulated GNSS outages are placed over the drive
// (calibration/qc/outage_plan.hpp); each is navigated inertial-only with every coefficient set from
// the aided filter's MEMS navigation state at its start (position, velocity, attitude; recorded by
// OutageRecorder at every fix the filter handled), and the horizontal distance of the antenna from
// the fixes during the outage is its error. Used by `fit drive` (raw data, input set, result) and
// `qc` (the sets given) on recordings with gnss.csv.
#pragma once
#include <filesystem>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/drive/drive_stream.hpp"
#include "bench/drive/qc_drive.hpp"
#include "calibration/inmotion/inmotion_filter.hpp"
#include "calibration/qc/outage_plan.hpp"

namespace calbench {

struct OutageOptions {
  bool enabled = true;       // --outages none: off
  qc::OutageRequest request;  // lengths, count per length, gap (earliest_s: set by the caller)
  // Hook for a non-holonomic constraint during the outages (issue 34 item 4): the outages are
  // navigated inertial-only; true is refused until the NHC observation exists.
  bool nhc = false;
  // The lengths were given (--outages): one longer than the drive is then bad input; the default
  // lengths that do not fit are listed as not placed.
  bool lengths_given = false;
  // The logger's corrections the aided filter ran with (its states carry those stamps).
  LoggerCorrection logger;
};
// --outages: "15,30,60" (seconds, each > 0, at most 3600) or "none". InputError naming the option.
void parse_outage_lengths(const std::string& text, OutageOptions& o);
// The option values as one check (count >= 1, gap >= 0, nhc refused): InputError naming the option.
void check_outage_options(const OutageOptions& o);

// Where an outage may start: the aided filter took the fix, knows its heading to within
// kOutageMaxHeadingSigma (1σ) and the vehicle moves at kOutageMinSpeed or more (fix velocity, else
// the distance from the previous fix).
inline constexpr double kOutageMinSpeed = 1.0;              // m/s
inline constexpr double kOutageMaxHeadingSigmaDeg = 1.0;    // deg

struct OutageEpoch {
  double t = 0;           // fix time
  bool eligible = false;  // an outage may start here
  ins::NavState nav;      // the filter's MEMS navigation state after the fix
};

class OutageRecorder {
 public:
  // After every fix the filter handled (took: used, not rejected).
  void epoch(const inmotion::InMotionFilter& f, const inmotion::RefObs& r, bool took);
  const std::vector<OutageEpoch>& epochs() const { return epochs_; }

 private:
  std::vector<OutageEpoch> epochs_;
  bool have_prev_ = false;
  inmotion::RefObs prev_;
};

// The outages of `o` on the recording `dir` (gnss.csv) with every set, from the recorded epochs.
// aided_by and sample are stated in the JSON (docs/in-motion.md, RESULT.json qc.outages).
// A given length (lengths_given) longer than the fixes' span is bad input (InputError naming --outages).
nlohmann::json run_outage_qc(const std::filesystem::path& dir, const std::vector<QcSet>& sets,
                             const std::vector<OutageEpoch>& epochs, const OutageOptions& o, const std::string& aided_by,
                             const std::string& sample);
// The text summary: one line per length and set (median and largest of the per-outage maxima).
void print_outage_summary(const nlohmann::json& outages, std::ostream& os);

}  // namespace calbench
