#!/usr/bin/env bash
# Issue 35 items 2 and 8 and three of item 7 on a real PostgreSQL server (Debian package, temporary
# folder, free loopback port, stopped afterwards):
#   * `db user add` maps a login to a person (granting its group), `db user list`; bad logins exit 2;
#   * the signer is the login's person: an --operator that is another person is refused (exit 2,
#     naming the login and what to type), the person's name in any case and spacing or the login
#     itself is accepted, an unmapped QC login is refused (exit 2, what the admin runs);
#   * four-eyes compares logins: the same login under two typed names is refused, two logins under
#     one typed name are not;
#   * a status change without its audit row is refused by the database for a QC login and for the
#     owner (psql), and one written with its audit row passes and records the login;
#   * `db history` (text, --json) and the device report show login and name by each signature;
#   * a bench run stores its recording as file://HOST/absolute/path with the digest of its files;
#   * the provisioning login on a draft is told that a draft awaits approval;
#   * a URI without a database is exit 2, naming what is missing;
#   * a store at schema version 3 (schema.sql alone) with data is migrated to 8 by `db init`.
source "$SRC/tests/support/pg_test.sh"
cd "$T"
admin -d postgres -c "CREATE DATABASE calbench"
ADMIN="postgresql:///calbench?host=$T/pg&port=$port&user=calbench_admin"
"$CALBENCH" db init --db "$ADMIN" --roles --operator admin | grep -q "schema version 9" || fail "init"
export PGPASSFILE="$T/pgpass"
: > "$PGPASSFILE"; chmod 600 "$PGPASSFILE"
# Logins without a group: `db user add` grants it. tess is a QC login that may also store (both groups).
for name in station3 anna bob tess prov1 nobody; do
  pw=$(python3 -c 'import secrets; print(secrets.token_hex(12))')
  admin -d calbench -c "CREATE ROLE $name LOGIN PASSWORD '$pw'"
  echo "127.0.0.1:$port:calbench:$name:$pw" >> "$PGPASSFILE"
done
admin -d calbench -c "GRANT calbench_station TO station3, tess; GRANT calbench_qc TO nobody"
uri() { echo "postgresql://$1@127.0.0.1:$port/calbench"; }
run() { set +e; "$@" > out.txt 2> err.txt; rc=$?; set -e; }
export CALBENCH_STATION=line-3 CALBENCH_JOURNAL="$T/journal.db"
unset CALBENCH_OPERATOR CALBENCH_USER

# ---- the mapping ----
"$CALBENCH" db user add anna --name "Anna Berg" --role qc --db "$ADMIN" --operator admin > out.txt
grep -q "login anna = Anna Berg (qc, member of calbench_qc): added" out.txt || { cat out.txt; fail "user add"; }
[ "$(admin -d calbench -c "SELECT pg_has_role('anna', 'calbench_qc', 'MEMBER')")" = t ] || fail "calbench_qc not granted"
"$CALBENCH" db user add bob --name "Bob Ode" --role qc --db "$ADMIN" > /dev/null
"$CALBENCH" db user add tess --name "Tess Tuck" --role qc --db "$ADMIN" > /dev/null
"$CALBENCH" db user add prov1 --name "Pete Prov" --role provisioning --db "$ADMIN" > /dev/null
"$CALBENCH" db user add anna --name "Anna Berg" --role qc --db "$ADMIN" | grep -q ": unchanged" || fail "second add changed"
"$CALBENCH" db user list --db "$(uri bob)" --json | python3 -c '
import json, sys
u = {x["login"]: x for x in json.load(sys.stdin)["users"]}
assert sorted(u) == ["anna", "bob", "prov1", "tess"], u
assert u["anna"]["name"] == "Anna Berg" and u["anna"]["role"] == "qc" and u["anna"]["added_by"] == "calbench_admin", u["anna"]
assert u["prov1"]["role"] == "provisioning", u' || fail "user list"
[ "$(admin -d calbench -c "SELECT count(*) FROM audit_log WHERE entity = 'user' AND action = 'map'")" = 4 ] || fail "mapping not audited"
run "$CALBENCH" db user add ghost --name "G Host" --role qc --db "$ADMIN"
[ "$rc" = 2 ] && grep -q "LOGIN: no role 'ghost'.*CREATE ROLE ghost LOGIN" err.txt || { cat err.txt; fail "unknown login: exit $rc"; }
run "$CALBENCH" db user add calbench_qc --name "A Group" --role qc --db "$ADMIN"
[ "$rc" = 2 ] && grep -q "cannot log in (NOLOGIN)" err.txt || { cat err.txt; fail "group as login: exit $rc"; }
run "$CALBENCH" db user add anna --name "Anna Berg" --role admin --db "$ADMIN"
[ "$rc" = 2 ] && grep -q -- "--role" err.txt || { cat err.txt; fail "bad role: exit $rc"; }
run "$CALBENCH" db user add bob --name "bob@lab" --role qc --db "$ADMIN"
[ "$rc" = 2 ] && grep -q -- "--name: operator name 'bob@lab' must not contain '@'" err.txt || { cat err.txt; fail "bad name: exit $rc"; }
"$CALBENCH" db init --db s.db > /dev/null
# On SQLite `db user add` makes a web-console account (docs/console.md): its password from
# CALBENCH_PASSWORD or stdin, 8 characters at least, never on the command line.
run "$CALBENCH" db user add bob --name "Bob" --role qc --db s.db < /dev/null
[ "$rc" = 2 ] && grep -q "password: shorter than 8 characters" err.txt || { cat err.txt; fail "user add on SQLite without a password: exit $rc"; }
CALBENCH_PASSWORD=bob-secret-1 "$CALBENCH" db user add bob --name "Bob" --role qc --db s.db > out.txt
grep -q "console account bob = Bob (qc): added" out.txt || { cat out.txt; fail "user add on SQLite"; }
# The mapping table is the admin's: a QC login cannot map itself to someone else.
psql -h 127.0.0.1 -p "$port" -U anna -d calbench -w -qtAX -c "UPDATE calbench_users SET name = 'Bob Ode' WHERE login = 'anna'" \
  2> err.txt && fail "a QC login rewrote its person"
grep -q "permission denied" err.txt || { cat err.txt; fail "mapping rewrite refused for another reason"; }

# ---- sets to sign: a recording folder stored by the station's login ----
mkdir -p rec/sub
python3 -c 'import sys; print("t,gx,gy,gz,ax,ay,az"); [print(f"{i*0.01},0,0,0,0,0,9.81") for i in range(50)]' > rec/imu.csv
# meta.json names the unit: store-bench refuses a set with another unit's recording.
echo '{"format": "calbench-recording/1", "kind": "multipos", "device": {"model": "ADIS16488A", "serial": "S1"}, "imu_rate_hz": 100.0}' > rec/meta.json
printf 'x\0y' > rec/sub/blob.bin
coeffs() { python3 "$SRC/tests/support/make_coeffs.py" "$@"; }
coeffs S1 1 > c1.json; coeffs S1 2 > c2.json; coeffs S1 3 > c3.json; coeffs S1 4 > c4.json
"$CALBENCH" db store-bench --db "$(uri station3)" --coeffs c1.json --recording rec --qc residual=0.1:1 --operator sam > /dev/null
set1=$(admin -d calbench -c "SELECT max(id) FROM coefficient_sets")
# item 8: an absolute URI naming this host, and the digest of every file, computed independently.
row=$(admin -d calbench -c "SELECT recording_uri || ' ' || recording_digest FROM bench_runs ORDER BY id DESC LIMIT 1")
[ "$row" = "file://$(hostname)$T/rec $(python3 "$SRC/tests/support/folder_digest.py" rec)" ] || fail "recording uri/digest: $row"

# ---- the signer is the login's person ----
run "$CALBENCH" db approve "$set1" --db "$(uri anna)" --operator "Bob Ode"
[ "$rc" = 2 ] && grep -q "'Bob Ode' is not who is logged in: login 'anna' is Anna Berg; type --operator \"Anna Berg\"" err.txt \
  || { cat err.txt; fail "another person's name accepted: exit $rc"; }
[ "$(admin -d calbench -c "SELECT status FROM coefficient_sets WHERE id = $set1")" = draft ] || fail "refused signer changed the status"
run "$CALBENCH" db approve "$set1" --db "$(uri nobody)" --operator nobody
[ "$rc" = 2 ] && grep -q "login 'nobody' .* is not mapped to a person.*calbench db user add nobody" err.txt || { cat err.txt; fail "unmapped login: exit $rc"; }
# The station's own login may not sign at all: the database's refusal, exit 1.
run "$CALBENCH" db approve "$set1" --db "$(uri station3)" --operator sam
[ "$rc" = 1 ] && grep -q "refused this to role 'station3'" err.txt || { cat err.txt; fail "station login signed: exit $rc"; }
# The person's name in another case and spacing signs; the audit row carries the login and the name.
"$CALBENCH" db approve "$set1" --db "$(uri anna)" --operator "anna  BERG" > out.txt || { cat out.txt err.txt; fail "approve as anna"; }
[ "$(admin -d calbench -c "SELECT \"user\" || '|' || db_role FROM audit_log WHERE entity_id = $set1 AND action = 'status'")" = "Anna Berg|anna" ] \
  || fail "approval row: not the login's person"

# ---- four-eyes by login ----
# tess stores a set under a typed name that is not hers, then tries to approve it: the same login.
"$CALBENCH" db store-bench --db "$(uri tess)" --coeffs c2.json --sha256 "$(printf '%064x' 2)" --qc residual=0.1:1 \
  --operator "Somebody Else" > /dev/null
set2=$(admin -d calbench -c "SELECT max(id) FROM coefficient_sets")
[ "$(admin -d calbench -c "SELECT created_by_role FROM coefficient_sets WHERE id = $set2")" = tess ] || fail "created_by_role"
run "$CALBENCH" db approve "$set2" --db "$(uri tess)"
[ "$rc" = 1 ] && grep -q "four-eyes: set $set2 was stored by 'Somebody Else' with login 'tess' (Tess Tuck), and Tess Tuck (login tess) is the same person" err.txt \
  || { cat err.txt; fail "same login approved: exit $rc"; }
# A set stored by station3 under the typed name "Anna Berg": another login, but the same person
# (issue 54: four-eyes is between persons), so anna may not approve it; bob may.
"$CALBENCH" db store-bench --db "$(uri station3)" --coeffs c3.json --sha256 "$(printf '%064x' 3)" --qc residual=0.1:1 \
  --operator "Anna Berg" > /dev/null
set3=$(admin -d calbench -c "SELECT max(id) FROM coefficient_sets")
run "$CALBENCH" db approve "$set3" --db "$(uri anna)"
[ "$rc" = 1 ] && grep -q "four-eyes: set $set3 was stored by 'Anna Berg' with login 'station3'" err.txt \
  || { cat err.txt; fail "the person who ran the station approved its set: exit $rc"; }
"$CALBENCH" db approve "$set3" --db "$(uri bob)" > out.txt || { cat err.txt; fail "another person may approve"; }
grep -q "set $set3 approved" out.txt || fail "approve output"

# ---- a status change outside the server's functions: refused for everyone (issue 54) ----
"$CALBENCH" db store-bench --db "$(uri station3)" --coeffs c4.json --sha256 "$(printf '%064x' 4)" --qc residual=0.1:1 \
  --operator sam > /dev/null
set4=$(admin -d calbench -c "SELECT max(id) FROM coefficient_sets")
psql -h 127.0.0.1 -p "$port" -U anna -d calbench -w -v ON_ERROR_STOP=1 -qtAX \
  -c "update coefficient_sets set status='approved' where id=$set4" 2> err.txt && fail "QC login approved by psql"
grep -q "permission denied for table coefficient_sets" err.txt || { cat err.txt; fail "psql as QC refused for another reason"; }
admin -d calbench -c "update coefficient_sets set status='approved' where id=$set4" 2> err.txt && fail "the owner approved by psql"
grep -q "a status changes only through calbench_approve" err.txt || { cat err.txt; fail "psql as owner refused for another reason"; }
admin -d calbench -c "begin; set constraints all immediate; update coefficient_sets set status='revoked' where id=$set4; commit" \
  2> err.txt && fail "immediate constraints let a status change through"
# Even with a hand-written audit row in the same transaction (schema 8 let that through).
psql -h 127.0.0.1 -p "$port" -U anna -d calbench -w -v ON_ERROR_STOP=1 -qtAX -c "begin;
  update coefficient_sets set status='revoked' where id=$set4;
  insert into audit_log(\"user\", station, db_role, entity, entity_id, action, detail) values ('Anna Berg', 'psql', 'bob', 'coefficient_set', $set4, 'status', 'draft -> revoked: by hand');
  commit" 2> err.txt && fail "a status change with a hand-written audit row passed"
[ "$(admin -d calbench -c "SELECT status FROM coefficient_sets WHERE id = $set4")" = draft ] || fail "status changed by hand"
# Revoked through the function: the row names the login and its person.
psql -h 127.0.0.1 -p "$port" -U anna -d calbench -w -v ON_ERROR_STOP=1 -qtAX \
  -c "select calbench_revoke($set4, 'by hand', 'psql')" > /dev/null 2> err.txt || { cat err.txt; fail "calbench_revoke refused"; }
[ "$(admin -d calbench -c "SELECT db_role || ' ' || \"user\" FROM audit_log WHERE entity_id = $set4 AND action = 'status'")" = "anna Anna Berg" ] \
  || fail "the audit row of calbench_revoke"

# ---- history and report show login and name ----
"$CALBENCH" db history S1 --db "$(uri bob)" > hist.txt
grep -q "Anna Berg@line-3  coefficient_set $set1  status  draft -> approved: signed by Anna Berg (login anna), stored by sam (login station3).*\[login anna\]" hist.txt \
  || { cat hist.txt; fail "history text without login and name"; }
grep -q "recording file://$(hostname)$T/rec  SHA-256 of its files [0-9a-f]\{64\}" hist.txt || { cat hist.txt; fail "history without the recording URI"; }
"$CALBENCH" db history S1 --db "$(uri bob)" --json | python3 -c '
import json, sys
h = json.load(sys.stdin)
assert h["authenticated"] is True, h
sig = [e for e in h["history"] if e["action"] == "status" and e["entity_id"] == int(sys.argv[1])]
assert sig and sig[0]["login"] == "anna" and sig[0]["name"] == "Anna Berg", sig
runs = [e for e in h["history"] if e["entity"] == "bench_run"]
r = runs[0]["recording"]
assert r["uri"].startswith("file://") and r["uri"].endswith(sys.argv[2] + "/rec"), r
assert r["digest_sha256"] == sys.argv[3], r' "$set1" "$T" "$(python3 "$SRC/tests/support/folder_digest.py" rec)" || fail "history --json"
"$CALBENCH" report S1 --db "$(uri bob)" --html r.html > /dev/null
grep -q "Anna Berg@line-3 (login anna)" r.html || fail "report without the signer's login"
grep -q "file://$(hostname)$T/rec" r.html || fail "report without the recording URI"

# ---- item 7: the provisioning login on a draft; a URI without a database ----
coeffs S2 5 > c5.json
"$CALBENCH" db store-bench --db "$(uri station3)" --coeffs c5.json --sha256 "$(printf '%064x' 5)" --operator sam > /dev/null
set5=$(admin -d calbench -c "SELECT max(id) FROM coefficient_sets")
run "$CALBENCH" provision S2 --export p.json --db "$(uri prov1)"
[ "$rc" = 1 ] && grep -q "device S2 has no approved coefficient set: its newest, set $set5 (v1), is draft, awaiting approval: a QC login approves it (calbench db approve $set5 --db postgresql://QC_LOGIN@HOST/DB)" err.txt \
  || { cat err.txt; fail "provisioning on a draft: exit $rc"; }
! grep -q "has no coefficient set" err.txt || fail "still says no coefficient set"
run "$CALBENCH" db devices --db "postgresql://anna@127.0.0.1:$port"
[ "$rc" = 2 ] && grep -q "not a valid PostgreSQL URI: no database named" err.txt || { cat err.txt; fail "URI without a database: exit $rc"; }
run "$CALBENCH" db devices --db "postgresql://anna@127.0.0.1:$port/"
[ "$rc" = 2 ] && grep -q "no database named" err.txt || { cat err.txt; fail "URI with an empty database: exit $rc"; }

# ---- migration of an existing store: version 3 with data, then db init ----
admin -d postgres -c "CREATE DATABASE old"
admin -d old -1 -f "$SRC/db/postgres/schema.sql" > /dev/null
admin -d old -c "INSERT INTO devices(model, serial) VALUES ('ADIS16488A', 'OLD1');
  INSERT INTO coefficient_sets(device_id, version, source, payload_json, created_by) VALUES (1, 1, 'bench', '{}', 'old@x');
  INSERT INTO audit_log(\"user\", station, entity, entity_id, device_id, action) VALUES ('old', 'x', 'coefficient_set', 1, 1, 'create')"
"$CALBENCH" db init --db "postgresql:///old?host=$T/pg&port=$port&user=calbench_admin" --roles --operator admin | grep -q "schema version 9" \
  || fail "migration 3 -> 6"
[ "$(admin -d old -c "SELECT string_agg(version::text, ',' ORDER BY version) FROM schema_version")" = "3,4,5,6,7,8,9" ] || fail "versions"
[ "$(admin -d old -c "SELECT count(*) FROM audit_log WHERE action = 'create'")" = 1 ] || fail "old rows lost"
admin -d old -c "update coefficient_sets set status='approved' where id=1" 2> err.txt && fail "migrated store: approved by psql"
grep -q "a status changes only through calbench_approve" err.txt || { cat err.txt; fail "migrated store refused for another reason"; }
[ "$(admin -d old -c "SELECT creator FROM coefficient_sets WHERE id = 1")" = old ] || fail "creator of an older set"
echo "db_pg_signers: ok"
