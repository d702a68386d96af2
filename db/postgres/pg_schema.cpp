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
// Schema 8, the station's part (issue 38 item 3; the SQLite twin is db/schema.cpp
// schema8_station_progress, which says what the tables are). Who may do what is enforced here:
// a station login writes only its own progress rows and prompts (login = session_user, stamped by
// the server), QC and readers read them; a prompt is answered (once) by a station or QC login, whose
// login the server stamps. calbench_grant_station_live() holds the grants and row rules, called here
// and by roles.sql, so that they hold whichever of the two runs first.
const char* pg_schema8_station_progress() {
  return R"SQL(
CREATE TABLE station_progress (
  run_id        text NOT NULL,
  slot          text NOT NULL,
  station       text NOT NULL,
  login         text NOT NULL DEFAULT session_user,
  serial        text NOT NULL DEFAULT '',
  step_index    integer NOT NULL DEFAULT 0,
  step_count    integer NOT NULL DEFAULT 0,
  step_name     text NOT NULL DEFAULT '',
  step_kind     text NOT NULL DEFAULT '',
  step_fraction double precision NOT NULL DEFAULT 0 CHECK (step_fraction >= 0 AND step_fraction <= 1),
  check_name    text NOT NULL DEFAULT '',
  check_value   double precision,
  check_limit   double precision,
  check_unit    text NOT NULL DEFAULT '',
  state         text NOT NULL CHECK (state IN ('running', 'waiting', 'passed', 'failed', 'aborted')),
  reason        text NOT NULL DEFAULT '',
  started_at    timestamptz NOT NULL DEFAULT now(),
  heartbeat_at  timestamptz NOT NULL DEFAULT now(),
  PRIMARY KEY (run_id, slot),
  CHECK (state NOT IN ('failed', 'aborted') OR reason <> '')
);
CREATE INDEX station_progress_heartbeat ON station_progress(heartbeat_at);
CREATE TABLE station_prompts (
  id             bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  run_id         text NOT NULL,
  station        text NOT NULL,
  slot           text NOT NULL DEFAULT '',
  text           text NOT NULL CHECK (text <> ''),
  timeout_s      double precision NOT NULL CHECK (timeout_s > 0),
  created_at     timestamptz NOT NULL DEFAULT now(),
  created_login  text NOT NULL DEFAULT session_user,
  state          text NOT NULL DEFAULT 'waiting' CHECK (state IN ('waiting', 'confirmed', 'rejected', 'timed out')),
  reason         text NOT NULL DEFAULT '',
  answered_by    text NOT NULL DEFAULT '',
  answered_login text NOT NULL DEFAULT '',
  answered_at    timestamptz
);
CREATE INDEX station_prompts_run ON station_prompts(run_id);
-- The console's reads over a large store (tests/perf/console_load_bench.cpp): the QC queue (sets of
-- one status, oldest first), the fleet dashboard's units per hour (runs ended since a time) and the
-- audit search by person or login.
CREATE INDEX coefficient_sets_status ON coefficient_sets(status, id);
CREATE INDEX bench_runs_ended ON bench_runs(ended_at);
CREATE INDEX audit_user ON audit_log(lower("user"));
CREATE INDEX audit_db_role ON audit_log(db_role);
-- The server stamps who wrote a row: a login cannot write another's progress or answer as another.
CREATE FUNCTION calbench_stamp_progress() RETURNS trigger LANGUAGE plpgsql AS $f$
BEGIN
  NEW.login := session_user;
  NEW.heartbeat_at := now();
  RETURN NEW;
END $f$;
CREATE TRIGGER station_progress_stamp BEFORE INSERT OR UPDATE ON station_progress
  FOR EACH ROW EXECUTE FUNCTION calbench_stamp_progress();
CREATE FUNCTION calbench_prompt_answer() RETURNS trigger LANGUAGE plpgsql AS $f$
BEGIN
  IF TG_OP = 'INSERT' THEN
    NEW.created_login := session_user;
    NEW.state := 'waiting';
    RETURN NEW;
  END IF;
  IF OLD.state <> 'waiting' OR NEW.text IS DISTINCT FROM OLD.text OR NEW.run_id IS DISTINCT FROM OLD.run_id
     OR NEW.created_at IS DISTINCT FROM OLD.created_at OR NEW.created_login IS DISTINCT FROM OLD.created_login THEN
    RAISE EXCEPTION 'an operator prompt is answered once' USING ERRCODE = 'integrity_constraint_violation';
  END IF;
  NEW.answered_login := session_user;
  RETURN NEW;
END $f$;
CREATE TRIGGER station_prompts_answer BEFORE INSERT OR UPDATE ON station_prompts
  FOR EACH ROW EXECUTE FUNCTION calbench_prompt_answer();
CREATE FUNCTION calbench_grant_station_live() RETURNS void LANGUAGE plpgsql AS $f$
BEGIN
  IF NOT EXISTS (SELECT 1 FROM pg_roles WHERE rolname = 'calbench_station') THEN
    RETURN;  -- roles.sql, run later, calls this again
  END IF;
  REVOKE ALL ON station_progress, station_prompts FROM calbench_provisioning;
  GRANT SELECT ON station_progress, station_prompts TO calbench_station, calbench_qc, calbench_reader;
  GRANT INSERT, UPDATE ON station_progress TO calbench_station;
  GRANT INSERT ON station_prompts TO calbench_station;
  GRANT UPDATE (state, reason, answered_by, answered_at) ON station_prompts TO calbench_station, calbench_qc;
  ALTER TABLE station_progress ENABLE ROW LEVEL SECURITY;
  ALTER TABLE station_prompts ENABLE ROW LEVEL SECURITY;
  DROP POLICY IF EXISTS progress_read ON station_progress;
  DROP POLICY IF EXISTS progress_station_insert ON station_progress;
  DROP POLICY IF EXISTS progress_station_update ON station_progress;
  DROP POLICY IF EXISTS prompts_read ON station_prompts;
  DROP POLICY IF EXISTS prompts_station_insert ON station_prompts;
  DROP POLICY IF EXISTS prompts_answer ON station_prompts;
  CREATE POLICY progress_read ON station_progress FOR SELECT
    TO calbench_station, calbench_qc, calbench_reader USING (true);
  CREATE POLICY progress_station_insert ON station_progress FOR INSERT
    TO calbench_station WITH CHECK (login = session_user);
  CREATE POLICY progress_station_update ON station_progress FOR UPDATE
    TO calbench_station USING (login = session_user) WITH CHECK (login = session_user);
  CREATE POLICY prompts_read ON station_prompts FOR SELECT
    TO calbench_station, calbench_qc, calbench_reader USING (true);
  CREATE POLICY prompts_station_insert ON station_prompts FOR INSERT
    TO calbench_station WITH CHECK (created_login = session_user);
  CREATE POLICY prompts_answer ON station_prompts FOR UPDATE
    TO calbench_station, calbench_qc USING (state = 'waiting') WITH CHECK (true);
END $f$;
SELECT calbench_grant_station_live();
INSERT INTO schema_version(version) VALUES (8);
)SQL";
}

// Schema 9 (issue 54): signatures that hold against an insider. Audit rows are written only by the
// server's functions and triggers; see docs/database.md "Threat model".
const char* pg_schema9_insider() {
  return R"SQL(
-- A security event that changed nothing (failed log-in, lock-out, a refusal): the one kind of row a
-- login may ask to be written, always as itself (db_role and "user" are the server's).
CREATE FUNCTION calbench_audit_security(action text, login text, detail text, station text) RETURNS void
  LANGUAGE plpgsql SECURITY DEFINER SET search_path = public, pg_temp AS $f$
BEGIN
  IF action NOT IN ('login-failed', 'lockout', 'refused') THEN
    RAISE EXCEPTION 'calbench_audit_security: % is not a security event', action USING ERRCODE = 'check_violation';
  END IF;
  INSERT INTO audit_log("user", station, entity, entity_id, action, detail)
  VALUES (coalesce((SELECT u.name FROM calbench_users u WHERE u.login = session_user), session_user::text),
          left(coalesce(station, ''), 200), 'security', 0, action,
          left(coalesce(login, '') || CASE WHEN coalesce(detail, '') = '' THEN '' ELSE ': ' || detail END, 4000));
END $f$;
REVOKE ALL ON FUNCTION calbench_audit_security(text, text, text, text) FROM PUBLIC;
DO $$
DECLARE r text;
BEGIN
  FOREACH r IN ARRAY ARRAY['calbench_station', 'calbench_qc', 'calbench_provisioning', 'calbench_reader'] LOOP
    IF EXISTS (SELECT 1 FROM pg_roles WHERE rolname = r) THEN
      EXECUTE format('GRANT EXECUTE ON FUNCTION calbench_audit_security(text, text, text, text) TO %I', r);
    END IF;
  END LOOP;
END $$;
INSERT INTO schema_version(version) VALUES (9);
)SQL";
}

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
      // ---- 8: the station's live state and its operator prompts (issue 38) ----
      pg_schema8_station_progress(),
      // ---- 9: signatures that hold against an insider (issue 54) ----
      pg_schema9_insider(),
  };
  return m;
}

}  // namespace calbench::db
