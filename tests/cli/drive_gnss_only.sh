#!/usr/bin/env bash
# GNSS-only drive (issue 16, item 6): a recording with gnss.csv and no reference.csv, a 60 s opening
# standstill, raw data (data-sheet priors). fit drive aids with the fixes by itself, levels at the
# standstill, takes the heading from the course over ground once moving and never locks out;
# RESULT.json and the summary say so. Bad input exits 2 naming file/option and field.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
# The short test route at 100 Hz with a 60 s opening standstill.
sed -e 's/^rate_hz = 400.0/rate_hz = 100.0/' "$SRC/bench/routes/short.toml" |
  awk 'BEGIN{n=0} /^duration_s = 20.0/ && n==0 {print "duration_s = 60.0"; n=1; next} {print}' > "$T/route.toml"
grep -q '^duration_s = 60.0' "$T/route.toml"
"$CALBENCH" simulate drive --route "$T/route.toml" --truth random --seed 5 --out "$T/rec" >/dev/null
rm "$T/rec/reference.csv"   # no reference INS: GNSS fixes only

"$CALBENCH" fit drive "$T/rec" --out "$T/r_posvel.json" > "$T/summary.txt"
grep -q "alignment        GNSS fixes, levelled" "$T/summary.txt"
grep -q "heading from the course over ground at" "$T/summary.txt"
"$CALBENCH" fit drive "$T/rec" --obs pos --out "$T/r_pos.json" >/dev/null
python3 - "$T" <<'PY'
import json, sys, math
d = sys.argv[1]
t = json.load(open(d + "/rec/truth.json"))
for name, obs in (("r_posvel", "pos,vel"), ("r_pos", "pos")):
    r = json.load(open(f"{d}/{name}.json"))
    assert r["aiding"] == "gnss" and r["observations"] == obs, (r.get("aiding"), r["observations"])
    assert r["recording"]["sha256_reference"] is None and len(r["recording"]["sha256_gnss"]) == 64
    a = r["alignment"]
    assert a["mode"] == "gnss", a
    assert a["level"]["t_s"][0] == 0 and 5 <= a["level"]["t_s"][1] <= 15, a["level"]
    # Heading from the course soon after the vehicle starts at 60 s, never before.
    assert 60 < a["heading"]["t_s"] < 80, a["heading"]
    assert a["heading_known_at_end"] is True
    assert a["covariance_widenings"] == 0, r["recoveries"]          # no lock-out
    assert r["recoveries"][0]["reason"].startswith("start of motion without a heading"), r["recoveries"]
    assert r["recoveries"][0]["action"].startswith("heading re-aligned from the course over ground"), r["recoveries"]
    for k, c in r["consistency"].items():
        assert c["forced"] == 0 and c["rejected"] <= 0.02 * c["epochs"] + 1, (name, k, c)
        assert 0.5 < c["mean_nis"] < 6, (name, k, c)
    # No reference INS: the QC is the outage QC against the fixes (drive_outage_qc.sh tests it).
    assert r["qc"]["sample"].startswith("in-sample") and "outages" in r["qc"], r["qc"]
    # The yaw gyro drift (unobservable while standing without a heading) is found once moving.
    c = r["coefficients"]["gyro"]
    err = abs(c["bias"][2] - t["gyro"]["bias"][2])
    assert err <= 3 * c["sigma_bias"][2] and c["sigma_bias"][2] < 60 * math.pi / 180 / 3600, (name, err, c["sigma_bias"][2])
    print(name, "heading at", a["heading"]["t_s"], "s; gyro z error %.1f deg/h (sigma %.1f)" % (err / (math.pi / 180 / 3600), c["sigma_bias"][2] / (math.pi / 180 / 3600)))
PY

# With a reference INS and --obs pos at 1 Hz (the first 300 s of the 1 h route, seed 5): the heading
# drifts during the 60 s standstill with the raw 0.5 deg/s gyro prior; the filter used to lose track
# once moving (98 epochs rejected, yaw gyro drift 912 deg/h off). Now it re-aligns at the start of
# motion and says so.
"$CALBENCH" simulate drive --route "$SRC/bench/routes/gnss_1h.toml" --truth random --seed 5 --until 300 --out "$T/ref" >/dev/null
"$CALBENCH" fit drive "$T/ref" --obs pos --obs-rate 1 --out "$T/r_ref.json" > "$T/summary_ref.txt"
grep -q "heading re-alignment" "$T/summary_ref.txt"
python3 - "$T/r_ref.json" "$T/ref/truth.json" <<'PY'
import json, sys, math
r = json.load(open(sys.argv[1])); t = json.load(open(sys.argv[2]))
assert "aiding" not in r and r["alignment"]["mode"] == "reference", r["alignment"]
assert r["alignment"]["realignments"] >= 1 and r["alignment"]["covariance_widenings"] == 0, r["recoveries"]
assert r["recoveries"][0]["reason"].startswith("start of motion"), r["recoveries"]
c = r["consistency"]["position"]
assert c["forced"] == 0 and c["rejected"] <= 15, c
g = r["coefficients"]["gyro"]
for i in range(3):
    assert abs(g["bias"][i] - t["gyro"]["bias"][i]) <= 3 * g["sigma_bias"][i], (i, g["bias"][i], t["gyro"]["bias"][i], g["sigma_bias"][i])
PY

# Bad input: exit 2 naming what is wrong.
source "$SRC/tests/support/cli_expect.sh"
expect2 "att" "$CALBENCH" fit drive "$T/rec" --obs pos,att --out "$T/x.json"
mkdir "$T/nognss" && cp "$T/rec/meta.json" "$T/rec/imu.csv" "$T/nognss/"
expect2 "gnss.csv" "$CALBENCH" fit drive "$T/nognss" --aiding gnss --out "$T/x.json"
cp -r "$T/rec" "$T/broken"
python3 - "$T/broken/gnss.csv" <<'PY'
import sys
p = sys.argv[1]
lines = open(p).read().splitlines()
out = []
for l in lines:
    if l.startswith('#'): out.append(l); continue
    f = l.split(','); del f[5]; out.append(','.join(f))   # drop ve_m_s
open(p, 'w').write('\n'.join(out) + '\n')
PY
expect2 "ve_m_s" "$CALBENCH" fit drive "$T/broken" --out "$T/x.json"
grep -q "gnss.csv" "$T/out.txt"
echo "drive_gnss_only: ok"
