// Bench plan files (TOML). Format: docs/bench-calibration.md; example: bench/plans/factory.toml.
#pragma once
#include <filesystem>

#include "calibration/bench_plan.hpp"

namespace calbench {

// Parse and validate a plan; errors name the file, line and key.
BenchPlan load_plan(const std::filesystem::path& file);

}  // namespace calbench
