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
