#!/usr/bin/env bash
# Issue 54 items 1, 3 and 4 on a SQLite store, each as the security review reproduced it:
#  1. an '@' in the station name made the creator parse as another person (four-eyes defeated);
#  3. anyone who could write the file reset a QC account's password (account take-over);
#  4. `UPDATE coefficient_sets SET status = 'approved'` by hand was provisioned, and one hand-inserted
#     audit row turned the device report to PASS.
set -euo pipefail
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
cd "$T"
fail() { echo "FAIL: $*" >&2; exit 1; }
unset CALBENCH_OPERATOR CALBENCH_USER CALBENCH_PASSWORD CALBENCH_ADMIN_PASSWORD CALBENCH_CURRENT_PASSWORD
export CALBENCH_DB="$T/s.db"
run() { set +e; "$@" > out.txt 2> err.txt; rc=$?; set -e; }
status() { sqlite3 s.db "SELECT status FROM coefficient_sets WHERE id = $1"; }

# ---- 1: the creator is a field of its own; a station called bench@hall-2 changes nothing ----
CALBENCH_STATION='bench@hall-2' "$CALBENCH" station run --plan "$SRC/tests/data/short_plan.toml" --emulated --db s.db \
  --out run --operator "Tess Tuck" > /dev/null 2>&1 || fail "station run"
[ "$(sqlite3 s.db "SELECT creator || '|' || created_by FROM coefficient_sets WHERE id = 1")" = "Tess Tuck|Tess Tuck@bench@hall-2" ] \
  || fail "creator field"
run "$CALBENCH" db approve 1 --operator "Tess Tuck"
[ "$rc" = 1 ] && grep -q "four-eyes: set 1 was stored by 'Tess Tuck'" err.txt || { cat out.txt err.txt; fail "self-approval under station bench@hall-2: exit $rc"; }
[ "$(status 1)" = draft ] || fail "approved by its creator"
# The same through a console account of the creator's (login tess, person Tess Tuck), on a station 'line@3'.
CALBENCH_PASSWORD=tess-pass-1 "$CALBENCH" db user add tess --name "Tess Tuck" --role qc > /dev/null
CALBENCH_STATION='line@3' "$CALBENCH" db store-bench --coeffs run/COEFFS.json --recording run/recording \
  --operator tess --qc residual=0.1:1 > /dev/null
run "$CALBENCH" db approve 2 --operator "Tess Tuck"
[ "$rc" = 1 ] && grep -q "four-eyes" err.txt || { cat err.txt; fail "the login's person approved a set stored under the login: exit $rc"; }

# ---- 3: changing an account needs its password or an admin's ----
CALBENCH_PASSWORD=rita-pass-1 "$CALBENCH" db user add qc2 --name "Rita Review" --role qc > /dev/null
run env CALBENCH_PASSWORD=sam-owns-rita-1 "$CALBENCH" db user add qc2 --name "Rita Review" --role qc --operator "Sam Station"
[ "$rc" = 1 ] && grep -q "account 'qc2' exists: changing it needs its current password" err.txt || { cat err.txt; fail "take-over: exit $rc"; }
run env CALBENCH_PASSWORD=sam-owns-rita-1 CALBENCH_CURRENT_PASSWORD=wrong-pass-1 "$CALBENCH" db user add qc2 --name "Rita Review" --role qc
[ "$rc" = 1 ] || fail "a wrong current password changed the account"
# Her own password changes it, and only the password.
CALBENCH_PASSWORD=rita-pass-2 CALBENCH_CURRENT_PASSWORD=rita-pass-1 "$CALBENCH" db user add qc2 --name "Rita Review" --role qc \
  | grep -q "authorized by its own password" || fail "own password change"
run env CALBENCH_PASSWORD=rita-pass-3 CALBENCH_CURRENT_PASSWORD=rita-pass-2 "$CALBENCH" db user add qc2 --name "Rita Review" --role station
[ "$rc" = 1 ] && grep -q "a new name or role needs an admin account" err.txt || { cat err.txt; fail "role changed with the own password"; }
# The first admin of a store with accounts: only with a qc account's password.
run env CALBENCH_PASSWORD=admin-pass-1 "$CALBENCH" db user add boss --name "Ada Admin" --role admin
[ "$rc" = 1 ] || fail "an admin appointed by nobody"
CALBENCH_PASSWORD=admin-pass-1 CALBENCH_ADMIN_PASSWORD=rita-pass-2 "$CALBENCH" db user add boss --name "Ada Admin" --role admin \
  --admin qc2 > /dev/null || fail "the first admin, appointed by a qc account"
# With an admin, nobody else adds accounts; the admin does, and changes roles.
run env CALBENCH_PASSWORD=sam-pass-11 "$CALBENCH" db user add sam --name "Sam Station" --role qc
[ "$rc" = 1 ] && grep -q "this store has an admin account" err.txt || { cat err.txt; fail "account added without the admin"; }
CALBENCH_PASSWORD=sam-pass-11 CALBENCH_ADMIN_PASSWORD=admin-pass-1 "$CALBENCH" db user add sam --name "Sam Station" \
  --role station --admin boss | grep -q "authorized by admin boss" || fail "the admin adds an account"
# An admin signs nothing.
run "$CALBENCH" db verify
[ "$rc" = 0 ] || { cat out.txt; fail "verify after calbench's own changes"; }
# An account row edited with sqlite3 is found by db verify.
sqlite3 s.db "UPDATE console_accounts SET role = 'qc' WHERE login = 'sam'"
run "$CALBENCH" db verify --json
[ "$rc" = 1 ] && python3 -c 'import json,sys; d=json.load(open("out.txt")); assert any(p.get("console_account")=="sam" for p in d["problems"]), d' \
  || { cat out.txt; fail "edited account not found"; }
sqlite3 s.db "UPDATE console_accounts SET role = 'station' WHERE login = 'sam'"

# ---- 4: an approval needs its signed row; a forged row breaks the chain ----
if sqlite3 s.db "UPDATE coefficient_sets SET status = 'approved' WHERE id = 1" 2> upd.txt; then fail "status approved by hand"; fi
grep -q "an approval is made with its signed audit row" upd.txt || { cat upd.txt; fail "refused for another reason"; }
run "$CALBENCH" provision 1001 --set 1 --export x.json --operator "Pat Prov"
[ "$rc" = 1 ] && [ ! -e x.json ] || fail "a draft provisioned"
# A forged approval row with a made-up chain value lets the UPDATE through; verify, the report and
# provisioning all see it.
sqlite3 s.db "INSERT INTO audit_log(at, user, station, entity, entity_id, device_id, action, detail, db_role, chain)
  VALUES ('2026-11-29T10:00:00.000Z', 'Bob Ode', 'x', 'coefficient_set', 1, 1, 'status', 'draft -> approved: signed by Bob Ode', 'bob', 'ab');
  UPDATE coefficient_sets SET status = 'approved' WHERE id = 1"
[ "$(status 1)" = approved ] || fail "the forgery did not take"
run "$CALBENCH" db verify
[ "$rc" = 1 ] && grep -q "hash chain BROKEN" out.txt && grep -q "the approval row of set 1" out.txt || { cat out.txt; fail "verify missed the forged row"; }
run "$CALBENCH" provision 1001 --set 1 --export x.json --operator "Pat Prov"
[ "$rc" = 1 ] && grep -q "fails the audit log's hash chain" err.txt && [ ! -e x.json ] || { cat err.txt; fail "the forged approval was provisioned"; }
"$CALBENCH" report 1001 --html r.html > /dev/null
grep -q 'data-verdict="FAIL"' r.html && grep -q "its chain value does not match its contents" r.html || fail "the forged approval passed the report"
[ "$(sqlite3 s.db "SELECT count(*) FROM provisioning_events")" = 0 ] || fail "a provisioning event was recorded"
# A calbench approval by another person: verify and provisioning pass again for that set.
"$CALBENCH" db approve 2 --operator "Quinn QC" > /dev/null || fail "approval by another person"
"$CALBENCH" provision 1001 --set 2 --export y.json --operator "Pat Prov" > /dev/null || fail "a valid set refused"
echo "db_insider_sqlite: ok"
