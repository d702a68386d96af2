#!/usr/bin/env bash
# calbench db: init, store-bench, show, approve (refusal with reasons), export, revoke, history,
# devices, fleet; malformed inputs end with exit 2 and write nothing.
set -euo pipefail
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
cd "$T"
export CALBENCH_USER=qa-tester CALBENCH_STATION=line-3
fail() { echo "FAIL: $*" >&2; exit 1; }

coeffs() { python3 "$SRC/tests/support/make_coeffs.py" "$@"; }  # coeffs SERIAL SEED [sigma_gyro_bias] > file
count() { sqlite3 "$1" "SELECT COUNT(*) FROM $2"; }

"$CALBENCH" db init --db w.db | grep -q "schema version 9" || fail "init"
coeffs A100 1 > a1.json
"$CALBENCH" db store-bench --db w.db --coeffs a1.json --plan factory --sha256 "$(printf 'a%.0s' {1..64})" \
  --qc gyro_resid_rms=1e-5:1e-4:rad/s --firmware 1.10 | grep -q "set 1 (A100 v1, draft)" || fail "store-bench"
# CALBENCH_DB is honoured.
CALBENCH_DB=w.db "$CALBENCH" db show A100 | grep -q "set 1  v1  bench  draft" || fail "show via CALBENCH_DB"
"$CALBENCH" db approve 1 --operator qc-anna --db w.db | grep -q "approved" || fail "approve"
"$CALBENCH" db export 1 --db w.db --out e.json >/dev/null
python3 - a1.json e.json <<'PY' || fail "export differs from the stored set"
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:3])
assert a == b, (a, b)
PY
# A set with a too-large σ is refused with the reason, exit 1, stays draft.
coeffs A100 2 1e-3 > a2.json
"$CALBENCH" db store-bench --db w.db --coeffs a2.json --sha256 "$(printf 'b%.0s' {1..64})" --qc r=1:2 >/dev/null
set +e; "$CALBENCH" db approve 2 --operator qc-anna --db w.db 2> why.txt; rc=$?; set -e
[ "$rc" = 1 ] || fail "approve of a bad set: exit $rc"
grep -q "gyro bias x: σ = 206.3 °/h exceeds 10 °/h" why.txt || { cat why.txt; fail "refusal reason"; }
[ "$(sqlite3 w.db "SELECT status FROM coefficient_sets WHERE id = 2")" = draft ] || fail "refused set changed"
# A thresholds file can loosen it.
echo '{"gyro": {"max_sigma_bias_dph": 500}}' > th.json
"$CALBENCH" db approve 2 --operator qc-anna --db w.db --thresholds th.json --json | python3 -c 'import json,sys; assert json.load(sys.stdin)["approved"]'
echo '{"gyro": {"max_sigma_bias": 500}}' > typo.json
set +e; "$CALBENCH" db approve 2 --operator qc-anna --db w.db --thresholds typo.json 2> err.txt; rc=$?; set -e
[ "$rc" = 2 ] && grep -q "typo.json: 'gyro.max_sigma_bias': unknown key" err.txt || { cat err.txt; fail "thresholds typo"; }
"$CALBENCH" db revoke 1 --db w.db --reason "superseded" | grep -q revoked || fail "revoke"
set +e; "$CALBENCH" db approve 1 --operator qc-anna --db w.db >/dev/null 2>&1; rc=$?; set -e
[ "$rc" != 0 ] || fail "revoked set approved"
"$CALBENCH" db history A100 --db w.db > hist.txt
grep -q "qa-tester@line-3  coefficient_set 1  status  approved -> revoked: superseded" hist.txt || { cat hist.txt; fail "history"; }
grep -q "approve-refused" hist.txt || fail "refusal not in history"
"$CALBENCH" db devices --db w.db --json | python3 -c '
import json,sys; d=json.load(sys.stdin)["devices"]; assert len(d)==1 and d[0]["sets"]==2 and d[0]["firmware"]=="1.10", d'
for i in 1 2 3 4 5; do coeffs "F$i" "$((10+i))" > f.json; "$CALBENCH" db store-bench --db w.db --coeffs f.json --sha256 "$(printf 'c%.0s' {1..64})" >/dev/null; done
"$CALBENCH" db fleet --db w.db --json | python3 -c '
import json,sys; c=json.load(sys.stdin)["coefficients"]; assert len(c)==24 and all(x["n"]==6 for x in c), c[0]
# 6 devices are too few for a distribution: nothing is called an outlier (issue 56 item 14).
assert all(x["outliers_judged"] is False and x["outliers"] == [] for x in c), c[0]'
"$CALBENCH" db fleet --db w.db > fleet.txt
grep -q "outliers not judged: 6 device(s) are too few for a distribution (8 needed)" fleet.txt || { cat fleet.txt; fail "fleet of 6"; }

# Malformed inputs: exit 2, clear message, nothing written.
before=$(count w.db coefficient_sets)/$(count w.db audit_log)/$(count w.db devices)
head -c 200 a1.json > trunc.json
python3 -c 'import json; d=json.load(open("a1.json")); d["gyro"]["bias"][1]="0.1"; print(json.dumps(d))' > type.json
sed 's/"bias": \[/"bias": [NaN, /' a1.json > nan.json
python3 -c 'import json; d=json.load(open("a1.json")); d["device"]["serial"]="X\x27); DROP TABLE devices; --"; print(json.dumps(d))' > meta.json
for f in trunc type nan; do
  set +e; "$CALBENCH" db store-bench --db w.db --coeffs $f.json --sha256 "$(printf 'd%.0s' {1..64})" 2> err.txt; rc=$?; set -e
  [ "$rc" = 2 ] || fail "$f.json: exit $rc"
  grep -q "$f.json" err.txt || { cat err.txt; fail "$f.json: message does not name the file"; }
done
grep -q "'gyro.bias\[1\]'" <("$CALBENCH" db store-bench --db w.db --coeffs type.json 2>&1 || true) || fail "wrong-type field not named"
set +e; "$CALBENCH" db store-bench --db w.db --coeffs a1.json --qc "x=nan" 2> err.txt; rc=$?; set -e
[ "$rc" = 2 ] || fail "NaN QC accepted"
set +e; "$CALBENCH" db show NOPE --db w.db 2> err.txt; rc=$?; set -e
[ "$rc" = 2 ] && grep -q "unknown device 'NOPE'" err.txt || fail "unknown serial"
[ "$before" = "$(count w.db coefficient_sets)/$(count w.db audit_log)/$(count w.db devices)" ] || fail "bad input wrote something"
# SQL metacharacters in a serial are data, not SQL.
"$CALBENCH" db store-bench --db w.db --coeffs meta.json --sha256 "$(printf 'e%.0s' {1..64})" >/dev/null
"$CALBENCH" db show "X'); DROP TABLE devices; --" --db w.db | grep -q "v1  bench  draft" || fail "metacharacter serial"
[ "$(sqlite3 w.db 'PRAGMA integrity_check')" = ok ] || fail "integrity"
# A missing database is reported, not created, by read commands.
set +e; "$CALBENCH" db devices --db nothere.db 2> err.txt; rc=$?; set -e
[ "$rc" != 0 ] && [ ! -e nothere.db ] && grep -q "calbench db init" err.txt || fail "missing db"
echo "db_workflow: ok"
