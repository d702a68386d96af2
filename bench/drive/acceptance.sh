#!/usr/bin/env bash
# Acceptance measurement of the two-stage calibration (issues 5, 16; ~10 simulated 35-minute
# drives at 2460 Hz, in memory): 3σ coverage of gyro drift, accelerometer bias, scale and skew
# estimates and of the mounting; out-of-sample inertial-only ΔS over 10 minutes, bench-only vs
# bench + in-motion; gyro drift with --obs pos,vel vs pos,vel,att; and the fit throughput.
# Usage: bench/drive/acceptance.sh [BUILD_DIR]   (INMOTION_SEEDS=N to change the number of seeds)
set -euo pipefail
BUILD=${1:-build}
cmake --build "$BUILD" --target calbench_perf >/dev/null
INMOTION_ACCEPTANCE=1 "$BUILD/tests/calbench_perf" --benchmark_filter='BM_InMotion_' --benchmark_counters_tabular=true
