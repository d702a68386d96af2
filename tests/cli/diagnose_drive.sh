#!/usr/bin/env bash
# diagnose on drives through files: simulate a drive with a concealed time offset and lever arm
# (simulate drive --inject), diagnose it (no --coeffs: b and M fitted on the drive), check the JSON
# names both with the right values and that IMPROVED.json carries them, that diagnosing again with
# IMPROVED.json finds nothing new, the real PSINS drive runs, and bad input exits 2.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
ROUTE="$SRC/tests/data/drive_diag_route.toml"
"$CALBENCH" simulate drive --route "$ROUTE" --truth random --seed 41 --out "$T/rec" \
  --inject time_offset:value=0.002 --inject lever_arm:y=-0.04 >/dev/null
python3 -c "import json; t=json.load(open('$T/rec/truth.json')); assert t['time_offset']['s']==0.002 and t['lever_arm']['m'][1]==-0.04, t"
"$CALBENCH" diagnose "$T/rec" --json --out "$T/improved.json" --report "$T/report.html" >"$T/d.json"
python3 - "$T" <<'PY'
import json, sys
t = sys.argv[1]
d = json.load(open(t + "/d.json"))
assert d["kind"] == "drive", d.keys()
by = {f["effect"]: f for f in d["findings"]}
assert set(by) == {"time_offset", "lever_arm"}, d["findings"]
to, la = by["time_offset"], by["lever_arm"]
assert abs(to["value"] - 0.002) < 0.0004, to
assert la["sensor"] == "accel" and la["axis"] == "y", la
assert abs(la["value"][1] + 0.04) < 0.008, la
for f in (to, la):
    assert f["rms_after"] <= max(0.2 * f["rms_before"], f["evidence"]["rms_noise_floor"]), f
    assert f["sentence"], f
assert d["unexplained"] == [], d["unexplained"]
imp = json.load(open(t + "/improved.json"))
assert abs(imp["time_offset"]["s"] - 0.002) < 0.0004 and abs(imp["lever_arm"]["m"][1] + 0.04) < 0.008, imp
assert sorted(imp["diagnosis"]["effects_added"]) == ["lever_arm accel", "time_offset reference"], imp["diagnosis"]
PY
grep -q "data:image/png" "$T/report.html" || grep -q "plot unavailable" "$T/report.html" || { echo "report has no plot section"; exit 1; }
# Issue 17 item 6: long text lines wrap (they were cut at the page edge), images scale.
grep -q "pre{white-space:pre-wrap" "$T/report.html" && grep -q "img{max-width:100%" "$T/report.html" \
  || { echo "report text or plots cut at the page edge"; exit 1; }
# With IMPROVED.json (M fixed, its terms applied) nothing new is found.
"$CALBENCH" diagnose "$T/rec" --coeffs "$T/improved.json" --json >"$T/d2.json"
python3 -c "import json; d=json.load(open('$T/d2.json')); assert d['findings'] == [], d['findings']"
# The real drive runs and reports in the same schema.
"$CALBENCH" diagnose "$SHARED/data/psins-vehicle-100s" --device-class ADIS16488A --json >"$T/psins.json"
python3 -c "import json; d=json.load(open('$T/psins.json')); assert 'findings' in d and 'unexplained' in d and d['data']['blocks'] >= 90, d['data']"
# Bad input: a temperature term on a drive without temperature, an unknown effect → exit 2.
for opt in "temperature_bias:sensor=gyro,axis=x,value=1e-5" "wobble:x=1"; do
  set +e
  "$CALBENCH" simulate drive --route "$ROUTE" --truth random --out "$T/bad" --inject "$opt" 2>"$T/err"
  rc=$?
  set -e
  [ "$rc" -eq 2 ] || { echo "expected exit 2 for --inject $opt, got $rc"; cat "$T/err"; exit 1; }
  grep -q -- "--inject" "$T/err" || { echo "message does not name the option"; cat "$T/err"; exit 1; }
done
# A broken reference row → exit 2 naming file and line.
cp -r "$T/rec" "$T/broken"
sed -i '40s/^\([^,]*\),[^,]*,/\1,abc,/' "$T/broken/reference.csv"
set +e
"$CALBENCH" diagnose "$T/broken" 2>"$T/err2"
rc=$?
set -e
[ "$rc" -eq 2 ] || { echo "expected exit 2 on a broken reference.csv, got $rc"; cat "$T/err2"; exit 1; }
grep -q "reference.csv" "$T/err2" || { cat "$T/err2"; exit 1; }
echo "ok"
