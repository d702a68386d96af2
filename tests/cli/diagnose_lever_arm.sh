#!/usr/bin/env bash
# diagnose through files: simulate a bench run with a concealed lever arm, diagnose it (fit first),
# check the JSON names lever_arm on the accelerometers with the right value, that IMPROVED.json
# carries the documented key, that diagnosing again with IMPROVED.json finds nothing, and bad input.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$CALBENCH" simulate bench --plan "$SRC/bench/plans/diagnose.toml" --truth random --seed 7 --out "$T/rec" \
  --inject lever_arm:z=0.005 >/dev/null
"$CALBENCH" diagnose "$T/rec" --json --out "$T/improved.json" --report "$T/report.html" >"$T/d.json"
python3 - "$T" <<'PY'
import json, sys
t = sys.argv[1]
d = json.load(open(t + "/d.json"))
f = [x for x in d["findings"] if x["effect"] == "lever_arm"]
assert f, d["findings"]
f = f[0]
assert f["sensor"] == "accel" and f["axis"] == "z", f
assert abs(f["value"][2] - 0.005) < 0.001, f
assert f["rms_after"] <= 0.2 * f["rms_before"], f
imp = json.load(open(t + "/improved.json"))
assert abs(imp["lever_arm"]["m"][2] - 0.005) < 0.001, imp["lever_arm"]
PY
grep -q "<svg" "$T/report.html" || { echo "report has no plot"; exit 1; }
# Issue 17 item 6: the plot's x axis names its unit, "before" is drawn as open circles under the
# "after" dots (both visible), and the page scales wide content instead of cutting it.
grep -Eq "(rate|w_[xyz]|f_[xyz]|temperature|dT/dt|time|angle) \((rad/s|m/s²|°C|°C/s|s|°)\)" "$T/report.html" \
  || { echo "plot x axis without a unit"; exit 1; }
grep -q "svg{max-width:100%" "$T/report.html" || { echo "wide plots are cut, not scaled"; exit 1; }
"$CALBENCH" diagnose "$T/rec" --coeffs "$T/improved.json" --json >"$T/d2.json"
python3 -c "import json,sys; d=json.load(open('$T/d2.json')); assert not [f for f in d['findings'] if f['effect']=='lever_arm'], d['findings']"
# Bad input: unknown effect → exit 2 with the option named.
set +e
"$CALBENCH" simulate bench --plan "$SRC/bench/plans/diagnose.toml" --truth random --out "$T/bad" --inject wobble:x=1 2>"$T/err"
rc=$?
set -e
[ "$rc" = 2 ] || { echo "expected exit 2, got $rc"; exit 1; }
grep -q "unknown effect" "$T/err" || { cat "$T/err"; exit 1; }
echo ok
