#!/usr/bin/env bash
# Issue-7 acceptance sweep of the bench diagnosis (slow: ~150 in-memory simulations of the 6-minute
# diagnosis plan, each diagnosed; several minutes on two cores): clean recordings (false findings,
# DIAGNOSE_CLEAN_SEEDS, default 40) and every catalogue effect × 2–3 magnitudes × DIAGNOSE_SWEEP_SEEDS
# seeds and axes (default 3): detection, right sensor/axis, value error, cut of the systematic
# residual, other findings. Prints one row per benchmark with its counters, then writes the same as
# Markdown, stamped with the commit, date and command, to docs/validation/diagnose-bench-sweep.md
# (VALIDATION_NAME=OTHER.md for a partial run, e.g. one DIAGNOSE_SWEEP_FILTER; needs jq).
# Usage: bench/diagnose/sweep.sh [BUILD_DIR] [extra benchmark args, e.g. --benchmark_filter=lever_arm]
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
command="$(env | { grep -E '^DIAGNOSE_' || true; } | sort | tr '\n' ' ')bench/diagnose/sweep.sh $*"
BUILD=${1:-build}
shift || true
cmake --build "$BUILD" --target calbench_perf >/dev/null
json=$(mktemp /tmp/sweep.XXXXXX.json)
md=$(mktemp /tmp/sweep.XXXXXX.md)
trap 'rm -f "$json" "$md"' EXIT
DIAGNOSE_SWEEP=1 "$BUILD/tests/calbench_perf" --benchmark_filter="${DIAGNOSE_SWEEP_FILTER:-BM_Diagnose_Sweep}" \
  --benchmark_counters_tabular=true --benchmark_out="$json" --benchmark_out_format=json "$@"
command -v jq >/dev/null || { echo "no jq: docs/validation/ not written" >&2; exit 0; }
# The columns are those docs/validation/diagnosis-*-log.md and scripts/check-docs read (cells by row and header).
{
jq -r '
  def pct: if . == null or (type == "number" and isnan) then "–" else (. * 10 | round / 10 | tostring) end;
  [.benchmarks[] | select(.name | test("SweepClean"))] | select(length > 0) |
    (map(.runs) | add) as $n | (map(.runs * .no_finding_pct / 100 | round) | add) as $ok |
    "**Clean recordings: " + (map("\(.runs) on \(.name | sub("^BM_Diagnose_SweepClean"; "") | sub("/iterations:1$"; "") |
      if . == "" then "the diagnosis plan" elif . == "Factory" then "the factory plan" elif . == "Thermal" then "`thermal_short`" elif . == "Wedge" then "the wedge plan" else "`thermal_updown`" end)") | join(", ")) +
    ": no finding in \($ok) of \($n), \(map(.false_findings) | add) false findings, \(map(.runs_with_unexplained) | add) with something unexplained.**"
' "$json"
echo
echo "| effect / magnitude | runs | detected | right sensor, axis | value within 20 % | value within its 2σ | value error median / max | cut ≥ 80 % (measurable) | cut not measurable | runs with another finding | ambiguous: detected / missed but declared | all criteria |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
jq -r '
  def pct: if . == null or (type == "number" and isnan) then "–" else (. * 10 | round / 10 | tostring) end;
  .benchmarks[] | select(.name | test("SweepClean") | not) | select(.runs != null) |
    "| \(.name | sub("^BM_Diagnose_Sweep/"; "") | sub("/iterations:1$"; "")) | \(.runs) | \(.detected_pct | pct) % | \(.right_axis_pct | pct) % | \(.value_within20_pct | pct) % | \(.value_within_2sigma_pct | pct) % | \(.value_err_median_pct | pct) / \(.value_err_max_pct | pct) % | \(.cut_ge80_pct | pct) % | \(.cut_not_measurable_runs) | \(.other_findings_runs) | \(.detected_ambiguous_runs // 0) / \(.missed_but_alternative_runs // 0) | \(.all_criteria_pct | pct) % |"
' "$json"
} > "$md"
# Only a table made whole is written (set -e stops here when jq fails).
"$here/scripts/validation-stamp" "${VALIDATION_NAME:-diagnose-bench-sweep.md}" \
      "Diagnosis sweep on the bench (\`bench/diagnose/sweep.sh\`)" "$command" < "$md"
