// The device report's part for one in-motion run and the set it produced: the drive recording with
// the digests of its files, the reference system, which stage determined each coefficient (bench →
// combined, with σ), ΔS(t) of every QC set over the whole horizon (inline SVG), the QC metrics
// with thresholds and in-/out-of-sample, and the innovation consistency with a stated test.
#pragma once
#include <string>
#include <vector>

#include "db/store.hpp"

namespace calbench::report {

std::string inmotion_section(db::Store& store, const db::InMotionRun& run, const db::CoefficientSetRecord& set,
                             const std::vector<db::CoefficientSetRecord>& sets);

}  // namespace calbench::report
