#!/usr/bin/env bash
# Acceptance measurement of the two-stage calibration (issues 5, 16; ~10 simulated 35-minute
# drives at 2460 Hz, in memory): 3σ coverage of gyro drift, accelerometer bias, scale and skew
# estimates and of the mounting; out-of-sample inertial-only ΔS over 10 minutes, bench-only vs
# bench + in-motion; gyro drift with --obs pos,vel vs pos,vel,att; and the fit throughput.
# Prints the counters, then (with jq) writes every benchmark's counters as Markdown, stamped with the
# commit, date and command, to docs/validation/inmotion-acceptance-counters.md (VALIDATION_NAME to
# change it). docs/validation/inmotion-acceptance.md is the reading of such a run (per-seed lines
# from standard error, the comparison with the previous run), kept by hand and stamped likewise.
# Usage: bench/drive/acceptance.sh [BUILD_DIR]   (INMOTION_SEEDS=N to change the number of seeds)
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
command="$(env | { grep -E '^INMOTION_' || true; } | sort | tr '\n' ' ')bench/drive/acceptance.sh $*"
BUILD=${1:-build}
cmake --build "$BUILD" --target calbench_perf >/dev/null
json=$(mktemp /tmp/acceptance.XXXXXX.json)
md=$(mktemp /tmp/acceptance.XXXXXX.md)
trap 'rm -f "$json" "$md"' EXIT
INMOTION_ACCEPTANCE=1 "$BUILD/tests/calbench_perf" --benchmark_filter='BM_InMotion_' --benchmark_counters_tabular=true \
  --benchmark_out="$json" --benchmark_out_format=json
command -v jq >/dev/null || { echo "no jq: docs/validation/ not written" >&2; exit 0; }
# One table per benchmark (their counters differ): counter, value; repetitions as median rows only.
jq -r '
  .benchmarks[] | select((.aggregate_name // "median") == "median") |
    "## \(.run_name // .name)\n\nwall time \((.real_time // 0) * 1000 | round / 1000) \(.time_unit // "")\n\n| counter | value |\n|---|---|\n" +
    ([to_entries[] | select(.value | type == "number") |
      select(.key | test("^(real_time|cpu_time|iterations|repetitions|repetition_index|threads|family_index|per_family_instance_index)$") | not) |
      "| \(.key) | \(.value) |"] | join("\n")) + "\n"
' "$json" > "$md"
"$here/scripts/validation-stamp" "${VALIDATION_NAME:-inmotion-acceptance-counters.md}" \
  "In-motion acceptance counters (\`bench/drive/acceptance.sh\`)" "$command" < "$md"
