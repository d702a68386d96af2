#!/usr/bin/env bash
# The confusion tables of the diagnosis (issue 20): every catalogue effect of the sweep rows
# (bench/diagnose/sweep.sh, drive_sweep.sh) injected at its largest sweep magnitude on the factory
# plan, on the diagnosis plan, on the wedge plan, on the drive test route and on the default drive
# route (bench/routes/default.toml), DIAGNOSE_CONFUSION_SEEDS seeds each (default 5), against what
# the diagnosis names.
# Prints the tables and writes them, stamped, to docs/validation/diagnose-confusion.md
# (VALIDATION_NAME=OTHER.md for another file). ~45 min at 5 seeds on two cores.
# Usage: bench/diagnose/confusion.sh [BUILD_DIR]
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
command="$(env | { grep -E '^DIAGNOSE_' || true; } | sort | tr '\n' ' ')bench/diagnose/confusion.sh $*"
BUILD=${1:-build}
cmake --build "$BUILD" --target calbench_perf >/dev/null
md=$(mktemp /tmp/confusion.XXXXXX.md)
trap 'rm -f "$md"' EXIT
DIAGNOSE_SWEEP=1 DIAGNOSE_CONFUSION_OUT="$md" "$BUILD/tests/calbench_perf" --benchmark_filter='BM_Diagnose_Confusion' >/dev/null
DIAGNOSE_DRIVE_SWEEP=1 DIAGNOSE_CONFUSION_OUT="$md" "$BUILD/tests/calbench_perf" --benchmark_filter='BM_DiagnoseDrive_Confusion' >/dev/null
# The default route (35 minutes at 2460 Hz, in memory): the slow part (~30 min on two cores).
DIAGNOSE_DRIVE_SWEEP=1 DIAGNOSE_DRIVE_ROUTE=bench/routes/default.toml DIAGNOSE_CONFUSION_OUT="$md" \
  "$BUILD/tests/calbench_perf" --benchmark_filter='BM_DiagnoseDrive_Confusion' >/dev/null
[ -s "$md" ] || { echo "confusion.sh: no table written" >&2; exit 1; }
cat "$md"
{
  echo "Rows: the effect injected (name, magnitude, unit as in the sweep rows); columns: the effects the diagnosis"
  echo "named on any axis, counted per run; \"(n alt)\": runs where that finding lists the injected effect as not"
  echo "told apart (docs/diagnosis.md explains each such pair); \"truth not excited\": runs where the recording"
  echo "could not excite the injected term, which was therefore not a candidate."
  cat "$md"
} | "$here/scripts/validation-stamp" "${VALIDATION_NAME:-diagnose-confusion.md}" \
      "Confusion tables of the diagnosis (\`bench/diagnose/confusion.sh\`)" "$command"
