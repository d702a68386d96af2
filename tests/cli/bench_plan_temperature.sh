#!/usr/bin/env bash
# Plan [temperature] and [plan] repeat (docs/bench-calibration.md): a tiny plan whose chamber ramps
# 10 → 30 °C over 10 s (no lag, no self-heating) is simulated; imu.csv's temperature column starts at
# 10 °C and ends at 30 °C (TEMP_OUT quantisation), the steps run twice; bad keys → exit 2 naming
# file, line and key.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
cat >"$T/p.toml" <<'TOML'
[plan]
name = "tiny_thermal"
repeat = 2
[site]
lat_deg = 52.0
lon_deg = 13.0
[table]
settle_s = 0.5
[temperature]
start_c = 10.0
chamber = [[0.0, 10.0], [10.0, 30.0]]
[[step]]
kind = "static"
mount = "z"
dwell_s = 2.0
[[step]]
kind = "static"
outer_deg = 180.0
dwell_s = 2.0
TOML
"$CALBENCH" simulate bench --plan "$T/p.toml" --truth random --out "$T/rec" >/dev/null
python3 - "$T/rec" <<'PY'
import csv, sys
d = sys.argv[1]
rows = [r for r in csv.reader(l for l in open(d + "/imu.csv") if not l.startswith("#"))]
hdr, rows = rows[0], rows[1:]
k = hdr.index("temp_c")
t0, t1 = float(rows[0][k]), float(rows[-1][k])
assert abs(t0 - 10.0) < 0.01 and abs(t1 - 30.0) < 0.01, (t0, t1)
mid = [float(r[k]) for r in rows if abs(float(r[0]) - 5.0) < 0.001]
assert mid and abs(mid[0] - 20.0) < 0.05, mid
steps = set()
for l in open(d + "/reference.csv"):
    if l[0].isdigit():
        steps.add(int(l.split(",")[7]))
assert steps >= {0, 1, 2, 3}, sorted(steps)
PY
bad() {  # $1: sed expression making the plan invalid
  sed "$1" "$T/p.toml" >"$T/bad.toml"
  set +e
  "$CALBENCH" simulate bench --plan "$T/bad.toml" --truth random --out "$T/bad" 2>"$T/err"
  local rc=$?
  set -e
  [ "$rc" -eq 2 ] || { echo "expected exit 2 for '$1', got $rc"; exit 1; }
  grep -q "bad.toml:[0-9][0-9]*: '\(temperature\|plan\)\." "$T/err" || { echo "no file:line:key for '$1'"; cat "$T/err"; exit 1; }
}
bad 's/^start_c = 10.0$/lagg_s = 3.0/'              # unknown key
bad 's/\[10.0, 30.0\]/[-5.0, 30.0]/'               # setpoint times decrease
bad 's/^repeat = 2$/repeat = 2.5/'                  # not an integer
echo ok
