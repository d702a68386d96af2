#!/usr/bin/env bash
# Issue 7, item 4 through files: a bench recording with a concealed lever arm biases `fit bench`;
# `diagnose --out IMPROVED.json` finds it; `fit bench --effects IMPROVED.json` holds the term fixed,
# gives b and M within 3σ of the simulator's truth.json and carries the lever_arm key into its
# output; a file without catalogue keys is an input error (exit 2).
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$CALBENCH" simulate bench --plan "$SRC/bench/plans/diagnose.toml" --truth random --seed 4 --out "$T/rec" \
  --inject lever_arm:z=0.004 >/dev/null
"$CALBENCH" diagnose "$T/rec" --out "$T/improved.json" >/dev/null
"$CALBENCH" fit bench "$T/rec" --out "$T/plain.json" >/dev/null
if python3 "$SRC/tests/data/compare_coeffs.py" "$T/plain.json" "$T/rec/truth.json" 3 >"$T/cmp_plain"; then
  echo "plain fit unexpectedly within 3 sigma despite the concealed lever arm"; cat "$T/cmp_plain"; exit 1
fi
"$CALBENCH" fit bench "$T/rec" --effects "$T/improved.json" --out "$T/fixed.json" --json >"$T/fixed_out.json"
python3 "$SRC/tests/data/compare_coeffs.py" "$T/fixed.json" "$T/rec/truth.json" 3
python3 - "$T" <<'PY'
import json, sys
t = sys.argv[1]
c = json.load(open(t + "/fixed.json"))
assert abs(c["lever_arm"]["m"][2] - 0.004) < 0.0008, c["lever_arm"]
assert c["calibration"]["effects_held_fixed"] == ["lever_arm"], c["calibration"]
j = json.load(open(t + "/fixed_out.json"))
assert j["effects_held_fixed"] == ["lever_arm"], j.get("effects_held_fixed")
PY
set +e
"$CALBENCH" fit bench "$T/rec" --effects "$T/rec/meta.json" 2>"$T/err"
rc=$?
set -e
[ "$rc" -eq 2 ] || { echo "expected exit 2, got $rc"; exit 1; }
grep -q "no catalogue key" "$T/err" || { cat "$T/err"; exit 1; }
echo "ok"
