// The fit-quality figures of a bench fit (common/fit_quality.hpp) from its result: χ²/dof per triad
// axis and the mean residual of every plan step, the step's kind from its rate (|ω| > 1 °/s: a rate
// step). The fit writes them into its coefficients (bench/bench_recording.hpp); approval gates on them.
#pragma once
#include "calibration/bench_fit.hpp"
#include "common/fit_quality.hpp"

namespace calbench::qc {

BenchFitQuality bench_fit_quality(const BenchFitResult& r);

}  // namespace calbench::qc
