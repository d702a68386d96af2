#!/usr/bin/env bash
# Two calbench processes storing sets into one database at the same time: none lost, no
# "database is locked" reaches the user. (The 2 × 200 acceptance run is DbConcurrency in test_db.)
set -euo pipefail
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
cd "$T"
fail() { echo "FAIL: $*" >&2; exit 1; }
export CALBENCH_DB="$T/c.db"
python3 - <<'PY'
import json
z = lambda: {"bias": [0.0] * 3, "M": [[0.0] * 3 for _ in range(3)], "sigma_bias": [1e-6] * 3, "sigma_M": [[1e-5] * 3 for _ in range(3)]}
json.dump({"format": "calbench-coefficients/1", "device": {"model": "ADIS16488A", "serial": "C1"}, "gyro": z(), "accel": z()}, open("c.json", "w"))
PY
"$CALBENCH" db init >/dev/null
writer() { for i in $(seq 1 25); do "$CALBENCH" db store-bench --coeffs c.json --sha256 "$(printf 'a%.0s' {1..64})" >/dev/null || echo "failed $i"; done; }
writer 2> w1.err > w1.out & p1=$!
writer 2> w2.err > w2.out & p2=$!
wait $p1; wait $p2
! grep -qi "locked" w1.err w2.err || fail "'database is locked' surfaced: $(cat w1.err w2.err)"
! grep -q failed w1.out w2.out || fail "a store failed: $(cat w1.out w2.out w1.err w2.err)"
[ "$(sqlite3 "$CALBENCH_DB" "SELECT COUNT(*)||'/'||COUNT(DISTINCT version)||'/'||MAX(version) FROM coefficient_sets")" = "50/50/50" ] || fail "sets lost"
echo "db_concurrency: ok"
