// RESULT.json "reference_system": a description of what an in-motion fit compared the MEMS with,
// read from the recording — the reference's own description (the comment of reference.csv), its
// rate and span, the 1σ used for each observation type and where it came from (sigma columns,
// --sigma-* or the filter's defaults), which observations were used, and the recording's notes.
#pragma once
#include <filesystem>
#include <string>

#include "bench/drive/fit_drive.hpp"
#include "bench/io/recording.hpp"

namespace calbench {

std::string describe_reference(const std::filesystem::path& dir, const RecordingMeta& meta, const FitDriveArgs& a,
                               const inmotion::InMotionConfig& cfg, bool gnss = false);

}  // namespace calbench
