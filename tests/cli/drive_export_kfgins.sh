#!/usr/bin/env bash
# export kf-gins: a simulated drive into KF-GINS's text files; `import kf-gins` reads them back to the
# values written (17 significant digits), and a second export of the imported recording (whose IMU
# axes are then KF-GINS's) writes the same files byte for byte. Bad input names file and line, exit 2.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$CALBENCH" simulate drive --route "$SRC/bench/routes/rtk_town.toml" --truth random --seed 3 --until 45 --out "$T/d" > /dev/null
"$CALBENCH" export kf-gins "$T/d" --out "$T/e1" --start 5 > "$T/out.txt"
grep -q "exported 9001 IMU rows, 226 GNSS fixes, 2251 reference rows into $T/e1; KF-GINS starts at 5 s from the reference" "$T/out.txt" || { cat "$T/out.txt"; exit 1; }
for f in imu.txt gnss.pos truth.nav kf-gins.yaml; do test -s "$T/e1/$f"; done
grep -q '^starttime: 5$' "$T/e1/kf-gins.yaml"
grep -q '^antlever: \[-0.59999999999999998,0.40000000000000002,0.90000000000000002\]$' "$T/e1/kf-gins.yaml"
grep -q "^imupath: \"$T/e1/imu.txt\"$" "$T/e1/kf-gins.yaml"
# KF-GINS starts at its IMU: the reference body origin at 5 s moved by C_nb * lever arm (the unit
# stands level there, so 0.72 m horizontally and 0.9 m up).
python3 - "$T/d/reference.csv" "$T/e1/kf-gins.yaml" <<'PY'
import csv, math, re, sys
ref = [r for r in csv.DictReader(l for l in open(sys.argv[1]) if not l.startswith("#")) if float(r["t_s"]) == 5.0][0]
pos = [float(x) for x in re.search(r"^initpos: \[(.*)\]$", open(sys.argv[2]).read(), re.M).group(1).split(",")]
lat = math.radians(float(ref["lat_deg"]))
dn = math.radians(pos[0] - float(ref["lat_deg"])) * 6.3553e6  # meridian radius near 34 deg S (WGS-84)
de = math.radians(pos[1] - float(ref["lon_deg"])) * 6.3848e6 * math.cos(lat)  # prime vertical radius
d = math.hypot(dn, de)
assert abs(d - math.hypot(0.6, 0.4)) < 0.01, (d, dn, de)
assert abs(pos[2] - float(ref["h_m"]) - 0.9) < 0.01, pos[2] - float(ref["h_m"])
PY
"$CALBENCH" import kf-gins --imu "$T/e1/imu.txt" --truth "$T/e1/truth.nav" --gnss "$T/e1/gnss.pos" --out "$T/r" \
  --lever-arm 0.6,-0.4,-0.9 --ref-sigma-pos 0.02 --ref-sigma-vel 0.005 --ref-sigma-att 0.005 > /dev/null
python3 - "$T/d" "$T/r" "$T/e1" <<'PY'
import csv, math, sys
d, r, e = sys.argv[1:]
def rows(p):
    return list(csv.DictReader(l for l in open(p) if not l.startswith("#")))
# GNSS fixes and reference rows: the values written, exactly.
for name, cols in (("gnss.csv", ("t_s", "lat_deg", "lon_deg", "h_m", "sigma_h_m", "sigma_v_m")),
                   ("reference.csv", ("t_s", "lat_deg", "lon_deg", "h_m", "vn_m_s", "ve_m_s", "vd_m_s", "roll_deg", "pitch_deg", "yaw_deg"))):
    a, b = rows(d + "/" + name), rows(r + "/" + name)
    assert len(a) == len(b), (name, len(a), len(b))
    for x, y in zip(a, b):
        for c in cols:
            assert float(x[c]) == float(y[c]), (name, c, x[c], y[c])
# IMU: rates x interval, turned by the nominal mounting (yaw -90 deg): the norm of each increment
# is kept, and the body x axis (forward) is the MEMS y axis, body y the MEMS -x.
a, b = rows(d + "/imu.csv"), rows(r + "/imu.csv")
assert len(a) == len(b) == 9001, (len(a), len(b))
dt0 = 1 / 200.0
for k, (x, y) in enumerate(zip(a, b)):
    dt = float(x["t_s"]) - float(a[k - 1]["t_s"]) if k else dt0
    assert float(x["t_s"]) == float(y["t_s"])
    for s, i in (("g", "da"), ("a", "dv")):
        m = [float(x[s + c + ("_rad_s" if s == "g" else "_m_s2")]) * dt for c in "xyz"]
        n = [float(y[i + c + ("_rad" if s == "g" else "_m_s")]) for c in "xyz"]
        assert abs(n[0] - m[1]) <= 1e-12 * (1 + abs(m[1])) and abs(n[1] + m[0]) <= 1e-12 * (1 + abs(m[0])) and abs(n[2] - m[2]) <= 1e-15 + 1e-12 * abs(m[2]), (k, s, m, n)
PY
"$CALBENCH" export kf-gins "$T/r" --out "$T/e2" --start 5 > /dev/null
for f in imu.txt gnss.pos truth.nav; do cmp "$T/e1/$f" "$T/e2/$f"; done
# --standstill: the initial gyro bias from the opening standstill (rtk_town stands 30 s) is the
# simulated unit's (truth.json, MEMS axes; the IMU frame is turned by the mounting's -90 deg yaw)
# to within a few deg/h (the white noise over 25 s and the in-run drift); a window into the motion
# is refused.
"$CALBENCH" export kf-gins "$T/d" --out "$T/e5" --standstill 25 > /dev/null
python3 - "$T/d/truth.json" "$T/e5/kf-gins.yaml" <<'PY'
import json, math, re, sys
b = json.load(open(sys.argv[1]))["gyro"]["bias"]
want = [b[1], -b[0], b[2]]
got = [float(x) for x in re.search(r"^initgyrbias: \[(.*?)\]", open(sys.argv[2]).read(), re.M).group(1).split(",")]
for w, g in zip(want, got):
    assert abs(math.degrees(w) * 3600 - g) < 20, (want, got)
assert re.search(r"^initbgstd: \[([\d.]+),", open(sys.argv[2]).read(), re.M)
PY
set +e
"$CALBENCH" export kf-gins "$T/d" --out "$T/e6" --standstill 40 2> "$T/err.txt"; rc=$?
set -e
test $rc -eq 2 || { echo "expected 2 for a window into the motion, got $rc"; exit 1; }
grep -q "not a standstill" "$T/err.txt" || { cat "$T/err.txt"; exit 1; }
# An existing export is kept without --force.
set +e
"$CALBENCH" export kf-gins "$T/d" --out "$T/e1" 2> "$T/err.txt"; rc=$?
set -e
test $rc -eq 2 || { echo "expected 2 over an existing export, got $rc"; exit 1; }
grep -q "already holds a KF-GINS export" "$T/err.txt" || { cat "$T/err.txt"; exit 1; }
# A bad number in gnss.csv: file, line and field; nothing left under --out.
sed -i '5s/^\([^,]*\),[^,]*,/\1,north,/' "$T/d/gnss.csv"
set +e
"$CALBENCH" export kf-gins "$T/d" --out "$T/e3" 2> "$T/err.txt"; rc=$?
set -e
test $rc -eq 2 || { echo "expected 2 on a bad fix, got $rc"; cat "$T/err.txt"; exit 1; }
grep -q "gnss.csv:5" "$T/err.txt" || { cat "$T/err.txt"; exit 1; }
test ! -e "$T/e3" || { echo "a refused export left $T/e3"; exit 1; }
# No fixes at all: KF-GINS cannot run; said so.
rm "$T/d/gnss.csv"
set +e
"$CALBENCH" export kf-gins "$T/d" --out "$T/e4" 2> "$T/err.txt"; rc=$?
set -e
test $rc -eq 2 || { echo "expected 2 without gnss.csv, got $rc"; exit 1; }
grep -q "gnss.csv.*KF-GINS is aided by GNSS fixes" "$T/err.txt" || { cat "$T/err.txt"; exit 1; }
echo OK
