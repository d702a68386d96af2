#!/usr/bin/env bash
# bench/diagnose/inject_effects.py (issue 36), the independent effect generator: each effect changes
# the IMU output by what it claims and nothing else; increments stay increments; bad input exits 2
# naming file, line and field; the output folder is not written on a refusal.
set -euo pipefail
CALBENCH=${CALBENCH:-build/calbench}
SRC=${SRC:-.}
SHARED=${SHARED:-$SRC/../shared}
INJ="$SRC/bench/diagnose/inject_effects.py"
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$CALBENCH" simulate drive --route "$SRC/tests/data/drive_diag_level.toml" --truth random --seed 7 --out "$T/d" >/dev/null
"$CALBENCH" simulate bench --plan "$SRC/tests/data/short_plan.toml" --truth random --seed 7 --out "$T/b" >/dev/null
python3 "$INJ" "$T/d" "$T/d-shift" shift --sensor gyro --axis x --bias 30
python3 "$INJ" "$T/d" "$T/d-speed" speed --sensor gyro --axis z --k 2
python3 "$INJ" "$T/b" "$T/b-db" deadband --axis z --width 0.01
python3 "$INJ" "$T/b" "$T/b-sat" saturation --axis z
python3 "$INJ" "$T/b" "$T/b-warm" warmup --sensor accel --axis y --change 1 --dT 10
python3 "$INJ" "$T/b" "$T/b-mem" memory --axis z --memory 30
python3 - "$T" <<'PY'
import csv, json, math, sys
T = sys.argv[1]
DPH, MG, DEG = math.pi / 180 / 3600, 9.80665e-3, math.pi / 180
def cols(path):
    rows = [r for r in csv.reader(l for l in open(path) if not l.startswith("#"))]
    return {h: [float(r[i]) for r in rows[1:]] for i, h in enumerate(rows[0])}
def diff(a, b, c):
    return [y - x for x, y in zip(a[c], b[c])]
def check(cond, msg):
    if not cond:
        sys.exit("FAIL: " + msg)
d = cols(f"{T}/d/imu.csv")
s = cols(f"{T}/d-shift/imu.csv")
dx = diff(d, s, "gx_rad_s")
check(all(abs(v - 30 * DPH) < 1e-12 for v in dx), "shift: gyro x moves by 30 deg/h on every row")
for c in ("gy_rad_s", "gz_rad_s", "ax_m_s2", "ay_m_s2", "az_m_s2", "t_s"):
    check(d[c] == s[c], f"shift: {c} unchanged")
check(json.load(open(f"{T}/d-shift/injected.json"))["effect"] == "shift", "injected.json names the effect")
sp = cols(f"{T}/d-speed/imu.csv")
dz = diff(d, sp, "gz_rad_s")
ref = cols(f"{T}/d/reference.csv")
vmax = max(math.sqrt(a * a + b * b + c * c) for a, b, c in zip(ref["vn_m_s"], ref["ve_m_s"], ref["vd_m_s"]))
check(min(dz) >= -1e-15 and min(dz) < 2 * DPH * 0.05, "speed: (almost) no bias at standstill (the reference speed is noisy by mm/s)")
check(abs(max(dz) - 2 * DPH * vmax) < 0.02 * 2 * DPH * vmax, f"speed: top bias 2 deg/h per m/s x {vmax:.1f} m/s")
b = cols(f"{T}/b/imu.csv")
br = cols(f"{T}/b/reference.csv")
db = diff(b, cols(f"{T}/b-db/imu.csv"), "gz_rad_s")
check(all(abs(v) < 0.01 * DEG + 1e-15 for v in db), "deadband: the change never exceeds the width")
check(sum(1 for v in db if v != 0) > len(db) // 10, "deadband: static samples lose their small true rate")
check(sum(1 for v in db if v == 0) > len(db) // 10, "deadband: samples at a table rate are untouched")
sat = cols(f"{T}/b-sat/imu.csv")["gz_rad_s"]
lim = 0.97 * max(abs(w) for w in br["wz_rad_s"])
check(max(abs(v) for v in sat) <= lim + 1e-15, "saturation: output within the limit")
check(sum(1 for v in sat if abs(v) == lim) > 100, "saturation: the top rate clips")
w = cols(f"{T}/b-warm/imu.csv")
check(all(x <= y for x, y in zip(w["temp_c"], w["temp_c"][1:])), "warmup: temperature rises monotonically")
rise = w["temp_c"][-1] - w["temp_c"][0]
check(abs(rise - 10 * (1 - math.exp(-3))) < 0.05, f"warmup: rise {rise:.2f} C over three time constants")
dy = diff(b, w, "ay_m_s2")
check(abs(dy[-1] - 0.1 * MG * rise) < 1e-9, "warmup: accel y bias follows 0.1 mg/C")
check(b["gz_rad_s"] == w["gz_rad_s"], "warmup on accel y leaves gyro z alone")
m = diff(b, cols(f"{T}/b-mem/imu.csv"), "gz_rad_s")
check({round(v / DPH, 6) for v in m} <= {0.0, 30.0, -30.0} and {30.0, -30.0} <= {round(v / DPH, 6) for v in m},
      "memory: the bias is 0 before the first rotation, then +-30 deg/h")
print("OK: effects as claimed")
PY
# Increments (the PSINS drive): a shift of 36 deg/h adds 36 deg/h x dt to every angle increment.
if [ -d "$SHARED/data/psins-vehicle-100s" ]; then
  python3 "$INJ" "$SHARED/data/psins-vehicle-100s" "$T/p" shift --axis y --bias 36
  python3 - "$SHARED/data/psins-vehicle-100s/imu.csv" "$T/p/imu.csv" <<'PY'
import csv, math, sys
def cols(path):
    rows = [r for r in csv.reader(l for l in open(path) if not l.startswith("#"))]
    return {h: [float(r[i]) for r in rows[1:]] for i, h in enumerate(rows[0])}
a, b = cols(sys.argv[1]), cols(sys.argv[2])
t = a["t_s"]
for i in range(1, len(t)):
    want = 36 * math.pi / 180 / 3600 * (t[i] - t[i - 1])
    if abs(b["day_rad"][i] - a["day_rad"][i] - want) > 1e-15 + 1e-9 * want:
        sys.exit(f"FAIL: increment row {i}: {b['day_rad'][i] - a['day_rad'][i]} != {want}")
print("OK: increments")
PY
fi
# Bad input: exit 2, file, line and field named, nothing written.
bad() {  # bad EXPECTED-TEXT ARGS...
  local want=$1 rc=0
  shift
  python3 "$INJ" "$@" 2> "$T/err" || rc=$?
  [ "$rc" -eq 2 ] || { echo "FAIL: exit $rc, not 2, for $*"; cat "$T/err"; exit 1; }
  grep -qF -- "$want" "$T/err" || { echo "FAIL: '$want' not in: $(cat "$T/err")"; exit 1; }
  [ ! -e "$T/out" ] || { echo "FAIL: output written on a refusal"; exit 1; }
}
mkdir "$T/nan" "$T/back" "$T/nocol"
for x in nan back nocol; do cp "$T/d/meta.json" "$T/d/reference.csv" "$T/$x/"; done
head -4 "$T/d/imu.csv" > "$T/nan/imu.csv"; echo "9,0,0,nan,0,0,-9.8" >> "$T/nan/imu.csv"
head -5 "$T/d/imu.csv" > "$T/back/imu.csv"; sed -n 3p "$T/d/imu.csv" >> "$T/back/imu.csv"
cut -d, -f1-3,5- "$T/d/imu.csv" > "$T/nocol/imu.csv"
bad "nan/imu.csv:5: column 'gz_rad_s': not finite" "$T/nan" "$T/out" shift
bad "back/imu.csv:6: column 't_s': time goes backwards" "$T/back" "$T/out" shift
bad "missing column 'gz_rad_s'" "$T/nocol" "$T/out" shift
bad "memory needs the true rates of a bench reference.csv" "$T/d" "$T/out" memory
bad "speed needs a drive reference" "$T/b" "$T/out" speed
bad "meta.json: missing file" "$T/none" "$T/out" shift
bad "exists (use --force" "$T/d" "$T/d-shift" shift
echo "OK: bad input refused"
