#!/usr/bin/env bash
# A bench recording written by another tool (tests/data/foreign_bench.py knows only the spec):
# increments at 200 Hz, reference at 50 Hz, reordered and unknown columns, gaps. Both methods
# must recover the unit within 3σ and gyro M within 30 ppm.
set -euo pipefail
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
for seed in 1 2; do
  python3 "$SRC/tests/data/foreign_bench.py" "$tmp/rec$seed" $seed
  for m in lsq ekf; do
    "$CALBENCH" fit bench "$tmp/rec$seed" --method $m --out "$tmp/c.json" > /dev/null
    python3 "$SRC/tests/data/compare_coeffs.py" "$tmp/c.json" "$tmp/rec$seed/truth.json" 3 200
    python3 - "$tmp/c.json" "$tmp/rec$seed/truth.json" <<'PY'
import json, sys
e, t = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
worst = max(abs(e["gyro"]["M"][i][j] - t["gyro"]["M"][i][j]) for i in range(3) for j in range(3))
assert worst < 30e-6, worst
assert e["device"]["serial"] == "FOREIGN-1"
PY
  done
done
echo "foreign recording: ok"
