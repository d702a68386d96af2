#!/usr/bin/env bash
# Issue 35 item 3: a station with a central PostgreSQL store checks, before the table moves, that its
# login can store what a run stores: credentials, schema version, the role's privileges. A refusal is
# exit 2 with the reason, and the table never got a request (an external `calbench emulate table`
# counts them) nor was anything recorded. A server that cannot be reached at start is the offline case:
# the station says so at start, runs, and the journal keeps the run.
source "$SRC/tests/support/pg_test.sh"
cd "$T"
admin -d postgres -c "CREATE DATABASE calbench"
admin -d postgres -c "CREATE DATABASE old"
admin -d old -1 -f "$SRC/db/postgres/schema.sql" >/dev/null   # schema version 3: older than this calbench
ADMIN="postgresql:///calbench?host=$T/pg&port=$port&user=calbench_admin"
"$CALBENCH" db init --db "$ADMIN" --roles --operator admin > init.txt 2>&1 || { cat init.txt; fail "db init"; }
export PGPASSFILE="$T/pgpass"
: > "$PGPASSFILE"; chmod 600 "$PGPASSFILE"
for u in station3:calbench_station reader1:calbench_reader; do
  name=${u%%:*}; group=${u#*:}; pw=$(python3 -c 'import secrets; print(secrets.token_hex(12))')
  admin -d calbench -c "CREATE ROLE $name LOGIN PASSWORD '$pw' IN ROLE $group"
  echo "127.0.0.1:$port:calbench:$name:$pw" >> "$PGPASSFILE"
  echo "127.0.0.1:$port:old:$name:$pw" >> "$PGPASSFILE"
done
admin -d calbench -c "CREATE ROLE station9 LOGIN PASSWORD 'right-one' IN ROLE calbench_station"
echo "127.0.0.1:$port:calbench:station9:wrong-one" >> "$PGPASSFILE"
admin -d old -c "GRANT SELECT ON ALL TABLES IN SCHEMA public TO station3"
uri() { echo "postgresql://$1@127.0.0.1:$port/${2:-calbench}"; }
export CALBENCH_STATION=line-3 CALBENCH_JOURNAL="$T/journal.db"
PLAN="$SRC/tests/data/short_plan.toml"

# An external table emulator: it counts the requests it answered.
"$CALBENCH" emulate table --listen 127.0.0.1:0 --port-file tport > table.txt 2>&1 &
tpid=$!
for _ in $(seq 1 100); do [ -s tport ] && break; sleep 0.05; done
[ -s tport ] || fail "table emulator did not start"
TABLE="modbus-tcp://127.0.0.1:$(cat tport)"

refused() {  # refused WHAT DB PATTERN: exit 2 naming PATTERN, before the table is connected, nothing recorded, no journal
  local what=$1 db=$2 pat=$3 rc=0
  "$CALBENCH" station run --plan "$PLAN" --emulated --table "$TABLE" --db "$db" --out "$what" > "$what.json" 2> "$what.txt" || rc=$?
  [ "$rc" = 2 ] || { cat "$what.txt"; fail "$what: exit $rc, expected 2"; }
  grep -q -- "$pat" "$what.txt" || { cat "$what.txt"; fail "$what: message lacks '$pat'"; }
  grep -q "station not started (nothing ran)" "$what.txt" || { cat "$what.txt"; fail "$what: not refused before the start"; }
  ! grep -q "^table:" "$what.txt" || fail "$what: the table was connected"
  [ ! -e "$what/recording" ] && [ ! -e "$what/COEFFS.json" ] || fail "$what: something was recorded"
  [ ! -e "$T/journal.db" ] || fail "$what: the journal was written"
  echo "ok: $what refused: $(grep -o 'calbench: .*' "$what.txt" | head -c 200)"
}
refused wrong-password "$(uri station9)" "the server refused the credentials"
refused no-privileges "$(uri reader1)" "role 'reader1' may not store a station run (missing INSERT on devices"
refused old-schema "$(uri station3 old)" "schema version 3, this calbench needs [4-9]"
refused no-database "$(uri station3 nosuch)" "nosuch"
kill -INT $tpid; wait $tpid || true
grep -q "stopped after 0 requests" table.txt || { cat table.txt; fail "the table got requests from a refused station"; }
echo "ok: the table got no request"

# The station's own login: checked at start, then the run is stored and forwarded.
"$CALBENCH" station run --plan "$PLAN" --emulated --seed 3 --db "$(uri station3)" --out good --json > good.json 2> good.txt \
  || { cat good.txt; fail "station run with its own login"; }
head -3 good.txt | grep -q "central store postgresql://station3@127.0.0.1:$port/calbench: role station3 may store the run" \
  || { cat good.txt; fail "no access line at start"; }
python3 -c 'import json,sys; c=json.load(open("good.json"))["db"]["central"]; assert c["reached"] and c["set"] > 0, c'

# The server unreachable at start (a port nobody listens on): the offline case, said at start; the run
# completes on the journal (exit 0) and waits there.
dead=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
"$CALBENCH" station run --plan "$PLAN" --emulated --seed 4 --db "postgresql://station3@127.0.0.1:$dead/calbench" --out offline \
  > offline.json 2> offline.txt || { cat offline.txt; fail "offline station run: exit $?"; }
first=$(grep -n "central store not reached at start" offline.txt | cut -d: -f1)
tab=$(grep -n "^table:" offline.txt | cut -d: -f1)
[ -n "$first" ] && [ -n "$tab" ] && [ "$first" -lt "$tab" ] || { cat offline.txt; fail "offline not said at start"; }
grep -q "the run goes to the journal $T/journal.db" offline.txt || { cat offline.txt; fail "journal not named"; }
[ -e offline/COEFFS.json ] || fail "offline run did not complete"
[ "$(sqlite3 "$T/journal.db" "SELECT count(*) FROM bench_runs WHERE uid NOT IN (SELECT uid FROM forwarded)")" = 1 ] \
  || fail "the offline run is not waiting in the journal"
echo "ok: offline at start: the run completed on the journal"
