#!/usr/bin/env bash
# Real drive (PSINS, 100 Hz MEMS increments, 10 Hz FOG INS reference, no GNSS): fit drive on the
# first half and qc on the second half run end to end; the in-motion set navigates better than
# no calibration out of sample.
set -euo pipefail
D="$SHARED/data/psins-vehicle-100s"
test -d "$D" || { echo "no $D: skipped"; exit 0; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
# The unit's model is unknown ("unknown low-cost MEMS IMU"): the class is named (docs/in-motion.md,
# "Device classes"); without it the fit refuses (tests/cli/drive_device_class.sh).
"$CALBENCH" fit drive "$D" --device-class ADIS16488A --window 0:50 --out "$T/r.json" >/dev/null
"$CALBENCH" qc "$D" --coeffs none --coeffs "$T/r.json" --json > "$T/q.json"
python3 - "$T/r.json" "$T/q.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1])); q = json.load(open(sys.argv[2]))
assert r["device"]["serial"] == "psins-vehicle"
assert all(s is not None and s > 0 for s in r["coefficients"]["gyro"]["sigma_bias"])
assert q["sample"].startswith("out-of-sample") and abs(q["from_s"] - 50) < 0.2
s = {x["name"]: x for x in q["sets"]}
assert s["r"]["final_cpe_m"] < s["none"]["final_cpe_m"], s
PY
echo OK
