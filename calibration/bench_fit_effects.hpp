// Bench fit with catalogue terms held fixed (issue 7, item 4: "the estimators understand the extra
// keys"). A coefficient set such as diagnose's IMPROVED.json carries terms beyond the spec's
// measured = (I + M)·true + b (docs/diagnosis.md). Here they are taken as known: the extra output
// they predict is computed at 0.05 s resolution (DiagData sub-blocks: within-revolution effects,
// nonlinear terms and the time offset need the fine grid, not 1 s means), subtracted from the
// measurements, and the corrected ~1 s blocks go to the unchanged lsq or ekf fit of b and M.
// A correlated_drift key replaces the data-sheet drift prior (σ, τ) of its triad.
// The plain `fit bench` path (bench/bench_recording.cpp → fit_bench) is not touched.
#pragma once
#include <string>
#include <vector>

#include "calibration/bench_fit.hpp"
#include "calibration/diagnosis/diag_data.hpp"
#include "calibration/effects/effect_registry.hpp"

namespace calbench {

// The DiagData parent blocks (~1 s inside plan steps) as bench-fit blocks, with the extra output of
// `e` (predict_extra per sub-block) removed from the measured means. The within-block scatter is
// that of the corrected residual (sub-block scatter plus the spread of the sub-block means).
std::vector<BenchBlock> blocks_without_effects(const DiagData& d, const EffectTerms& e);

// `opt` with the drift prior of a triad replaced where `e` carries correlated_drift.
BenchFitOptions options_with_effects(BenchFitOptions opt, const EffectTerms& e);

// fit_bench on blocks_without_effects with options_with_effects. When `sigma` (1σ of the terms, same
// layout, e.g. from IMPROVED.json) is given, the uncertainty of the held terms is propagated into
// the σ of b and M: σ² += Σ_params (∂estimate/∂param · σ_param)², the derivative by refitting with
// each parameter moved by its σ. (For terms estimated jointly with b and M on the same data this is
// the marginal σ of the joint fit; without it the σ would be conditional on exact terms.)
BenchFitResult fit_bench_with_effects(const DiagData& d, const EffectTerms& e, const BenchFitOptions& opt,
                                      const EffectTerms* sigma = nullptr);

// effect_ids_present (the names of the terms `e` carries): effect_registry.hpp.

}  // namespace calbench
