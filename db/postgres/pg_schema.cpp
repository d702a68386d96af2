// Migrations of the PostgreSQL store after its base schema, as data. Never edit a released one:
// append. Each records its version in schema_version.
#include "db/postgres/pg_schema.hpp"

#include "db/postgres/pg_schema_sql.hpp"

namespace calbench::db {

const char* pg_base_schema() { return generated::kPgSchemaSql; }
const char* pg_roles_sql() { return generated::kPgRolesSql; }

// ---- 7 (console part, issue 38): nothing to create. The web console's users on PostgreSQL are the
//      database's own logins (each request runs as that role); the SQLite store's local accounts
//      (db/schema.cpp, schema7_console_accounts) have no counterpart here. ----
static const char* const pg_schema7_console_accounts = R"SQL(
INSERT INTO schema_version(version) VALUES (7);
)SQL";

const std::vector<const char*>& pg_migrations() {
  static const std::vector<const char*> m = {
      // ---- 4: a stable id per run and set (forwarding from a station's journal is idempotent) ----
      R"SQL(
ALTER TABLE bench_runs ADD COLUMN uid text UNIQUE;
ALTER TABLE inmotion_runs ADD COLUMN uid text UNIQUE;
ALTER TABLE coefficient_sets ADD COLUMN uid text UNIQUE;
-- (coefficient_sets.uid is immutable with the other columns: calbench_set_update compares them all.)
INSERT INTO schema_version(version) VALUES (4);
)SQL",
      // ---- 5: several units per table cycle (issue 21): the unit's slot on the fixture, and the id
      //         of the table run that ties the units of one cycle ----
      R"SQL(
ALTER TABLE bench_runs ADD COLUMN slot text NOT NULL DEFAULT '';
ALTER TABLE bench_runs ADD COLUMN table_run text NOT NULL DEFAULT '';
CREATE INDEX bench_runs_table_run ON bench_runs(table_run);
INSERT INTO schema_version(version) VALUES (5);
)SQL",
      // ---- 6: signatures a QC team can rely on, recordings a central store can use (issue 35) ----
      R"SQL(
-- Who a login is: the person who signs with it (calbench db user add). History keeps the name
-- written at signing time; this table says who may sign now.
CREATE TABLE calbench_users (
  login    text PRIMARY KEY,
  name     text NOT NULL CHECK (name <> ''),
  role     text NOT NULL CHECK (role IN ('qc', 'station', 'provisioning')),
  added_at timestamptz NOT NULL DEFAULT now(),
  added_by text NOT NULL DEFAULT session_user
);
DO $$
DECLARE r text;
BEGIN
  FOREACH r IN ARRAY ARRAY['calbench_station', 'calbench_qc', 'calbench_provisioning', 'calbench_reader'] LOOP
    IF EXISTS (SELECT 1 FROM pg_roles WHERE rolname = r) THEN
      EXECUTE format('GRANT SELECT ON calbench_users TO %I', r);
    END IF;
  END LOOP;
END $$;
ALTER TABLE bench_runs ADD COLUMN recording_uri text NOT NULL DEFAULT '';
ALTER TABLE bench_runs ADD COLUMN recording_digest text NOT NULL DEFAULT '';
-- The transaction that wrote an audit row (stamped by the server, as db_role).
ALTER TABLE audit_log ADD COLUMN txid bigint NOT NULL DEFAULT txid_current();
CREATE FUNCTION calbench_stamp_txid() RETURNS trigger LANGUAGE plpgsql AS $f$
BEGIN
  NEW.txid := txid_current();
  RETURN NEW;
END $f$;
CREATE TRIGGER audit_log_txid BEFORE INSERT ON audit_log FOR EACH ROW EXECUTE FUNCTION calbench_stamp_txid();
-- No status change without its audit row, for every role, the owner included: at commit, the
-- transaction that moved a set's status must have written the audit row saying so.
CREATE FUNCTION calbench_status_audited() RETURNS trigger LANGUAGE plpgsql SECURITY DEFINER
  SET search_path = public, pg_temp AS $f$
BEGIN
  IF NOT EXISTS (SELECT 1 FROM audit_log a WHERE a.entity = 'coefficient_set' AND a.entity_id = NEW.id
                 AND a.action = 'status' AND a.txid = txid_current()
                 AND a.detail LIKE OLD.status || ' -> ' || NEW.status || '%') THEN
    RAISE EXCEPTION 'status change of coefficient set % (% -> %) without its audit row: change a status with '
                    'calbench (db approve, db revoke, provision), which writes both in one transaction',
                    NEW.id, OLD.status, NEW.status USING ERRCODE = 'integrity_constraint_violation';
  END IF;
  RETURN NULL;
END $f$;
CREATE CONSTRAINT TRIGGER coefficient_sets_status_audited AFTER UPDATE OF status ON coefficient_sets
  DEFERRABLE INITIALLY DEFERRED FOR EACH ROW WHEN (OLD.status IS DISTINCT FROM NEW.status)
  EXECUTE FUNCTION calbench_status_audited();
-- Which sets a device has, and their status, for every role (provisioning sees no draft's row, but
-- may be told that one waits for approval).
CREATE FUNCTION calbench_set_statuses(device bigint) RETURNS TABLE (id bigint, version integer, status text)
  LANGUAGE sql STABLE SECURITY DEFINER SET search_path = public, pg_temp AS $f$
  SELECT s.id, s.version, s.status FROM coefficient_sets s WHERE s.device_id = device ORDER BY s.version
$f$;
INSERT INTO schema_version(version) VALUES (6);
)SQL",
      pg_schema7_console_accounts,
  };
  return m;
}

}  // namespace calbench::db
