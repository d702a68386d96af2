#!/usr/bin/env bash
# A unit's scale changed since its factory calibration, found on a drive through files: the unit is
# simulated on the factory plan and fitted (fit bench), the same unit then driven with a gyro z
# scale shift injected (simulate drive --truth <its truth.json> --inject scale_factor:...), and the
# drive diagnosed with the factory coefficients (--coeffs: M fixed). The JSON names scale_factor on
# gyro z with the right value; IMPROVED.json carries it in M (not as an extra key); diagnosing again
# with IMPROVED.json finds nothing; without --coeffs scale_factor is no candidate (M is fitted).
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$CALBENCH" simulate bench --plan "$SRC/bench/plans/factory.toml" --truth random --seed 81 --out "$T/bench" >/dev/null
"$CALBENCH" fit bench "$T/bench" --out "$T/coeffs.json" >/dev/null
"$CALBENCH" simulate drive --route "$SRC/tests/data/drive_diag_route.toml" --truth "$T/bench/truth.json" --seed 81 \
  --out "$T/drive" --inject scale_factor:sensor=gyro,axis=z,value=-8e-4 >/dev/null
python3 -c "import json; t=json.load(open('$T/drive/truth.json')); assert t['scale_factor']['gyro'][2] == -8e-4, t.get('scale_factor')"
"$CALBENCH" diagnose "$T/drive" --coeffs "$T/coeffs.json" --json --no-innovations --out "$T/improved.json" >"$T/d.json"
python3 - "$T" <<'PY'
import json, sys
t = sys.argv[1]
d = json.load(open(t + "/d.json"))
fs = d["findings"]
assert [(f["effect"], f["sensor"], f["axis"]) for f in fs] == [("scale_factor", "gyro", "z")], fs
f = fs[0]
assert abs(f["value"] + 8e-4) <= 0.2 * 8e-4, f
assert f["unit"] == "1", f
assert f["rms_after"] <= max(0.2 * f["rms_before"], f["evidence"]["rms_noise_floor"]), f
assert "scale factor differs from the given coefficients" in f["sentence"] and "ppm" in f["sentence"], f["sentence"]
assert d["unexplained"] == [], d["unexplained"]
given = json.load(open(t + "/coeffs.json"))
imp = json.load(open(t + "/improved.json"))
assert "scale_factor" not in imp, "the scale change belongs in M"
mz, mz0 = imp["gyro"]["M"][2][2], given["gyro"]["M"][2][2]
assert abs((mz - mz0) - f["value"]) < 1e-12, (mz, mz0, f["value"])
assert imp["diagnosis"]["effects_added"] == ["scale_factor gyro z"], imp["diagnosis"]
PY
# IMPROVED.json explains the drive: nothing new.
"$CALBENCH" diagnose "$T/drive" --coeffs "$T/improved.json" --json --no-innovations >"$T/d2.json"
python3 -c "import json; d=json.load(open('$T/d2.json')); assert d['findings'] == [], d['findings']"
# Without --coeffs the drive fits M itself: the shift is part of M, no finding.
"$CALBENCH" diagnose "$T/drive" --json --no-innovations >"$T/d3.json"
python3 -c "import json; d=json.load(open('$T/d3.json')); assert all(f['effect'] != 'scale_factor' for f in d['findings']), d['findings']"
echo "ok"
