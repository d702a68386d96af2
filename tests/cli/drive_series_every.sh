#!/usr/bin/env bash
# fit drive --series-every: the forward-pass series gets rows between the epochs the filter used
# (its solution through a gap in the fixes), and the filter is only read: the rows at the used
# epochs and RESULT.json's estimates are those of the run without it.
set -euo pipefail
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$CALBENCH" simulate drive --route "$SRC/bench/routes/rtk_town.toml" --truth random --seed 2 --until 70 --out "$T/s" > /dev/null
# The fixes of 50 < t <= 60 removed (as bench/drive/peer_outages.py makes its outages, its outage_copy).
python3 -c "import sys; sys.path.insert(0, sys.argv[1]); from peer_outages import outage_copy; k, r = outage_copy(sys.argv[2], sys.argv[3], [(50, 60)]); assert r > 0, r" "$SRC/bench/drive" "$T/s" "$T/d"
"$CALBENCH" fit drive "$T/d" --aiding gnss --outages none --series "$T/a.csv" --out "$T/a.json" > /dev/null
"$CALBENCH" fit drive "$T/d" --aiding gnss --outages none --series "$T/b.csv" --series-every 0.5 --out "$T/b.json" > /dev/null
python3 - "$T" <<'PY'
import json, sys
T = sys.argv[1]
a = open(T + "/a.csv").read().splitlines()
b = open(T + "/b.csv").read().splitlines()
assert a[:2] == b[:2], "header"
rows_a, rows_b = a[2:], b[2:]
ta = [float(l.split(",")[0]) for l in rows_a]
tb = [float(l.split(",")[0]) for l in rows_b]
# Every row of the plain series is in the other, unchanged.
sb = set(rows_b)
missing = [l for l in rows_a if l not in sb]
assert not missing, missing[:2]
# Inside the gap: no row without the option, a row every 0.5 s with it (50.5 ... 60).
assert not any(50.2 < t < 60 for t in ta), [t for t in ta if 50.2 < t < 60]
gap = [t for t in tb if 50.2 < t < 60]
assert len(gap) == 19 and all(abs(t * 2 - round(t * 2)) < 1e-9 for t in gap), gap
assert tb == sorted(tb)
ra, rb = json.load(open(T + "/a.json")), json.load(open(T + "/b.json"))
keys = ("coefficients", "mounting_rpy_deg", "consistency", "alignment", "recoveries", "adaptive_noise", "in_run_drift_end")
for k in keys:
    assert k in ra, (k, list(ra))
    assert ra[k] == rb[k], k
PY
echo OK
