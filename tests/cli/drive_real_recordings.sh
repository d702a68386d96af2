#!/usr/bin/env bash
# The in-motion fit on the real recordings of ../shared/data (issue 34, item 7): no lock-out and
# honest output. The handheld RTK walk (consumer IMU, 4 Hz fixes of 1-2 cm, GNSS-only, winding at
# walking pace): the heading is found (among the hypotheses: no course over ground at 1.3 m/s), no
# forced widening, no re-alignment after the first, at most 5 % of the fixes rejected, mean NIS
# within 0.5-2x of its expectation, the adaptive process noise reported. The PSINS car drive (FOG
# reference INS) with and without attitude observations: no forced widening, no re-alignment.
# A gross outlier during the heading search (the walk's fix at 20 s moved 111 m north) is rejected by
# every hypothesis and decides nothing: the heading is the clean walk's (it picked -179 deg before).
set -euo pipefail
W="$SHARED/data/rtk-walk-135s"
P="$SHARED/data/psins-vehicle-100s"
test -d "$W" -a -d "$P" || { echo "no $W or $P: skipped"; exit 77; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$CALBENCH" fit drive "$W" --out "$T/walk.json" > "$T/walk.txt"
grep -q "heading chosen among heading hypotheses at" "$T/walk.txt"
grep -q "adaptive noise   navigation noise variance scaled up" "$T/walk.txt"
"$CALBENCH" fit drive "$W" --adaptive off --out "$T/walk_off.json" > /dev/null
cp -r "$W" "$T/walk_outlier"
python3 - "$T/walk_outlier/gnss.csv" <<'PY'
import sys
p = sys.argv[1]
lines = open(p).read().split("\n")
head = [i for i, l in enumerate(lines) if l.startswith("t_s")][0]
cols = lines[head].split(",")
rows = [i for i in range(head + 1, len(lines)) if lines[i] and not lines[i].startswith("#")]
k = min(rows, key=lambda i: abs(float(lines[i].split(",")[0]) - 20.0))
v = lines[k].split(",")
v[cols.index("lat_deg")] = repr(float(v[cols.index("lat_deg")]) + 0.001)
lines[k] = ",".join(v)
open(p, "w").write("\n".join(lines))
PY
"$CALBENCH" fit drive "$T/walk_outlier" --out "$T/walk_outlier.json" > "$T/walk_outlier.txt"
heading() { sed -n 's/.*heading chosen among [0-9]* hypotheses.*): \(-\{0,1\}[0-9.]*\) deg, sigma.*/\1/p' "$1"; }
h0=$(heading "$T/walk.txt"); h1=$(heading "$T/walk_outlier.txt")
echo "walk heading $h0 deg; with a 111-m outlier at 20 s: $h1 deg"
python3 -c "import sys, math; d = math.remainder(float(sys.argv[1]) - float(sys.argv[2]), 360); assert abs(d) < 3, d" "$h0" "$h1"
python3 - "$T/walk_outlier.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
assert r["alignment"]["covariance_widenings"] == 0 and r["alignment"]["realignments"] == 1, r["alignment"]
assert r["consistency"]["position"]["rejected"] >= 1, r["consistency"]["position"]
PY
for obs in pos,vel,att pos; do
  # The PSINS unit is of no known class: the class its published figures assume is named.
  "$CALBENCH" fit drive "$P" --device-class ADIS16488A --obs "$obs" --out "$T/psins_$obs.json" > /dev/null
done
python3 - "$T" <<'PY'
import json, sys, os
T = sys.argv[1]
def load(n): return json.load(open(os.path.join(T, n)))
def share_rejected(r):
    c = r["consistency"].values()
    used = sum(x["epochs"] for x in c); rej = sum(x["rejected"] for x in c); forced = sum(x["forced"] for x in c)
    return rej / max(1, used + rej + forced)
w = load("walk.json")
al = w["alignment"]
assert al["mode"] == "gnss" and al["heading"]["t_s"] is not None, al
assert al["heading"]["source"].startswith("hypotheses"), al["heading"]
assert al["covariance_widenings"] == 0 and al["realignments"] == 1, al
assert share_rejected(w) <= 0.05, w["consistency"]
for k in ("position", "velocity"):
    c = w["consistency"][k]
    assert c["forced"] == 0 and 0.5 <= c["mean_nis"] / c["expected_nis"] <= 2.0, (k, c)
an = w["adaptive_noise"]
assert an["enabled"] and an["option"] == "auto" and an["increases"] > 0 and an["scale_max"] > 1, an
# Without the adaptation the same walk is inconsistent: the adaptation is what holds it.
off = load("walk_off.json")
assert not off["adaptive_noise"]["enabled"]
assert off["consistency"]["position"]["mean_nis"] > 2 * 3 or off["alignment"]["covariance_widenings"] > 0, off["consistency"]
for obs in ("pos,vel,att", "pos"):
    r = load("psins_%s.json" % obs)
    assert not r["adaptive_noise"]["enabled"], "auto is off against a reference INS"
    for k, c in r["consistency"].items():
        assert c["forced"] == 0, (obs, k, c)
    assert r.get("alignment", {}).get("realignments", 0) == 0, (obs, r.get("alignment"))
    assert share_rejected(r) <= 0.05, (obs, r["consistency"])
print("walk: heading at %.2f s, %.1f %% rejected, NIS/expected %.2f, %.2f; adaptive scale max %.3g"
      % (al["heading"]["t_s"], 100 * share_rejected(w), w["consistency"]["position"]["mean_nis"] / 3,
         w["consistency"]["velocity"]["mean_nis"] / 3, an["scale_max"]))
PY
