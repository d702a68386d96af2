#!/usr/bin/env bash
# Issue 18 through the CLI, on a real PostgreSQL server (Debian package, temporary folder, free
# loopback port, stopped afterwards):
#   * `db init --roles` by the owner, twice at once on an empty database (one migration);
#   * a station's credentials store runs and drafts (through its journal) but cannot approve or
#     revoke: exit 1 with the role named; QC approves; provisioning writes the set to an
#     emulated unit and records it;
#   * the server stopped half-way through a station run: it completes on its journal; with the
#     server still away, stores go to the journal, `db sync --status` lists them,
#     `db sync` forwards it after the restart; 20 syncs killed with SIGKILL at random points,
#     then one to the end: every journal item at the centre exactly once;
#   * bad targets: a malformed URI (exit 2, no journal written), an unreachable host and wrong
#     credentials (exit 1, the password never echoed), an older schema (exit 1, what to do).
source "$SRC/tests/support/pg_test.sh"
cd "$T"
admin -d postgres -c "CREATE DATABASE calbench"
ADMIN="postgresql:///calbench?host=$T/pg&port=$port&user=calbench_admin"

# Two processes initialise the empty database at once: one migration, both succeed.
"$CALBENCH" db init --db "$ADMIN" --roles --operator admin > i1.txt 2>&1 &
p1=$!
"$CALBENCH" db init --db "$ADMIN" --roles --operator admin > i2.txt 2>&1 || { cat i2.txt; fail "second init"; }
wait $p1 || { cat i1.txt; fail "first init"; }
grep -q "schema version 9" i1.txt && grep -q "schema version 9" i2.txt || fail "init output"
[ "$(admin -d calbench -c "SELECT count(*) FROM schema_version WHERE version = 5")" = 1 ] || fail "migrated twice"
[ "$(admin -d calbench -c "SELECT count(*) FROM audit_log WHERE entity = 'schema' AND action = 'migrate'")" = 1 ] || fail "migration audited twice"

export PGPASSFILE="$T/pgpass"
: > "$PGPASSFILE"; chmod 600 "$PGPASSFILE"
declare -A PW
for u in station3:calbench_station anna:calbench_qc prov1:calbench_provisioning reader1:calbench_reader; do
  name=${u%%:*}; group=${u#*:}; PW[$name]=$(python3 -c 'import secrets; print(secrets.token_hex(12))')
  admin -d calbench -c "CREATE ROLE $name LOGIN PASSWORD '${PW[$name]}' IN ROLE $group"
  echo "127.0.0.1:$port:calbench:$name:${PW[$name]}" >> "$PGPASSFILE"
done
uri() { echo "postgresql://$1@127.0.0.1:$port/calbench"; }
ST=$(uri station3) QC=$(uri anna) PV=$(uri prov1) RD=$(uri reader1)
# The people who sign with the QC and provisioning logins (issue 35).
"$CALBENCH" db user add anna --name anna --role qc --db "$ADMIN" --operator admin > /dev/null
"$CALBENCH" db user add prov1 --name pete --role provisioning --db "$ADMIN" --operator admin > /dev/null
export CALBENCH_STATION=line-3 CALBENCH_JOURNAL="$T/journal.db"

# A station run on emulated hardware into the central store (through the journal).
"$CALBENCH" station run --plan "$SRC/bench/plans/factory.toml" --emulated --seed 5 --db "$ST" --out st \
  --operator sam > st.txt 2>&1 || { cat st.txt; fail "station run"; }
grep -q "forwarded to postgresql://station3@127.0.0.1:$port/calbench: 1005 run 1 (pass) -> central run" st.txt || { cat st.txt; fail "station did not forward"; }
set_id=$(sed -n 's/^next: calbench db approve \([0-9]*\) --db postgresql.*/\1/p' st.txt)
[ -n "$set_id" ] || { cat st.txt; fail "no central set in the next-step hint"; }
grep -q "^next: calbench db approve $set_id --db postgresql://QC_LOGIN@127.0.0.1:$port/calbench" st.txt || { cat st.txt; fail "the hint does not say QC approves"; }
[ "$(admin -d calbench -c "SELECT s.status || ' ' || s.created_by || ' ' || s.created_by_role || ' ' || st.name FROM coefficient_sets s JOIN bench_runs r ON r.id = s.bench_run_id JOIN stations st ON st.id = r.station_id WHERE s.id = $set_id")" = "draft sam@line-3 station3 line-3" ] \
  || fail "central set not recorded as the station's draft"

# The station's credentials cannot approve or revoke (refused by the database), exit 1, role named.
for cmd in "approve $set_id" "revoke $set_id --reason x"; do
  set +e; "$CALBENCH" db $cmd --db "$ST" --operator sam2 2> err.txt; rc=$?; set -e
  [ "$rc" = 1 ] || fail "station: db $cmd exit $rc"
  grep -q "refused this to role 'station3': permission denied for table coefficient_sets" err.txt || { cat err.txt; fail "station: db $cmd message"; }
done
# A reader reads, and cannot store.
"$CALBENCH" db show 1005 --db "$RD" | grep -q "set $set_id  v1  bench  draft" || fail "reader cannot read"
# QC approves (signed, four-eyes), provisioning writes it to the unit and records it.
"$CALBENCH" db approve "$set_id" --db "$QC" --operator anna | grep -q "set $set_id approved" || fail "QC approve"
set +e; "$CALBENCH" provision 1005 --to-device emu://1005 --db "$QC" --operator anna > /dev/null 2> err.txt; rc=$?; set -e
[ "$rc" = 1 ] && grep -q "refused this to role 'anna'" err.txt || { cat err.txt; fail "QC provisioned (exit $rc)"; }
"$CALBENCH" provision 1005 --to-device emu://1005 --db "$PV" --operator pete > pv.txt 2>&1 || { cat pv.txt; fail "provision"; }
[ "$(admin -d calbench -c "SELECT status FROM coefficient_sets WHERE id = $set_id")" = provisioned ] || fail "not provisioned"
x=$(admin -d calbench -c "SELECT db_role || ' ' || ok FROM provisioning_events WHERE set_id = $set_id"); [ "$x" = "prov1 true" ] || fail "provisioning event: $x"
"$CALBENCH" db history 1005 --db "$RD" > hist.txt
grep -q "anna@line-3  coefficient_set $set_id  status  draft -> approved" hist.txt || { cat hist.txt; fail "history"; }

# The server away: stores go to the journal; sync forwards them after the restart.
coeffs() { python3 "$SRC/tests/support/make_coeffs.py" "$@"; }
# A station run while the server goes away half-way: it completes on the journal (exit 0) and says so.
"$CALBENCH" station run --plan "$SRC/bench/plans/factory.toml" --emulated --seed 6 --db "$ST" --out st6 \
  --operator sam > st6.txt 2>&1 &
spid=$!
for _ in $(seq 1 600); do grep -q "step 19/38" st6.txt && break; kill -0 $spid 2>/dev/null || break; sleep 0.05; done
grep -q "step 19/38" st6.txt || { cat st6.txt; fail "the station did not get half-way"; }
"$SRC/tests/support/pg_server.sh" stop "$T/pg"
wait $spid || { cat st6.txt; fail "station run with the server away: exit $?"; }
grep -q "central store not reached" st6.txt && grep -q "^next: calbench db sync" st6.txt || { cat st6.txt; fail "offline station run"; }
N=30
for i in $(seq 1 $N); do
  coeffs "J$((i % 7))" "$i" > c.json
  "$CALBENCH" db store-bench --db "$ST" --coeffs c.json --sha256 "$(printf '%064x' "$i")" --operator sam > sb.txt 2>&1 \
    || { cat sb.txt; fail "store-bench offline exit"; }
done
grep -q "central store not reached" sb.txt || { cat sb.txt; fail "offline store did not say so"; }
"$CALBENCH" db sync --db "$ST" --status | grep -q "$((N + 1)) run(s) not yet in" || fail "sync --status"
set +e; "$CALBENCH" db sync --db "$ST" > /dev/null 2> err.txt; rc=$?; set -e
[ "$rc" = 1 ] && grep -q "central store not reached" err.txt || { cat err.txt; fail "sync with the server away: exit $rc"; }
"$SRC/tests/support/pg_server.sh" start "$T/pg" > /dev/null
newport=$(cat "$T/pg/port")
if [ "$newport" != "$port" ]; then  # a new free port: point the URIs and the password file at it
  sed -i "s/^127.0.0.1:$port:/127.0.0.1:$newport:/" "$PGPASSFILE"; port=$newport; ST=$(uri station3)
fi
# 20 syncs killed at random points, then one to the end.
for k in $(seq 1 20); do
  "$CALBENCH" db sync --db "$ST" > /dev/null 2>&1 &
  pid=$!
  sleep "0.$(printf '%03d' $((RANDOM % 250)))"
  kill -9 $pid 2>/dev/null || true
  wait $pid 2>/dev/null || true
done
"$CALBENCH" db sync --db "$ST" > sync.txt || { cat sync.txt; fail "final sync"; }
"$CALBENCH" db sync --db "$ST" --status | grep -q "0 run(s) not yet in" || fail "pending after the final sync"
# Every journal item is at the centre exactly once, whole, with gapless versions per serial.
juids=$(sqlite3 "$T/journal.db" "SELECT uid FROM bench_runs ORDER BY uid" | tr '\n' ' ')
cuids=$(admin -d calbench -c "SELECT uid FROM bench_runs WHERE uid IS NOT NULL ORDER BY uid" | tr '\n' ' ')
[ "$juids" = "$cuids" ] || fail "journal and centre differ: $(echo "$juids" | wc -w) vs $(echo "$cuids" | wc -w) runs"
[ "$(admin -d calbench -c "SELECT count(*) FROM coefficient_sets s JOIN bench_runs r ON r.id = s.bench_run_id WHERE r.uid IS NOT NULL")" = "$((N + 2))" ] || fail "sets at the centre"
[ "$(admin -d calbench -c "SELECT count(*) FROM coefficient_sets s WHERE (SELECT count(*) FROM coefficient_values v WHERE v.set_id = s.id) <> 24")" = 0 ] || fail "a partial set"
[ "$(admin -d calbench -c "SELECT count(*) FROM (SELECT device_id FROM coefficient_sets GROUP BY device_id HAVING max(version) <> count(*) OR min(version) <> 1) g")" = 0 ] || fail "versions not gapless"

# Bad targets.
set +e
"$CALBENCH" db store-bench --db "postgresql://station3@127.0.0.1:notaport/calbench" --coeffs c.json --journal new.db 2> err.txt; rc=$?
set -e
[ "$rc" = 2 ] && grep -q "not a valid PostgreSQL URI" err.txt && [ ! -e new.db ] || { cat err.txt; fail "malformed URI: exit $rc"; }
set +e; "$CALBENCH" db devices --db "postgresql://station3:Sup3rSecret9@127.0.0.1:1/calbench" > out.txt 2> err.txt; rc=$?; set -e
[ "$rc" = 1 ] && grep -q "cannot reach the database server" err.txt || { cat err.txt; fail "unreachable: exit $rc"; }
! grep -q "Sup3rSecret9" err.txt out.txt || fail "password echoed (unreachable)"
set +e; "$CALBENCH" db devices --db "postgresql://station3:Wr0ngPass7@127.0.0.1:$port/calbench" > out.txt 2> err.txt; rc=$?; set -e
[ "$rc" = 1 ] && grep -q "refused the credentials" err.txt || { cat err.txt; fail "wrong password: exit $rc"; }
! grep -q "Wr0ngPass7" err.txt out.txt || fail "password echoed (wrong password)"
# No password file line for this database (a typo in its name): said so, not "wrong password".
set +e; "$CALBENCH" db devices --db "postgresql://station3@127.0.0.1:$port/calbnch" > out.txt 2> err.txt; rc=$?; set -e
[ "$rc" = 1 ] && grep -q "no password found: a PGPASSFILE or ~/.pgpass line must match HOST:PORT:DATABASE:USER" err.txt || { cat err.txt; fail "no pgpass line: exit $rc"; }
# A role that may not grant runs db init --roles: one error line, no flood of server warnings.
set +e; "$CALBENCH" db init --db "$ST" --roles 2> err.txt; rc=$?; set -e
[ "$rc" = 1 ] && [ "$(wc -l < err.txt)" = 1 ] && ! grep -q WARNING err.txt || { head -5 err.txt; fail "db init --roles as a station: exit $rc, $(wc -l < err.txt) lines"; }
set +e; "$CALBENCH" db devices --db "postgresql://station3:bad%zzpw@127.0.0.1:$port/calbench" > out.txt 2> err.txt; rc=$?; set -e
[ "$rc" = 2 ] || { cat err.txt; fail "bad percent-encoding: exit $rc"; }
! grep -q "zzpw" err.txt out.txt || fail "password echoed (malformed)"
# An older schema: a database at version 3 (schema.sql alone), opened by a station.
admin -d postgres -c "CREATE DATABASE old"
admin -d old -1 -f "$SRC/db/postgres/schema.sql" > /dev/null
admin -d old -f "$SRC/db/postgres/roles.sql" > /dev/null
echo "127.0.0.1:$port:old:station3:${PW[station3]}" >> "$PGPASSFILE"
set +e; "$CALBENCH" db devices --db "postgresql://station3@127.0.0.1:$port/old" 2> err.txt; rc=$?; set -e
[ "$rc" = 1 ] && grep -q "schema version 3, this calbench needs 9" err.txt && grep -q "db init" err.txt || { cat err.txt; fail "older schema: exit $rc"; }
# Two units in one table cycle (a fixture): both reach the centre with their slots and one table run.
"$CALBENCH" station run --plan "$SRC/tests/data/short_plan.toml" --emulated --units 2 --seed 40 --db "$ST" --out fx \
  --json > fx.json 2> fx.txt || { cat fx.txt; fail "fixture station run"; }
run_id=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["run_id"])' fx.json)
# The next steps name a QC login, not the station's own (which the database refuses an approval).
[ "$(grep -c "^next (slot [12]): calbench db approve [0-9]* --db postgresql://QC_LOGIN@127.0.0.1:$port/calbench" fx.txt)" = 2 ] \
  || { cat fx.txt; fail "the fixture's next steps do not name a QC login"; }
! grep "^next" fx.txt | grep -q "station3@" || { cat fx.txt; fail "a next step suggests the station's login"; }
[ "$(admin -d calbench -c "SELECT string_agg(r.slot || ':' || d.serial, ' ' ORDER BY r.slot) FROM bench_runs r JOIN devices d ON d.id = r.device_id WHERE r.table_run = '$run_id'")" = "1:1040 2:1041" ] \
  || { admin -d calbench -c "SELECT slot, table_run FROM bench_runs"; fail "the fixture's runs at the centre"; }
echo "PASS"
