// Bench plan files (TOML). Format: docs/bench-calibration.md; example: bench/plans/factory.toml.
#pragma once
#include <filesystem>

#include "calibration/bench_plan.hpp"

namespace calbench {

// Parse and validate a plan; errors name the file, line and key.
// A plan as the station reads it: the bench plan and the kind of table it is for. [plan] kind =
// "positions": a position-only table or indexing head (no rate mode, nominal angles only): static
// steps and the moves between them, on one mount; the station records it as one continuous multipos
// recording (moves included: the gyros see the rotations) and fits it without a reference
// (docs/devices.md "Positions plans"). "rates" (default): a rate table, every other plan.
struct StationPlan : BenchPlan {
  bool position_only = false;
};

StationPlan load_plan(const std::filesystem::path& file);

}  // namespace calbench
