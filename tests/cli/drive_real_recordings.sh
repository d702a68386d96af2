#!/usr/bin/env bash
# The in-motion fit on the real recordings of ../shared/data (issue 34, item 7): no lock-out and
# honest output. The handheld RTK walk (consumer IMU, 4 Hz fixes of 1-2 cm, GNSS-only, winding at
# walking pace): the heading is found (among the hypotheses: no course over ground at 1.3 m/s), no
# forced widening, no re-alignment after the first, at most 5 % of the fixes rejected, mean NIS
# within 0.5-2x of its expectation; issue 53: the IMU carries the navigation: the logger's sample
# timing and the fix velocity's latency measured from the recording, the adaptive noise scale at
# most 10 at the end (it heals), the outage QC placed and a 15-s outage within 15 m (the peer,
# rtklibexplorer's GNSS_IMU on the same raw walk without its velocity matching: 14.1 and 3.1 m);
# without the two measured properties and the adaptation the walk loses track. The PSINS car drive (FOG
# reference INS) with and without attitude observations: no forced widening, no re-alignment.
# A gross outlier during the heading search (the walk's fix at 20 s moved 111 m north) is rejected by
# every hypothesis and decides nothing: the heading is the clean walk's (it picked -179 deg before).
set -euo pipefail
W="$SHARED/data/rtk-walk-135s"
P="$SHARED/data/psins-vehicle-100s"
test -d "$W" -a -d "$P" || { echo "no $W or $P: skipped"; exit 77; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$CALBENCH" fit drive "$W" --out "$T/walk.json" --series "$T/walk_series.csv" > "$T/walk.txt"
grep -q "heading chosen among heading hypotheses at" "$T/walk.txt"
grep -q "sample timing    .* repeated reads); stamp scatter sigma" "$T/walk.txt"
grep -q "GNSS velocity    describes the motion" "$T/walk.txt"
! grep -q "FAILED" "$T/walk.txt"
"$CALBENCH" fit drive "$W" --adaptive off --sample-time off --gnss-vel-latency off --out "$T/walk_off.json" > /dev/null
"$CALBENCH" fit drive "$W" --adaptive off --out "$T/walk_physics.json" > /dev/null
# Without the two properties the adaptation still ends far above its limit on the walk's first minute:
# said in plain words, with when it began and the motion there, and refused by the approval preview.
"$CALBENCH" fit drive "$W" --sample-time off --gnss-vel-latency off --window 0:60 --out "$T/walk_fail.json" > "$T/walk_fail.txt"
grep -q "FAILED           the filter ended with the IMU's noise scaled x.* above the limit since t .* m/s turning" "$T/walk_fail.txt"
grep -q "in-motion filter: the navigation noise variance was scaled ×.* at the end of the fit (limit 10)" "$T/walk_fail.txt"
python3 -c 'import json,sys; a=json.load(open(sys.argv[1]))["adaptive_noise"]; assert a["failed"] and a["scale_end"] > 10 and a["above_fail_since"]["t_s"] > 0, a' "$T/walk_fail.json"
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
"$CALBENCH" fit drive "$T/walk_outlier" --out "$T/walk_outlier.json" --series "$T/walk_outlier_series.csv" > "$T/walk_outlier.txt"
# The headings are chosen at instants the likelihoods decide (the walker turns in between): compare
# the two filters' yaw at the fixes both used after both had chosen.
python3 - "$T/walk_series.csv" "$T/walk_outlier_series.csv" <<'PY'
import csv, math, sys
def yaw(p):
    rows = csv.DictReader(l for l in open(p) if not l.startswith("#"))
    return {round(float(r["t_s"]), 3): float(r["yaw_deg"]) for r in rows}
a, b = yaw(sys.argv[1]), yaw(sys.argv[2])
d = sorted(abs(math.remainder(a[t] - b[t], 360)) for t in a if t in b and t > 45)
assert len(d) > 100, len(d)
print("walk yaw with and without a 111-m outlier at 20 s: median difference %.2f deg over %d fixes" % (d[len(d) // 2], len(d)))
assert d[len(d) // 2] < 10, d[len(d) // 2]  # not decided by the outlier (it picked -179 deg before: 219 deg off)
PY
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
assert an["enabled"] and an["option"] == "auto" and an["scale_end"] <= 10 and not an["failed"], an
st, gl = w["sample_timing"], w["gnss_velocity_latency"]
assert st["repeated_rows"] > 0 and 1.0 <= st["sigma_ms"] <= 4.0 and st["used_ms"] == st["sigma_ms"], st
# Second reads show a logger that stamps at the read (polling): they are dropped, every one the scan
# counted. The stamps' mean lateness is reported (not applied): for a delay spread over a read
# interval about √3 σ (uniform).
ap = st["applied"]
assert ap["dropped_repeated_rows"] and st["polling"] and ap["rows_dropped"] == st["repeated_rows"], st
assert 0.8 * 3 ** 0.5 * st["sigma_ms"] <= st["lateness_ms"] <= 1.25 * 3 ** 0.5 * st["sigma_ms"], st
assert gl["established"] and 0.08 <= gl["used_s"] <= 0.2, gl
outs = w["qc"]["outages"]["outages"]
assert outs, w["qc"]["outages"].get("not_placed")
o15 = [o["max_m"]["in-motion"] for o in outs if o["length_s"] == 15]
assert o15 and max(o15) <= 15.0, outs
# Without the measured timing and latency and without the adaptation the walk loses track; with
# them and still without the adaptation it holds: the IMU model, not the noise scale, carries it.
off = load("walk_off.json")
assert not off["adaptive_noise"]["enabled"]
assert off["consistency"]["position"]["mean_nis"] > 2 * 3 or off["alignment"]["covariance_widenings"] > 0, off["consistency"]
ph = load("walk_physics.json")
assert ph["alignment"]["covariance_widenings"] == 0 and ph["alignment"]["realignments"] == 1, ph["alignment"]
assert share_rejected(ph) <= 0.05 and all(c["mean_nis"] / c["expected_nis"] <= 2.0 for c in ph["consistency"].values()), ph["consistency"]
for obs in ("pos,vel,att", "pos"):
    r = load("psins_%s.json" % obs)
    assert not r["adaptive_noise"]["enabled"], "auto is off against a reference INS"
    for k, c in r["consistency"].items():
        assert c["forced"] == 0, (obs, k, c)
    assert r.get("alignment", {}).get("realignments", 0) == 0, (obs, r.get("alignment"))
    assert share_rejected(r) <= 0.05, (obs, r["consistency"])
print("walk: heading at %.2f s, %.1f %% rejected, NIS/expected %.2f, %.2f; adaptive scale max %.3g, end %.3g; "
      "sample timing %.2f ms, velocity latency %.0f ms; 15-s outage %.1f m"
      % (al["heading"]["t_s"], 100 * share_rejected(w), w["consistency"]["position"]["mean_nis"] / 3,
         w["consistency"]["velocity"]["mean_nis"] / 3, an["scale_max"], an["scale_end"], st["sigma_ms"],
         1e3 * gl["used_s"], max(o15)))
PY
