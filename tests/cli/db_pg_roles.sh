#!/usr/bin/env bash
# Issue 18 item 2 at the SQL level: the central store's roles are enforced by PostgreSQL itself
# (db/postgres/schema.sql + roles.sql on a real server from the Debian package, started in a
# temporary folder on a free loopback port and stopped afterwards). A station's credentials cannot
# approve, revoke, edit or delete a set even through plain psql; QC cannot provision or edit;
# provisioning sees approved sets only and may only mark them provisioned; a reader writes nothing;
# the audit log is append-only for everyone, the owner included, and records the database role.
source "$SRC/tests/support/pg_test.sh"
admin -d postgres -c "CREATE DATABASE calbench"
admin -d calbench -1 -f "$SRC/db/postgres/schema.sql" >/dev/null
admin -d calbench -f "$SRC/db/postgres/roles.sql" >/dev/null
admin -d calbench -f "$SRC/db/postgres/roles.sql" >/dev/null   # idempotent
export PGPASSFILE="$T/pgpass"
: > "$PGPASSFILE"; chmod 600 "$PGPASSFILE"
for u in st:calbench_station qa:calbench_qc pv:calbench_provisioning rd:calbench_reader; do
  name=${u%%:*}; group=${u#*:}; pw=$(python3 -c 'import secrets; print(secrets.token_hex(12))')
  admin -d calbench -c "CREATE ROLE $name LOGIN PASSWORD '$pw' IN ROLE $group"
  echo "127.0.0.1:$port:calbench:$name:$pw" >> "$PGPASSFILE"
done
n=0
as() {  # as ROLE SQL: must succeed; prints the result
  local who=$1; shift
  psql -h 127.0.0.1 -p "$port" -U "$who" -d calbench -w -v ON_ERROR_STOP=1 -qtAX -c "$*" 2> "$T/err" \
    || { cat "$T/err" >&2; fail "$who could not: $*"; }
  n=$((n + 1))
}
refused() {  # refused ROLE PATTERN SQL: must fail with an error matching PATTERN, changing nothing
  local who=$1 pat=$2; shift 2
  if psql -h 127.0.0.1 -p "$port" -U "$who" -d calbench -w -v ON_ERROR_STOP=1 -qtAX -c "$*" > "$T/out" 2> "$T/err"; then
    fail "$who was allowed: $*"
  fi
  grep -Eq "$pat" "$T/err" || { cat "$T/err" >&2; fail "$who refused for another reason than /$pat/: $*"; }
  n=$((n + 1))
}
noop() {  # noop ROLE SQL: succeeds but touches no row (a row rule hides the target)
  local who=$1; shift
  out=$(psql -h 127.0.0.1 -p "$port" -U "$who" -d calbench -w -v ON_ERROR_STOP=1 -tAX -c "$*" 2>&1) || { echo "$out" >&2; fail "$who: $*"; }
  echo "$out" | grep -Eq "^(UPDATE|DELETE) 0$" || fail "$who changed rows: $* -> $out"
  n=$((n + 1))
}
denied='permission denied'
rls='violates row-level security policy'

# The station registers a unit, stores a run, a draft set with its values and its audit entry.
as st "INSERT INTO devices(model, serial) VALUES ('ADIS16488A', 'U1')"
as st "INSERT INTO stations(name) VALUES ('line-3')"
as st "INSERT INTO bench_runs(device_id, station_id, outcome) VALUES (1, 1, 'pass')"
as st "INSERT INTO coefficient_sets(device_id, version, source, bench_run_id, payload_json, created_by)
       VALUES (1, 1, 'bench', 1, '{}', 'Sam@line-3')"
as st "INSERT INTO coefficient_values(set_id, name, value, sigma) VALUES (1, 'gyro.bias.x', 1e-3, 1e-6)"
as st "INSERT INTO audit_log(\"user\", station, db_role, entity, entity_id, device_id, action)
       VALUES ('Sam', 'line-3', 'qa', 'coefficient_set', 1, 1, 'create')"
[ "$(admin -d calbench -c "SELECT db_role FROM audit_log WHERE id = 1")" = st ] || fail "the audit row took the client's db_role"
[ "$(admin -d calbench -c "SELECT created_by_role FROM coefficient_sets WHERE id = 1")" = st ] || fail "created_by_role"
# ... and nothing else.
refused st "$denied" "UPDATE coefficient_sets SET status = 'approved' WHERE id = 1"
refused st "$denied" "UPDATE coefficient_sets SET status = 'revoked' WHERE id = 1"
refused st "$denied" "UPDATE coefficient_sets SET payload_json = '{\"x\":1}' WHERE id = 1"
refused st "$denied" "DELETE FROM coefficient_sets WHERE id = 1"
refused st "$denied" "TRUNCATE coefficient_sets CASCADE"
refused st "stored as draft|$rls" "INSERT INTO coefficient_sets(device_id, version, source, payload_json, created_by, status)
                   VALUES (1, 2, 'bench', '{}', 'Sam@line-3', 'approved')"
refused st "$denied" "INSERT INTO settings(key, value, changed_by) VALUES ('four_eyes', 'off', 'Sam')"
refused st "$denied" "UPDATE audit_log SET detail = 'x'"
refused st "$denied" "DELETE FROM audit_log"
refused st "$denied" "INSERT INTO provisioning_events(set_id, device_id, kind, target, ok, actor) VALUES (1, 1, 'export', 'f', true, 'Sam')"
refused st "$denied" "UPDATE devices SET serial = 'U9' WHERE id = 1"
refused st "$denied" "CREATE TABLE mine(x int)"
as st "UPDATE devices SET firmware = '1.10' WHERE id = 1"   # the one column a station may update
# Versions are unique per device.
refused st "duplicate key value violates unique constraint" \
  "INSERT INTO coefficient_sets(device_id, version, source, payload_json, created_by) VALUES (1, 1, 'bench', '{}', 'Sam')"

# Provisioning sees no draft (nor its values) and cannot touch it.
[ "$(psql -h 127.0.0.1 -p "$port" -U pv -d calbench -w -qtAX -c "SELECT count(*) FROM coefficient_sets")" = 0 ] || fail "provisioning sees a draft"
[ "$(psql -h 127.0.0.1 -p "$port" -U pv -d calbench -w -qtAX -c "SELECT count(*) FROM coefficient_values")" = 0 ] || fail "provisioning sees a draft's values"
noop pv "UPDATE coefficient_sets SET status = 'provisioned' WHERE id = 1"
refused pv "$denied" "SELECT * FROM bench_runs"

# QC approves; cannot provision, edit or delete.
refused qa "$denied" "UPDATE coefficient_sets SET payload_json = '{}' WHERE id = 1"
refused qa "$denied" "DELETE FROM coefficient_sets WHERE id = 1"
refused qa "$denied" "INSERT INTO coefficient_sets(device_id, version, source, payload_json, created_by) VALUES (1, 2, 'bench', '{}', 'Q')"
as qa "UPDATE coefficient_sets SET status = 'approved' WHERE id = 1"
refused qa "$rls" "UPDATE coefficient_sets SET status = 'provisioned' WHERE id = 1"   # approved -> provisioned is not QC's
as qa "INSERT INTO settings(key, value, changed_by) VALUES ('four_eyes', 'on', 'Quinn')"
as qa "INSERT INTO audit_log(\"user\", station, entity, entity_id, device_id, action) VALUES ('Quinn', 'qc', 'coefficient_set', 1, 1, 'status')"
# The station cannot add values to a set that is no longer a draft.
refused st "$rls" "INSERT INTO coefficient_values(set_id, name, value) VALUES (1, 'gyro.bias.y', 0)"

# Provisioning now sees it with its values, marks it provisioned, records the event; cannot revoke.
[ "$(psql -h 127.0.0.1 -p "$port" -U pv -d calbench -w -qtAX -c "SELECT count(*) FROM coefficient_values")" = 1 ] || fail "provisioning cannot read an approved set's values"
refused pv "$rls" "UPDATE coefficient_sets SET status = 'revoked' WHERE id = 1"
as pv "UPDATE coefficient_sets SET status = 'provisioned' WHERE id = 1"
as pv "INSERT INTO provisioning_events(set_id, device_id, kind, target, ok, actor) VALUES (1, 1, 'device', 'emu://U1', true, 'Pat@line-9')"
[ "$(admin -d calbench -c "SELECT db_role FROM provisioning_events")" = pv ] || fail "provisioning db_role"
refused pv "$denied" "UPDATE provisioning_events SET ok = false"

# A reader reads and writes nothing.
[ "$(psql -h 127.0.0.1 -p "$port" -U rd -d calbench -w -qtAX -c "SELECT status FROM coefficient_sets WHERE id = 1")" = provisioned ] || fail "reader cannot read"
refused rd "$denied" "INSERT INTO devices(model, serial) VALUES ('ADIS16488A', 'U2')"
refused rd "$denied" "UPDATE coefficient_sets SET status = 'revoked' WHERE id = 1"
refused rd "$denied" "INSERT INTO audit_log(\"user\", station, entity, entity_id, action) VALUES ('r', 'r', 'x', 0, 'x')"

# The rules hold for the owner too: sets immutable, statuses forwards only, the record kept.
owner_refused() {  # owner_refused PATTERN SQL
  local pat=$1; shift
  if admin -d calbench -c "$*" > "$T/out" 2> "$T/err"; then fail "the owner was allowed: $*"; fi
  grep -Eq "$pat" "$T/err" || { cat "$T/err" >&2; fail "owner refused for another reason than /$pat/: $*"; }
  n=$((n + 1))
}
owner_refused "coefficient sets are immutable" "UPDATE coefficient_sets SET payload_json = '{\"y\":2}' WHERE id = 1"
owner_refused "status change not allowed: provisioned -> draft" "UPDATE coefficient_sets SET status = 'draft' WHERE id = 1"
owner_refused "never deleted" "DELETE FROM coefficient_sets WHERE id = 1"
owner_refused "coefficient values are immutable" "UPDATE coefficient_values SET value = 0"
owner_refused "append-only" "UPDATE audit_log SET detail = 'rewritten'"
owner_refused "append-only" "TRUNCATE audit_log"
owner_refused "stored as draft" "INSERT INTO coefficient_sets(device_id, version, source, payload_json, created_by, status)
                                 VALUES (1, 3, 'bench', '{}', 'admin', 'approved')"
# No password in anything this test printed or the server logged.
! grep -q "$(cut -d: -f5 "$PGPASSFILE" | head -1)" "$T/pg/server.log" || fail "a password in the server log"
echo "db_pg_roles: $n checks passed"
