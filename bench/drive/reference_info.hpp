// RESULT.json "reference_system": a description of what an in-motion fit compared the MEMS with,
// read from the recording — the reference's own description (the comment of reference.csv), its
// rate and span, the 1σ used for each observation type and where it came from (sigma columns,
// --sigma-* or the filter's defaults), which observations were used, and the recording's notes.
#pragma once
#include <filesystem>
#include <limits>
#include <string>

#include "bench/drive/fit_drive.hpp"
#include "bench/io/recording.hpp"

namespace calbench {

// What the description needs of the aiding file, gathered from its rows as the fit reads them (the
// file is not read a second time): epochs, span, and the range of each σ column.
struct AidingStats {
  struct Range {
    double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
    void add(double v);
    bool any() const { return lo <= hi; }
  };
  long n = 0, with_vel = 0;
  double t0 = 0, t1 = 0;
  Range sp, sv, sa;  // reference.csv: σ position, velocity, attitude; gnss.csv: σ horizontal, vertical
  void add(const DriveRefRow& r);
  void add(const GnssRow& r);
};

std::string describe_reference(const std::filesystem::path& dir, const RecordingMeta& meta, const FitDriveArgs& a,
                               const inmotion::InMotionConfig& cfg, bool gnss, const AidingStats& stats);

}  // namespace calbench
