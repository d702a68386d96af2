#!/usr/bin/env bash
# Issue-7 acceptance sweep of the bench diagnosis (slow: ~150 in-memory simulations of the 6-minute
# diagnosis plan, each diagnosed; several minutes on two cores): clean recordings (false findings,
# DIAGNOSE_CLEAN_SEEDS, default 40) and every catalogue effect × 2–3 magnitudes × DIAGNOSE_SWEEP_SEEDS
# seeds and axes (default 3): detection, right sensor/axis, value error, cut of the systematic
# residual, other findings. Prints one row per benchmark with its counters.
# Usage: bench/diagnose/sweep.sh [BUILD_DIR] [extra benchmark args, e.g. --benchmark_filter=lever_arm]
set -euo pipefail
BUILD=${1:-build}
shift || true
cmake --build "$BUILD" --target calbench_perf >/dev/null
DIAGNOSE_SWEEP=1 "$BUILD/tests/calbench_perf" --benchmark_filter="${DIAGNOSE_SWEEP_FILTER:-BM_Diagnose_Sweep}" \
  --benchmark_counters_tabular=true "$@"
