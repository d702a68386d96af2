#!/usr/bin/env bash
# Outage QC of a GNSS-only drive (issue 34, item 5): fit drive and qc place simulated GNSS outages
# over the drive, navigate each inertial-only from the aided filter's state at its start with raw
# data and with the result, and measure the horizontal error against the fixes. The result must
# beat the raw data; qc on the recording with the same sets gives the same figures; RESULT.json's
# qc.outages keeps its contract; db import-inmotion carries it (with the never-worse check) and the
# device report plots it; bad --outages values exit 2 with a clear message.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
# The short test route at 100 Hz (4 minutes), GNSS fixes only (1 Hz, 0.3 m: the error of a short
# outage is then the navigation's, not the fixes' noise).
sed -e 's/^rate_hz = 400\.0$/rate_hz = 100.0/' \
    -e 's/^rate_hz = 1\.0$/rate_hz = 1.0\nsigma_h_m = 0.3\nsigma_v_m = 0.5\nsigma_vel_m_s = 0.03/' \
  "$SRC/bench/routes/short.toml" > "$T/route.toml"
grep -q '^sigma_h_m = 0.3' "$T/route.toml"
"$CALBENCH" simulate drive --route "$T/route.toml" --truth random --seed 11 --out "$T/rec" >/dev/null
rm "$T/rec/reference.csv"
O=(--outages 10,20 --outage-count 2 --outage-gap 10)

"$CALBENCH" fit drive "$T/rec" "${O[@]}" --out "$T/r.json" > "$T/summary.txt"
grep -q "outage QC (in-sample" "$T/summary.txt" || fail "no outage summary: $(cat "$T/summary.txt")"
"$CALBENCH" qc "$T/rec" --coeffs none --coeffs "$T/r.json" --from 0 "${O[@]}" --json > "$T/q.json"
"$CALBENCH" qc "$T/rec" --coeffs none --coeffs "$T/r.json" --from 0 "${O[@]}" | grep -q "simulated GNSS outages" || fail "qc text"
python3 - "$T" <<'PY'
import json, sys
d = sys.argv[1]
r = json.load(open(d + "/r.json"))
o = r["qc"]["outages"]
assert r["qc"]["sample"] == o["sample"] and o["sample"].startswith("in-sample"), r["qc"]["sample"]
for k in ("aided_by", "rule", "lengths_s", "count_per_length", "gap_s", "earliest_s", "start_condition", "nhc",
          "error", "set_names", "outages", "sets", "not_placed"):
    assert k in o, k
assert o["lengths_s"] == [10, 20] and o["count_per_length"] == 2 and o["gap_s"] == 10 and o["nhc"] is False
assert o["set_names"] == ["none", "in-motion"], o["set_names"]
L = o["outages"]
assert len(L) >= 2, (L, o["not_placed"])
prev_end = -1e9
for e in L:
    assert e["length_s"] in (10, 20) and e["fixes"] >= e["length_s"] - 1, e   # 1-Hz fixes
    assert e["start_s"] >= prev_end + 10 - 1e-6, (e, prev_end)             # no overlap, the gap kept
    prev_end = e["start_s"] + e["length_s"]
    for s in o["set_names"]:
        assert 0 <= e["end_m"][s] <= e["max_m"][s], e
assert len(L) + len(o["not_placed"]) == 4
# Per set and length: the median and the largest of the per-outage maxima.
by = {s["name"]: {p["length_s"]: p for p in s["per_length"]} for s in o["sets"]}
for name, per in by.items():
    for length, p in per.items():
        mx = sorted(e["max_m"][name] for e in L if e["length_s"] == length)
        assert p["count"] == len(mx) and abs(p["max_max_m"] - mx[-1]) < 1e-9, (name, p, mx)
        med = mx[len(mx) // 2] if len(mx) % 2 else 0.5 * (mx[len(mx) // 2 - 1] + mx[len(mx) // 2])
        assert abs(p["median_max_m"] - med) < 2e-3, (name, p, mx)
# The result navigates better than the raw data: per length (median of the largest errors), and
# through every outage of the longest length.
for length in by["none"]:
    assert by["in-motion"][length]["median_max_m"] < by["none"][length]["median_max_m"], (length, by)
for e in L:
    if e["length_s"] == 20:
        assert e["max_m"]["in-motion"] < e["max_m"]["none"], e
for length in by["none"]:
    print("outage %g s: median largest error raw %.2f m, result %.2f m" %
          (length, by["none"][length]["median_max_m"], by["in-motion"][length]["median_max_m"]))
# qc with the same sets: the same aided filter (raw data), the same outages and errors.
q = json.load(open(d + "/q.json"))["outages"]
assert [e["start_s"] for e in q["outages"]] == [e["start_s"] for e in L], (q["outages"], L)
for a, b in zip(q["outages"], L):
    assert abs(a["max_m"]["none"] - b["max_m"]["none"]) < 2e-3, (a, b)
    assert abs(a["max_m"]["r"] - b["max_m"]["in-motion"]) < 2e-3, (a, b)
PY

# Bad input: exit 2 with the option named.
for bad in "-5" "abc" "10,,20" "0" "1000"; do
  set +e; "$CALBENCH" fit drive "$T/rec" --outages="$bad" --out "$T/bad.json" 2> "$T/err.txt"; rc=$?; set -e
  [ $rc -eq 2 ] || fail "--outages $bad: exit $rc"
  grep -q -- "--outages" "$T/err.txt" || fail "--outages $bad: $(cat "$T/err.txt")"
  [ ! -e "$T/bad.json" ] || fail "--outages $bad wrote a result"
done
grep -q "longer than the drive" "$T/err.txt" || fail "1000 s: $(cat "$T/err.txt")"
set +e; "$CALBENCH" qc "$T/rec" --coeffs none --outages abc 2> "$T/err.txt"; rc=$?; set -e
[ $rc -eq 2 ] && grep -q -- "--outages" "$T/err.txt" || fail "qc --outages abc: exit $rc $(cat "$T/err.txt")"
for opt in "--horizon 50" "--plot $T/x.png"; do   # options of the reference QC that cannot act here
  set +e; "$CALBENCH" qc "$T/rec" --coeffs none $opt 2> "$T/err.txt"; rc=$?; set -e
  [ $rc -eq 2 ] && grep -q -- "${opt%% *}" "$T/err.txt" || fail "qc $opt: exit $rc $(cat "$T/err.txt")"
done
set +e; "$CALBENCH" fit drive "$T/rec" --outage-count 0 --out "$T/bad.json" 2> "$T/err.txt"; rc=$?; set -e
[ $rc -eq 2 ] || fail "--outage-count 0: exit $rc"

# The database keeps the outage figures; the result's median largest error of each length is
# checked against the raw data's; the device report plots them.
export CALBENCH_DB="$T/m.db"
"$CALBENCH" db init >/dev/null
python3 - "$T" <<'PY'
import json, sys
d = sys.argv[1]
r = json.load(open(d + "/r.json"))
c = {"format": "calbench-coefficients/1", "device": r["device"], "gyro": r["coefficients"]["gyro"],
     "accel": r["coefficients"]["accel"]}
json.dump(c, open(d + "/bench.json", "w"))
PY
"$CALBENCH" db store-bench --coeffs "$T/bench.json" --sha256 "$(printf 'a%.0s' {1..64})" --qc r=1:2 >/dev/null
"$CALBENCH" db import-inmotion "$T/r.json" --json > "$T/imp.json"
python3 - "$T" <<'PY'
import json, sys
d = sys.argv[1]
o = json.load(open(d + "/r.json"))["qc"]["outages"]
assert o["fix_sigma_h_m"] == 0.3, o["fix_sigma_h_m"]
import sqlite3
db = sqlite3.connect(d + "/m.db")
rows = {m: (v, th, p, s) for m, v, th, p, s in
        db.execute("SELECT metric, value, threshold, pass, sample FROM qc_results WHERE metric LIKE 'outages.%'")}
raw = {s["name"]: {p["length_s"]: p for p in s["per_length"]} for s in o["sets"]}
for length in (10, 20):
    v, th, ok, smp = rows["outages.in-motion.%ds.median_max_m" % length]
    base = raw["none"][length]["median_max_m"]
    assert abs(v - raw["in-motion"][length]["median_max_m"]) < 1e-9 and smp == "in-sample", rows
    assert abs(th - (base + 3 * 0.3)) < 1e-9 and ok == 1, (th, base, ok)   # never worse than raw, beyond the fixes' noise
    assert rows["outages.none.%ds.median_max_m" % length][1] is None         # the raw figures are informative
PY
SERIAL=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['device']['serial'])" "$T/r.json")
"$CALBENCH" report "$SERIAL" --html "$T/report.html" >/dev/null
python3 - "$T" <<'PY'
import re, sys
h = open(sys.argv[1] + "/report.html").read()
assert "Simulated GNSS outages" in h, "no outage part in the report"
assert "Circular position error ΔS(t)" not in h, "a GNSS-only run has no reference ΔS(t) to show"
m = re.search(r'<svg[^>]*class="outages"[^>]*>(.*?)</svg>', h, re.S)
assert m, "no outage plot"
curves = re.findall(r'data-curve="([^"]+)"', m.group(1))
assert "none" in curves and "in-motion" in curves, curves
assert re.search(r'outages\.in-motion\.10s\.median_max_m', h), "outage metric not in the QC table"
PY
echo "outage QC: ok"
