#!/usr/bin/env bash
# Issue 54 items 2, 5, 6 and 8 on the central PostgreSQL store (a throw-away server), each as the
# security review reproduced it:
#  2. four-eyes compared logins: Anna stored as anna_st and approved as anna;
#  5. bob approved in psql a set `db approve` refused for a failed QC metric (UPDATE plus a hand-
#     written audit row in one transaction), and provisioning wrote it;
#  6. any role appended misleading audit rows ("signed by Bob Ode" inserted by a station login);
#  8. a login changed from qc to station kept its QC rights.
source "$SRC/tests/support/pg_test.sh"
cd "$T"
admin -d postgres -c "CREATE DATABASE calbench"
ADMIN="postgresql:///calbench?host=$T/pg&port=$port&user=calbench_admin"
"$CALBENCH" db init --db "$ADMIN" --roles --operator admin > /dev/null
export PGPASSFILE="$T/pgpass"
: > "$PGPASSFILE"; chmod 600 "$PGPASSFILE"
for u in anna:qc anna_st:station bob:qc carl:qc prov1:provisioning; do
  login=${u%%:*}; role=${u#*:}; pw=$(python3 -c 'import secrets; print(secrets.token_hex(12))')
  admin -d calbench -c "CREATE ROLE $login LOGIN PASSWORD '$pw'"
  echo "127.0.0.1:$port:calbench:$login:$pw" >> "$PGPASSFILE"
  case $login in anna|anna_st) name="Anna Berg";; bob) name="Bob Ode";; carl) name="Carl Check";; *) name="Pete Prov";; esac
  "$CALBENCH" db user add "$login" --name "$name" --role "$role" --db "$ADMIN" --operator admin > /dev/null
done
uri() { echo "postgresql://$1@127.0.0.1:$port/calbench"; }
run() { set +e; "$@" > out.txt 2> err.txt; rc=$?; set -e; }
as() { psql -h 127.0.0.1 -p "$port" -U "$1" -d calbench -w -v ON_ERROR_STOP=1 -qtAX -c "$2"; }
refused() {  # refused LOGIN PATTERN SQL: fails with an error matching PATTERN
  if as "$1" "$3" > /dev/null 2> e.txt; then fail "$1 was allowed: $3"; fi
  grep -Eq "$2" e.txt || { cat e.txt; fail "$1 refused for another reason than /$2/: $3"; }
}
status() { admin -d calbench -c "SELECT status FROM coefficient_sets WHERE id = $1"; }
export CALBENCH_STATION=line-3 CALBENCH_JOURNAL="$T/journal.db"

# Two sets stored by Anna as anna_st: one clean, one with a failed QC metric.
"$CALBENCH" station run --plan "$SRC/tests/data/short_plan.toml" --emulated --db "$(uri anna_st)" --out st \
  --operator "Anna Berg" > st.txt 2>&1 || { cat st.txt; fail "station run"; }
python3 -c 'import json; c = json.load(open("st/COEFFS.json")); c["device"]["serial"] = "2002"; json.dump(c, open("c2.json", "w"))'
"$CALBENCH" db store-bench --db "$(uri anna_st)" --coeffs c2.json --sha256 "$(printf '%064x' 2)" --qc residual=5:1 \
  --operator "Anna Berg" > /dev/null
[ "$(admin -d calbench -c "SELECT creator || '|' || created_by_role FROM coefficient_sets WHERE id = 1")" = "Anna Berg|anna_st" ] \
  || fail "creator and login of set 1"

# ---- 2: four-eyes between persons, in the client and in the database ----
run "$CALBENCH" db approve 1 --db "$(uri anna)"
[ "$rc" = 1 ] && grep -q "four-eyes: set 1 was stored by 'Anna Berg' with login 'anna_st' (Anna Berg), and Anna Berg (login anna) is the same person" err.txt \
  || { cat err.txt; fail "Anna approved her own set under another login: exit $rc"; }
# The database says the same when asked directly (no client reasons).
[ "$(as anna "SELECT array_to_string(calbench_approve(1, 'psql', '{}', ''), '|')")" = \
  "four-eyes: set 1 was stored by Anna Berg (login anna_st, Anna Berg); Anna Berg (login anna) is the same person: another person must approve it" ] \
  || fail "calbench_approve let the same person approve"
[ "$(status 1)" = draft ] || fail "set 1 approved by its creator"
[ "$(admin -d calbench -c "SELECT count(*) FROM audit_log WHERE entity_id = 1 AND action = 'approve-refused' AND db_role = 'anna'")" = 2 ] \
  || fail "refusals not audited"

# ---- 5: approval only through calbench_approve, which runs the database's verdict ----
run "$CALBENCH" db approve 2 --db "$(uri bob)"
[ "$rc" = 1 ] && grep -q "QC residual = 5 failed" err.txt || { cat err.txt; fail "db approve of the failed set: exit $rc"; }
refused bob "permission denied for table (coefficient_sets|audit_log)" "BEGIN; UPDATE coefficient_sets SET status = 'approved' WHERE id = 2;
  INSERT INTO audit_log(\"user\", station, entity, entity_id, action, detail) VALUES ('Bob Ode', 'psql', 'coefficient_set', 2, 'status', 'draft -> approved: by hand'); COMMIT"
admin -d calbench -c "UPDATE coefficient_sets SET status = 'approved' WHERE id = 2" 2> e.txt && fail "the owner approved by hand"
grep -q "a status changes only through calbench_approve" e.txt || { cat e.txt; fail "owner refused for another reason"; }
[ "$(as bob "SELECT array_to_string(calbench_approve(2, 'psql', '{}', 'by hand'), '|')")" = \
  "QC residual = 5 failed (threshold 1) (the database's check)" ] || fail "calbench_approve approved a failed set"
[ "$(status 2)" = draft ] || fail "the failed set was approved"
# The database holds the device classes' coefficient limits (db init): a set with accel M.xx = -0.6
# passes no calbench_approve, whatever the caller says of thresholds.
[ "$(admin -d calbench -c "SELECT source FROM approval_limits WHERE model = 'adis16488a'")" = "class ADIS16488A" ] \
  || fail "db init did not write the class limits"
python3 -c 'import json; c = json.load(open("st/COEFFS.json")); c["device"]["serial"] = "4004"; c["accel"]["M"][0][0] = -0.6; json.dump(c, open("c4.json", "w"))'
"$CALBENCH" db store-bench --db "$(uri anna_st)" --coeffs c4.json --sha256 "$(printf '%064x' 4)" --qc residual=0.1:1 \
  --operator "Anna Berg" > /dev/null
big=$(admin -d calbench -c "SELECT s.id FROM coefficient_sets s JOIN devices d ON d.id = s.device_id WHERE d.serial = '4004'")
as bob "SELECT array_to_string(calbench_approve($big, 'psql', '{}', 'thresholds: lax.json'), '|')" > r.txt
grep -q "accel.M.xx = -0.6 exceeds the database's scale limit 0.025 (class ADIS16488A)" r.txt || { cat r.txt; fail "calbench_approve passed a -0.6 scale"; }
[ "$(status "$big")" = draft ] || fail "the -0.6 set was approved"
# Provisioning re-checks: nothing approved without its signed row reaches a file.
run "$CALBENCH" provision 2002 --set 2 --export x.json --db "$(uri prov1)"
[ "$rc" != 0 ] && [ ! -e x.json ] || { cat err.txt; fail "the failed draft was provisioned"; }
refused prov1 "not approved" "SELECT calbench_record_provisioning(2, 'export', 'f', true, '{}', '', 'psql')"
refused prov1 "permission denied for table (provisioning_events|coefficient_sets)" \
  "INSERT INTO provisioning_events(set_id, device_id, kind, target, ok, actor) VALUES (1, 1, 'export', 'f', true, 'x')"
# The clean set: approved by bob (another person), provisioned, its rows written by the functions.
"$CALBENCH" db approve 1 --db "$(uri bob)" > /dev/null || fail "bob approves set 1"
"$CALBENCH" provision 1001 --export y.json --db "$(uri prov1)" > /dev/null || fail "provision set 1"
[ "$(admin -d calbench -c "SELECT db_role || '|' || \"user\" FROM audit_log WHERE entity_id = 1 AND action = 'status' ORDER BY id LIMIT 1")" = "bob|Bob Ode" ] \
  || fail "the approval row"
[ "$(admin -d calbench -c "SELECT count(*) FROM audit_log WHERE entity_id = 1 AND action = 'export' AND db_role = 'prov1'")" = 1 ] \
  || fail "the export row"

# ---- 6: audit rows only from the functions that make the change ----
refused anna_st "permission denied for table audit_log" "INSERT INTO audit_log(\"user\", station, entity, entity_id, action, detail)
  VALUES ('Bob Ode', 'x', 'coefficient_set', 1, 'status', 'draft -> approved: signed by Bob Ode')"
refused anna_st "written only by the function that makes the change" "SELECT calbench_audit('coefficient_set', 1, 'status', 'signed by Bob Ode', 'Bob Ode', 'x')"
refused anna_st "names a row its own transaction wrote" "SELECT calbench_audit('coefficient_set', 1, 'create', 'signed by Bob Ode', 'Bob Ode', 'x')"
refused anna_st "not a security event" "SELECT calbench_audit_security('status', 'x', 'signed by Bob Ode', 'x')"
refused bob "permission denied for table settings" "UPDATE settings SET value = 'off'"
refused anna_st "permission denied" "SELECT calbench_set_setting('four_eyes', 'off', 'x')"
[ "$(admin -d calbench -c "SELECT count(*) FROM audit_log WHERE detail LIKE '%signed by Bob Ode%' AND db_role <> 'bob'")" = 0 ] || fail "a forged row got in"
# A security event is written as the login itself, whatever name it gives.
as anna_st "SELECT calbench_audit_security('refused', 'anna_st', 'tried', 'x')" > /dev/null
[ "$(admin -d calbench -c "SELECT \"user\" || '|' || db_role FROM audit_log WHERE entity = 'security'")" = "Anna Berg|anna_st" ] || fail "security row"

# ---- 8: a role change takes the old group away at once ----
python3 -c 'import json; c = json.load(open("st/COEFFS.json")); c["device"]["serial"] = "3003"; json.dump(c, open("c3.json", "w"))'
"$CALBENCH" db store-bench --db "$(uri anna_st)" --coeffs c3.json --sha256 "$(printf '%064x' 3)" --qc residual=0.1:1 \
  --operator "Anna Berg" > /dev/null
"$CALBENCH" db user add carl --name "Carl Check" --role station --db "$ADMIN" --operator admin | grep -q "changed" || fail "role change"
[ "$(admin -d calbench -c "SELECT pg_has_role('carl', 'calbench_qc', 'MEMBER')")" = f ] || fail "carl still in calbench_qc"
s3=$(admin -d calbench -c "SELECT s.id FROM coefficient_sets s JOIN devices d ON d.id = s.device_id WHERE d.serial = '3003'")
run "$CALBENCH" db approve "$s3" --db "$(uri carl)"
[ "$rc" = 1 ] && grep -q "refused this to role 'carl'" err.txt || { cat err.txt; fail "carl approved as station: exit $rc"; }
refused carl "permission denied" "SELECT calbench_approve($s3, 'psql', '{}', '')"
[ "$(status "$s3")" = draft ] || fail "set $s3 approved by a former QC login"
echo "db_pg_insider: ok"
