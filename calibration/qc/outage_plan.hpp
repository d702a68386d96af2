// Simulated GNSS outages on a GNSS-only drive (docs/in-motion.md, "Outage QC"): where they are
// placed, and the statistics of their errors. No I/O; the navigation through each outage is
// inertial_qc.hpp's InertialRun, the pass over the recording bench/drive/outage_qc.cpp.
//
// Placement rule (deterministic): the requested lengths are cycled `count` times (15, 30, 60, 15,
// 30, 60, ...); an outage starts only at an eligible fix epoch (the aided filter converged there,
// the vehicle moving, at or after `earliest_s`); the span from the first eligible epoch A to the
// last fix B holds the sequence with `gap_s` between an outage's end and the next start, the slack
// of the span shared equally before the first, between the outages and after the last (evenly
// spread over the drive, and not right at the first converged epoch). Each planned start is
// moved to the first eligible epoch at or after it (and at least gap_s after the previous end);
// outages that do not fit the span (dropped from the end of the sequence) or find no eligible start
// early enough to end by B are listed as not placed, with the reason.
#pragma once
#include <string>
#include <vector>

namespace calbench::qc {

struct OutageRequest {
  std::vector<double> lengths_s{15, 30, 60};
  int count = 3;        // outages per length
  double gap_s = 30;    // least time between an outage's end and the next start
  double earliest_s = -1e300;  // no outage starts before (the end of a fit window)
};

struct PlannedOutage {
  double start_s = 0, length_s = 0;
  std::size_t epoch = 0;  // index of the start epoch in the candidate list
};
struct SkippedOutage {
  double length_s = 0;
  std::string reason;
};
struct OutagePlan {
  std::vector<PlannedOutage> outages;  // in time order
  std::vector<SkippedOutage> not_placed;
};

// t: fix epoch times (ascending); eligible: whether an outage may start there (same size);
// t_end: the last fix. Lengths must be > 0 and count >= 1 (checked by the caller).
OutagePlan plan_outages(const std::vector<double>& t, const std::vector<bool>& eligible, double t_end, const OutageRequest& req);

}  // namespace calbench::qc
