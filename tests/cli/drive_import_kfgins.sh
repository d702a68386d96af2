#!/usr/bin/env bash
# import kf-gins: KF-GINS text files (IMU increments, truth.nav, GNSS .pos) become a drive
# recording that fit drive reads; a bad number names file, line and column and exits 2.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
python3 - "$T" <<'PY'
import math, sys
d = sys.argv[1]
lat = math.radians(30.5); W = 7.292115e-5; g = 9.7936; dt = 0.005
with open(d + "/imu.txt", "w") as f:
    for k in range(1, 60 * 200 + 1):   # 60 s at 200 Hz, level, heading north, at rest
        t = 100000 + k * dt
        f.write("%.3f %.12e %.12e %.12e %.12e %.12e %.12e\n" % (t, W * math.cos(lat) * dt, 0.0, -W * math.sin(lat) * dt, 0.0, 0.0, -g * dt))
with open(d + "/truth.nav", "w") as f:
    for k in range(0, 60 * 10 + 1):
        t = 100000 + k * 0.1
        f.write("2100 %.3f 30.5 114.0 20.0 0 0 0 0 0 0\n" % t)
with open(d + "/gnss.pos", "w") as f:
    for k in range(0, 61):
        f.write("%.3f 30.5 114.0 20.0 0.02 0.02 0.05\n" % (100000 + k))
PY
"$CALBENCH" import kf-gins --imu "$T/imu.txt" --truth "$T/truth.nav" --gnss "$T/gnss.pos" --out "$T/rec" > "$T/out.txt"
grep -q "imported 12000 IMU rows (200 Hz), 601 reference rows, 61 GNSS fixes" "$T/out.txt" || { cat "$T/out.txt"; exit 1; }
grep -q '"kind": "drive"' "$T/rec/meta.json"
head -3 "$T/rec/imu.csv" | grep -q "dax_rad"
# The import writes model "unknown" (KF-GINS files name no IMU): the class is named.
"$CALBENCH" fit drive "$T/rec" --device-class ADIS16488A --out "$T/r.json" --json > "$T/fit.json"
python3 - "$T/r.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
assert r["consistency"]["position"]["epochs"] > 500, r["consistency"]
PY
sed -i '5s/.*/100000.025 0.1 x 0 0 0 0/' "$T/imu.txt"
set +e
"$CALBENCH" import kf-gins --imu "$T/imu.txt" --truth "$T/truth.nav" --out "$T/rec2" 2> "$T/err.txt"
rc=$?
set -e
test $rc -eq 2 || { echo "expected 2, got $rc"; exit 1; }
grep -q "imu.txt:5: 'column 3'" "$T/err.txt" || { cat "$T/err.txt"; exit 1; }
echo OK
