// Schema migrations, as data. Migration i (1-based) takes the database from user_version i−1 to i.
// Never edit a released migration: append a new one.
#include "db/schema.hpp"

#include <string>

namespace calbench::db {

// ---- 7 (console part, issue 38): the web console's local accounts on a SQLite store (`calbench db
//      user add LOGIN --name … --role …`): a person, a role and an argon2id password hash
//      (libsodium crypto_pwhash_str). PostgreSQL has none: its logins are the database's roles. ----
static const char* const schema7_console_accounts = R"SQL(
CREATE TABLE console_accounts (
  login         TEXT PRIMARY KEY CHECK (login <> ''),
  name          TEXT NOT NULL CHECK (name <> ''),
  role          TEXT NOT NULL CHECK (role IN ('qc', 'station', 'provisioning')),
  password_hash TEXT NOT NULL CHECK (password_hash LIKE '$argon2id$%'),
  added_at      TEXT NOT NULL,
  added_by      TEXT NOT NULL
);
)SQL";
// Schema 8, the station's part (issue 38 item 3): the live state of each slot of each running
// station run, and the operator prompts a plan's prompt steps raise (docs/database.md "Station
// progress and operator prompts"). Rows are replaced as a run goes (upserts keyed by run and slot):
// a live view, not history — the history is bench_runs and the audit log.
const char* schema8_station_progress() {
  return R"SQL(
CREATE TABLE station_progress (
  run_id       TEXT NOT NULL,
  slot         TEXT NOT NULL,
  station      TEXT NOT NULL,
  login        TEXT NOT NULL DEFAULT '',
  serial       TEXT NOT NULL DEFAULT '',
  step_index   INTEGER NOT NULL DEFAULT 0,
  step_count   INTEGER NOT NULL DEFAULT 0,
  step_name    TEXT NOT NULL DEFAULT '',
  step_kind    TEXT NOT NULL DEFAULT '',
  step_fraction REAL NOT NULL DEFAULT 0 CHECK (step_fraction >= 0 AND step_fraction <= 1),
  check_name   TEXT NOT NULL DEFAULT '',
  check_value  REAL,
  check_limit  REAL,
  check_unit   TEXT NOT NULL DEFAULT '',
  state        TEXT NOT NULL CHECK (state IN ('running', 'waiting', 'passed', 'failed', 'aborted')),
  reason       TEXT NOT NULL DEFAULT '',
  started_at   TEXT NOT NULL,
  heartbeat_at TEXT NOT NULL,
  PRIMARY KEY (run_id, slot),
  CHECK (state NOT IN ('failed', 'aborted') OR reason <> '')
);
CREATE INDEX station_progress_heartbeat ON station_progress(heartbeat_at);
CREATE TABLE station_prompts (
  id             INTEGER PRIMARY KEY,
  run_id         TEXT NOT NULL,
  station        TEXT NOT NULL,
  slot           TEXT NOT NULL DEFAULT '',
  text           TEXT NOT NULL CHECK (text <> ''),
  timeout_s      REAL NOT NULL CHECK (timeout_s > 0),
  created_at     TEXT NOT NULL,
  created_login  TEXT NOT NULL DEFAULT '',
  state          TEXT NOT NULL DEFAULT 'waiting'
                 CHECK (state IN ('waiting', 'confirmed', 'rejected', 'timed out')),
  reason         TEXT NOT NULL DEFAULT '',
  answered_by    TEXT NOT NULL DEFAULT '',
  answered_login TEXT NOT NULL DEFAULT '',
  answered_at    TEXT
);
CREATE INDEX station_prompts_run ON station_prompts(run_id);
-- The console's reads over a large store (tests/perf/console_load_bench.cpp): the QC queue (sets of
-- one status, oldest first), the fleet dashboard's units per hour (runs ended since a time) and the
-- audit search by person or login.
CREATE INDEX coefficient_sets_status ON coefficient_sets(status, id);
CREATE INDEX bench_runs_ended ON bench_runs(ended_at);
CREATE INDEX audit_user ON audit_log(lower("user"));
CREATE INDEX audit_db_role ON audit_log(db_role);
-- An answer is given once: a prompt that is no longer waiting never changes again.
CREATE TRIGGER station_prompts_answer_once BEFORE UPDATE ON station_prompts
WHEN OLD.state <> 'waiting' OR NEW.text IS NOT OLD.text OR NEW.run_id IS NOT OLD.run_id
  OR NEW.created_at IS NOT OLD.created_at
BEGIN SELECT RAISE(ABORT, 'an operator prompt is answered once'); END;
CREATE TRIGGER station_prompts_no_delete BEFORE DELETE ON station_prompts
BEGIN SELECT RAISE(ABORT, 'operator prompts are never deleted'); END;
)SQL";
}

// Schema 9 (issue 54, docs/database.md "Threat model"): the creator person in its own column
// (never parsed out of created_by), console accounts that an admin manages, and the audit log's
// hash chain (db/audit_chain.hpp). The chain of the rows already there is written by
// Store::migrate between this and schema9_after_seal(), with the append-only trigger lifted.
const char* schema9_insider() {
  return R"SQL(
ALTER TABLE coefficient_sets ADD COLUMN creator TEXT NOT NULL DEFAULT '';
-- Older sets: the name before the first '@' (an operator name never holds one).
UPDATE coefficient_sets SET creator = CASE WHEN instr(created_by, '@') > 0
  THEN substr(created_by, 1, instr(created_by, '@') - 1) ELSE created_by END;
CREATE TRIGGER coefficient_sets_creator_immutable BEFORE UPDATE OF creator ON coefficient_sets
WHEN NEW.creator IS NOT OLD.creator
BEGIN SELECT RAISE(ABORT, 'coefficient sets are immutable'); END;
CREATE TABLE console_accounts_9 (
  login         TEXT PRIMARY KEY CHECK (login <> ''),
  name          TEXT NOT NULL CHECK (name <> ''),
  role          TEXT NOT NULL CHECK (role IN ('qc', 'station', 'provisioning', 'admin')),
  password_hash TEXT NOT NULL CHECK (password_hash LIKE '$argon2id$%'),
  added_at      TEXT NOT NULL,
  added_by      TEXT NOT NULL
);
INSERT INTO console_accounts_9 SELECT login, name, role, password_hash, added_at, added_by FROM console_accounts;
DROP TABLE console_accounts;
ALTER TABLE console_accounts_9 RENAME TO console_accounts;
DROP TRIGGER audit_log_no_update;
ALTER TABLE audit_log ADD COLUMN chain TEXT;
)SQL";
}
const char* schema9_approval_signed_trigger() {
  return R"SQL(
-- An approval is made with its signed audit row, written just before in the same transaction
-- (db approve): `UPDATE coefficient_sets SET status = 'approved'` alone is refused.
CREATE TRIGGER coefficient_sets_approval_signed BEFORE UPDATE OF status ON coefficient_sets
WHEN NEW.status = 'approved' AND OLD.status IS NOT 'approved' AND NOT EXISTS (
  SELECT 1 FROM audit_log a WHERE a.id = (SELECT max(id) FROM audit_log) AND a.entity = 'coefficient_set'
    AND a.entity_id = NEW.id AND a.action = 'status' AND a.detail LIKE 'draft -> approved%' AND a.chain IS NOT NULL)
BEGIN SELECT RAISE(ABORT, 'an approval is made with its signed audit row (calbench db approve)'); END;
)SQL";
}
const char* schema9_after_seal() {
  static const std::string sql = std::string(R"SQL(
CREATE TRIGGER audit_log_no_update BEFORE UPDATE ON audit_log
BEGIN SELECT RAISE(ABORT, 'the audit log is append-only'); END;
)SQL") + schema9_approval_signed_trigger();
  return sql.c_str();
}

const std::vector<const char*>& migrations() {
  static const std::vector<const char*> m = {
      // ---- 1: initial schema ----
      R"SQL(
CREATE TABLE devices (
  id         INTEGER PRIMARY KEY,
  model      TEXT NOT NULL,
  serial     TEXT NOT NULL UNIQUE,
  firmware   TEXT NOT NULL DEFAULT '',
  created_at TEXT NOT NULL
);
CREATE TABLE stations (
  id          INTEGER PRIMARY KEY,
  name        TEXT NOT NULL UNIQUE,
  description TEXT NOT NULL DEFAULT '',
  created_at  TEXT NOT NULL
);
CREATE TABLE bench_runs (
  id               INTEGER PRIMARY KEY,
  device_id        INTEGER NOT NULL REFERENCES devices(id),
  station_id       INTEGER REFERENCES stations(id),
  plan             TEXT NOT NULL DEFAULT '',
  recording_path   TEXT NOT NULL DEFAULT '',
  recording_sha256 TEXT NOT NULL DEFAULT '',
  started_at       TEXT NOT NULL DEFAULT '',
  ended_at         TEXT NOT NULL DEFAULT '',
  outcome          TEXT NOT NULL CHECK (outcome IN ('pass', 'fail', 'aborted')),
  created_at       TEXT NOT NULL
);
CREATE INDEX bench_runs_device ON bench_runs(device_id);
CREATE TABLE inmotion_runs (
  id                 INTEGER PRIMARY KEY,
  device_id          INTEGER NOT NULL REFERENCES devices(id),
  recording_path     TEXT NOT NULL DEFAULT '',
  recording_sha256   TEXT NOT NULL DEFAULT '',
  reference_system   TEXT NOT NULL DEFAULT '',
  mounting_roll_deg  REAL, mounting_pitch_deg REAL, mounting_yaw_deg REAL,
  mounting_roll_sigma_deg REAL, mounting_pitch_sigma_deg REAL, mounting_yaw_sigma_deg REAL,
  consistency_json   TEXT NOT NULL DEFAULT '{}',
  qc_json            TEXT NOT NULL DEFAULT '{}',
  result_json        TEXT NOT NULL,
  created_at         TEXT NOT NULL
);
CREATE INDEX inmotion_runs_device ON inmotion_runs(device_id);
CREATE TABLE coefficient_sets (
  id              INTEGER PRIMARY KEY,
  device_id       INTEGER NOT NULL REFERENCES devices(id),
  version         INTEGER NOT NULL CHECK (version >= 1),
  source          TEXT NOT NULL CHECK (source IN ('bench', 'in-motion', 'combined')),
  parent_id       INTEGER REFERENCES coefficient_sets(id),
  bench_run_id    INTEGER REFERENCES bench_runs(id),
  inmotion_run_id INTEGER REFERENCES inmotion_runs(id),
  payload_json    TEXT NOT NULL,
  status          TEXT NOT NULL DEFAULT 'draft'
                  CHECK (status IN ('draft', 'approved', 'provisioned', 'revoked')),
  created_at      TEXT NOT NULL,
  created_by      TEXT NOT NULL,
  UNIQUE (device_id, version)
);
CREATE TABLE coefficient_values (
  set_id INTEGER NOT NULL REFERENCES coefficient_sets(id),
  name   TEXT NOT NULL,
  value  REAL NOT NULL,
  sigma  REAL,                 -- NULL: unknown (not estimated)
  PRIMARY KEY (set_id, name)
) WITHOUT ROWID;
CREATE TABLE qc_results (
  id              INTEGER PRIMARY KEY,
  bench_run_id    INTEGER REFERENCES bench_runs(id),
  inmotion_run_id INTEGER REFERENCES inmotion_runs(id),
  metric          TEXT NOT NULL,
  value           REAL NOT NULL,
  threshold       REAL,
  pass            INTEGER NOT NULL CHECK (pass IN (0, 1)),
  unit            TEXT NOT NULL DEFAULT '',
  CHECK ((bench_run_id IS NULL) <> (inmotion_run_id IS NULL))
);
CREATE INDEX qc_results_bench ON qc_results(bench_run_id);
CREATE INDEX qc_results_inmotion ON qc_results(inmotion_run_id);
CREATE TABLE provisioning_events (
  id            INTEGER PRIMARY KEY,
  set_id        INTEGER NOT NULL REFERENCES coefficient_sets(id),
  device_id     INTEGER NOT NULL REFERENCES devices(id),
  kind          TEXT NOT NULL CHECK (kind IN ('device', 'export')),
  target        TEXT NOT NULL,
  ok            INTEGER NOT NULL CHECK (ok IN (0, 1)),
  readback_json TEXT NOT NULL DEFAULT '{}',
  message       TEXT NOT NULL DEFAULT '',
  actor         TEXT NOT NULL,
  at            TEXT NOT NULL
);
CREATE INDEX provisioning_device ON provisioning_events(device_id);
CREATE TABLE audit_log (
  id        INTEGER PRIMARY KEY,
  at        TEXT NOT NULL,
  user      TEXT NOT NULL,
  station   TEXT NOT NULL,
  entity    TEXT NOT NULL,
  entity_id INTEGER NOT NULL,
  device_id INTEGER REFERENCES devices(id),
  action    TEXT NOT NULL,
  detail    TEXT NOT NULL DEFAULT ''
);
CREATE INDEX audit_device ON audit_log(device_id);

-- Coefficient sets are immutable: only the status may change, and only forwards.
CREATE TRIGGER coefficient_sets_immutable BEFORE UPDATE ON coefficient_sets
WHEN NEW.payload_json IS NOT OLD.payload_json OR NEW.device_id IS NOT OLD.device_id
  OR NEW.version IS NOT OLD.version OR NEW.source IS NOT OLD.source
  OR NEW.parent_id IS NOT OLD.parent_id OR NEW.bench_run_id IS NOT OLD.bench_run_id
  OR NEW.inmotion_run_id IS NOT OLD.inmotion_run_id OR NEW.created_at IS NOT OLD.created_at
  OR NEW.created_by IS NOT OLD.created_by
BEGIN SELECT RAISE(ABORT, 'coefficient sets are immutable'); END;
CREATE TRIGGER coefficient_sets_status BEFORE UPDATE OF status ON coefficient_sets
WHEN NOT ((OLD.status = 'draft' AND NEW.status IN ('approved', 'revoked'))
       OR (OLD.status = 'approved' AND NEW.status IN ('provisioned', 'revoked'))
       OR (OLD.status = 'provisioned' AND NEW.status IN ('provisioned', 'revoked')))
BEGIN SELECT RAISE(ABORT, 'status change not allowed'); END;
CREATE TRIGGER coefficient_sets_no_delete BEFORE DELETE ON coefficient_sets
BEGIN SELECT RAISE(ABORT, 'coefficient sets are never deleted (revoke them)'); END;
CREATE TRIGGER coefficient_values_immutable BEFORE UPDATE ON coefficient_values
BEGIN SELECT RAISE(ABORT, 'coefficient values are immutable'); END;
CREATE TRIGGER coefficient_values_no_delete BEFORE DELETE ON coefficient_values
BEGIN SELECT RAISE(ABORT, 'coefficient values are immutable'); END;
CREATE TRIGGER audit_log_no_update BEFORE UPDATE ON audit_log
BEGIN SELECT RAISE(ABORT, 'the audit log is append-only'); END;
CREATE TRIGGER audit_log_no_delete BEFORE DELETE ON audit_log
BEGIN SELECT RAISE(ABORT, 'the audit log is append-only'); END;
)SQL",
      // ---- 2: QC results say which data they were computed on and how pass was decided ----
      R"SQL(
ALTER TABLE qc_results ADD COLUMN sample TEXT NOT NULL DEFAULT ''
  CHECK (sample IN ('', 'in-sample', 'out-of-sample', 'not applicable'));
ALTER TABLE qc_results ADD COLUMN criterion TEXT NOT NULL DEFAULT '';
)SQL",
      // ---- 3: settings of this database (e.g. four-eyes approval), who changed them and when ----
      R"SQL(
CREATE TABLE settings (
  key        TEXT PRIMARY KEY,
  value      TEXT NOT NULL,
  changed_at TEXT NOT NULL,
  changed_by TEXT NOT NULL
);
)SQL",
      // ---- 4: a stable id per run and set (forwarding from a station's journal is idempotent),
      //         and the journal's record of what reached the central store ----
      R"SQL(
ALTER TABLE bench_runs ADD COLUMN uid TEXT;
CREATE UNIQUE INDEX bench_runs_uid ON bench_runs(uid);
ALTER TABLE inmotion_runs ADD COLUMN uid TEXT;
CREATE UNIQUE INDEX inmotion_runs_uid ON inmotion_runs(uid);
ALTER TABLE coefficient_sets ADD COLUMN uid TEXT;
CREATE UNIQUE INDEX coefficient_sets_uid ON coefficient_sets(uid);
CREATE TRIGGER coefficient_sets_uid_immutable BEFORE UPDATE OF uid ON coefficient_sets
WHEN NEW.uid IS NOT OLD.uid
BEGIN SELECT RAISE(ABORT, 'coefficient sets are immutable'); END;
CREATE TABLE forwarded (
  uid        TEXT PRIMARY KEY,
  entity     TEXT NOT NULL,
  local_id   INTEGER NOT NULL,
  central_id INTEGER NOT NULL,
  target     TEXT NOT NULL,
  at         TEXT NOT NULL
);
)SQL",
      // ---- 5: several units per table cycle (issue 21): the unit's slot on the fixture, and the id
      //         of the table run that ties the units of one cycle ----
      R"SQL(
ALTER TABLE bench_runs ADD COLUMN slot TEXT NOT NULL DEFAULT '';
ALTER TABLE bench_runs ADD COLUMN table_run TEXT NOT NULL DEFAULT '';
CREATE INDEX bench_runs_table_run ON bench_runs(table_run);
)SQL",
      // ---- 6: signatures and recordings a central store can use (issue 35): the login beside the
      //         typed name (SQLite: the OS user, not authenticated), and each recording's absolute
      //         URI and digest of all its files ----
      R"SQL(
ALTER TABLE coefficient_sets ADD COLUMN created_by_role TEXT NOT NULL DEFAULT '';
CREATE TRIGGER coefficient_sets_role_immutable BEFORE UPDATE OF created_by_role ON coefficient_sets
WHEN NEW.created_by_role IS NOT OLD.created_by_role
BEGIN SELECT RAISE(ABORT, 'coefficient sets are immutable'); END;
ALTER TABLE audit_log ADD COLUMN db_role TEXT NOT NULL DEFAULT '';
ALTER TABLE bench_runs ADD COLUMN recording_uri TEXT NOT NULL DEFAULT '';
ALTER TABLE bench_runs ADD COLUMN recording_digest TEXT NOT NULL DEFAULT '';
)SQL",
      schema7_console_accounts,
      // ---- 8: the station's live state and its operator prompts (issue 38) ----
      schema8_station_progress(),
      // ---- 9: signatures that hold against an insider (issue 54) ----
      schema9_insider(),
  };
  return m;
}

}  // namespace calbench::db
