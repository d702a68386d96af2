#!/usr/bin/env bash
# Issue 36, acceptance 4: `calbench diagnose` on the real recordings in ../shared/data (or REAL_DATA):
# the PSINS vehicle drive (as is, and with --device-class "consumer MEMS", since its meta.json names no
# known class and the in-motion filter needs one) and the GNSS-only RTK walk. Writes the text outputs,
# stamped, to docs/validation/diagnose-real-recordings.md (VALIDATION_NAME=OTHER.md).
# Usage: bench/diagnose/real_runs.sh [BUILD_DIR]
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
command="$(env | { grep -E '^REAL_' || true; } | sort | tr '\n' ' ')bench/diagnose/real_runs.sh $*"
BUILD=$(cd "${1:-build}" && pwd)
data=${REAL_DATA:-$here/../shared/data}
run() {  # TITLE ARGS...
  echo "## $1"; shift
  echo
  echo "\`calbench diagnose $(echo "$@" | sed "s|$data|../shared/data|g")\` (exit status shown last)"
  echo
  echo '```'
  set +e
  "$BUILD/calbench" diagnose "$@" 2>&1 | sed "s|$data|../shared/data|g"
  echo "exit status ${PIPESTATUS[0]}"
  set -e
  echo '```'
  echo
}
{
  run "PSINS vehicle drive (meta.json device model as given)" "$data/psins-vehicle-100s"
  run "PSINS vehicle drive, in-motion filter as a consumer-grade MEMS" "$data/psins-vehicle-100s" --device-class "consumer MEMS"
  run "RTK walk (GNSS-only)" "$data/rtk-walk-135s"
} | "$here/scripts/validation-stamp" "${VALIDATION_NAME:-diagnose-real-recordings.md}" \
      "The diagnosis on the real recordings (\`bench/diagnose/real_runs.sh\`)" "$command"
