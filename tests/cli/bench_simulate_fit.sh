#!/usr/bin/env bash
# simulate bench → fit bench (both methods, --json) on a short plan; estimates within 4σ of truth.
set -euo pipefail
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
"$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth random --seed 11 --out "$tmp/rec"
test -s "$tmp/rec/truth.json"
grep -q '"status": "complete"' "$tmp/rec/meta.json"
for m in lsq ekf; do
  "$CALBENCH" fit bench "$tmp/rec" --method $m --out "$tmp/$m.json" --json > "$tmp/$m.out"
  python3 - "$tmp/$m.out" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
assert j["coefficients"]["format"] == "calbench-coefficients/1"
assert j["not_determined"] == [], j["not_determined"]
assert len(j["steps"]) == 12, len(j["steps"])
for s in j["steps"]:
    assert s["samples"] > 0 and len(s["gyro_resid_rms_rad_s"]) == 3
arw = max(j["white_noise"]["gyro_rad_s_per_sqrt_hz"]) * 180 / 3.141592653589793 * 60
assert 0.2 < arw < 0.35, arw   # the simulated ADIS16488A has 0.26 °/√h
PY
  python3 "$SRC/tests/data/compare_coeffs.py" "$tmp/$m.json" "$tmp/rec/truth.json" 4
done
# --model paper: the scale factors are not estimated and carry no σ.
"$CALBENCH" fit bench "$tmp/rec" --model paper --out "$tmp/paper.json" > /dev/null
python3 - "$tmp/paper.json" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))
assert all(c["gyro"]["sigma_M"][i][i] is None for i in range(3)), c["gyro"]["sigma_M"]
assert c["calibration"]["model"] == "paper"
PY
# Refuses to overwrite a recording without --force.
if "$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth random --out "$tmp/rec" 2> "$tmp/err"; then
  echo "overwrote without --force"; exit 1; fi
grep -q "already holds a recording" "$tmp/err"
echo "bench simulate/fit: ok"
