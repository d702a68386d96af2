#!/usr/bin/env bash
# Issue-7 acceptance sweep of the DRIVE diagnosis (tests/perf/diagnose_drive_sweep_bench.cpp; slow:
# ~190 in-memory simulations of the 3.6-minute test route tests/data/drive_diag_route.toml, each
# diagnosed): clean drives (false findings, anything unexplained; DIAGNOSE_DRIVE_CLEAN_SEEDS, default
# 40) and every drive catalogue effect × 3 magnitudes around its detection limit ×
# DIAGNOSE_DRIVE_SWEEP_SEEDS seeds, axes and signs (default 5), plus two effects at once: detection,
# right sensor/axis, value error, cut of the systematic residual, other findings, unexplained.
# Prints one row per benchmark with its counters, then (with jq) writes the same as Markdown, stamped
# with the commit, date and command, to docs/validation/diagnose-drive-sweep.md (with
# DIAGNOSE_DRIVE_COEFFS=bench: diagnose-drive-sweep-factory-coeffs.md; VALIDATION_NAME=OTHER.md for a
# partial run); runs that miss a criterion are listed on stderr with seed and --inject options.
# DIAGNOSE_DRIVE_COEFFS=bench: each unit first fitted on the simulated factory plan, the drive
# diagnosed with those coefficients (--coeffs; docs/validation/diagnosis-drive-log.md).
# Usage: bench/diagnose/drive_sweep.sh [BUILD_DIR] [extra benchmark args, e.g. --benchmark_filter=lever_arm]
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
command="$(env | { grep -E '^DIAGNOSE_' || true; } | sort | tr '\n' ' ')bench/diagnose/drive_sweep.sh $*"
name=diagnose-drive-sweep.md title="Diagnosis sweep on drives (\`bench/diagnose/drive_sweep.sh\`)"
if [ "${DIAGNOSE_DRIVE_COEFFS:-}" = bench ]; then
  name=diagnose-drive-sweep-factory-coeffs.md
  title="Diagnosis sweep on drives with the factory coefficients (\`DIAGNOSE_DRIVE_COEFFS=bench\`)"
fi
BUILD=${1:-build}
shift || true
cmake --build "$BUILD" --target calbench_perf >/dev/null
json=$(mktemp /tmp/drive_sweep.XXXXXX.json)
md=$(mktemp /tmp/sweep.XXXXXX.md)
trap 'rm -f "$json" "$md"' EXIT
DIAGNOSE_DRIVE_SWEEP=1 "$BUILD/tests/calbench_perf" \
  --benchmark_filter="${DIAGNOSE_DRIVE_SWEEP_FILTER:-BM_DiagnoseDrive_Sweep}" \
  --benchmark_counters_tabular=true --benchmark_out="$json" --benchmark_out_format=json "$@"
command -v jq >/dev/null || { echo "no jq: docs/validation/ not written" >&2; exit 0; }
# The columns are those docs/validation/diagnosis-*-log.md and scripts/check-docs read (cells by row and header).
{
jq -r '
  def pct: if . == null or (type == "number" and isnan) then "–" else (. * 10 | round / 10 | tostring) end;
  [.benchmarks[] | select(.name | test("SweepClean"))][] |
    "**Clean drives: \(.runs) seeds, no finding in \(.no_finding_pct | pct) %, \(.false_findings) false findings, \(.runs_with_unexplained) with something unexplained; χ²/dof before \(.chi2_dof_min * 100 | round / 100)–\(.chi2_dof_max * 100 | round / 100) (median \(.chi2_dof_median * 100 | round / 100)).**"
' "$json"
echo
echo "| effect / magnitude | runs | detected | right sensor, axis | value within 20 % | value within its 2σ | drift σ·√(2/τ) within 20 % | value error median / max | cut ≥ 80 % or to floor (measurable) | cut not measurable | runs with another finding | scale_factor beside a nonlinearity | runs with unexplained | all criteria |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
jq -r '
  def pct: if . == null or (type == "number" and isnan) then "–" else (. * 10 | round / 10 | tostring) end;
  .benchmarks[] | select(.name | test("SweepClean") | not) | select(.runs != null) |
    "| \(.name | sub("^BM_DiagnoseDrive_Sweep/"; "") | sub("/iterations:1$"; "")) | \(.runs) | \(.detected_pct | pct) % | \(.right_axis_pct | pct) % | \(.value_within20_pct | pct) % | \(.value_within_2sigma_pct | pct) % | \(.random_walk_within20_pct | pct) % | \(.value_err_median_pct | pct) / \(.value_err_max_pct | pct) % | \(.cut_ge80_pct | pct) % | \(.cut_not_measurable) | \(.other_findings_runs) | \(.scale_factor_companion_runs // 0) | \(.unexplained_runs) | \(.all_criteria_pct | pct) % |"
' "$json"
} > "$md"
# Only a table made whole is written (set -e stops here when jq fails).
"$here/scripts/validation-stamp" "${VALIDATION_NAME:-$name}" "$title" "$command" < "$md"
