-- The coefficient store on PostgreSQL (issue 18): the same tables, statuses and rules as the
-- SQLite schema (db/schema.cpp, schema version 3), in PostgreSQL's terms. Apply once to an empty
-- database as its owner, then db/postgres/roles.sql. Who may do what is in roles.sql; the rules
-- here hold for every role, the owner included:
--   * coefficient sets and their values are immutable; only the status changes, only forwards
--     (draft → approved|revoked, approved → provisioned|revoked, provisioned → provisioned|revoked);
--     a set is stored as draft;
--   * the audit log is append-only, and each row records the database role that wrote it
--     (db_role = session_user, whatever the client claims);
--   * versions are per device, unique (gapless numbering is the writer's: lock the device row,
--     take max + 1, in one transaction).
-- Timestamps are timestamptz (UTC on output as ISO 8601 with milliseconds, as the SQLite store).
--
-- `calbench db init --db postgresql://OWNER@HOST/DB` applies this file and the migrations after it
-- (db/postgres/pg_schema.cpp) in one transaction; by hand: `psql -1 -f schema.sql` (one transaction).

CREATE TABLE schema_version (
  version    integer PRIMARY KEY,
  applied_at timestamptz NOT NULL DEFAULT now(),
  applied_by text NOT NULL DEFAULT session_user
);

CREATE TABLE devices (
  id         bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  model      text NOT NULL,
  serial     text NOT NULL UNIQUE,
  firmware   text NOT NULL DEFAULT '',
  created_at timestamptz NOT NULL DEFAULT now()
);
CREATE TABLE stations (
  id          bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  name        text NOT NULL UNIQUE,
  description text NOT NULL DEFAULT '',
  created_at  timestamptz NOT NULL DEFAULT now()
);
CREATE TABLE bench_runs (
  id               bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  device_id        bigint NOT NULL REFERENCES devices(id),
  station_id       bigint REFERENCES stations(id),
  plan             text NOT NULL DEFAULT '',
  recording_path   text NOT NULL DEFAULT '',
  recording_sha256 text NOT NULL DEFAULT '',
  started_at       text NOT NULL DEFAULT '',
  ended_at         text NOT NULL DEFAULT '',
  outcome          text NOT NULL CHECK (outcome IN ('pass', 'fail', 'aborted')),
  created_at       timestamptz NOT NULL DEFAULT now()
);
CREATE INDEX bench_runs_device ON bench_runs(device_id);
CREATE TABLE inmotion_runs (
  id                 bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  device_id          bigint NOT NULL REFERENCES devices(id),
  recording_path     text NOT NULL DEFAULT '',
  recording_sha256   text NOT NULL DEFAULT '',
  reference_system   text NOT NULL DEFAULT '',
  mounting_roll_deg  double precision, mounting_pitch_deg double precision, mounting_yaw_deg double precision,
  mounting_roll_sigma_deg double precision, mounting_pitch_sigma_deg double precision,
  mounting_yaw_sigma_deg double precision,
  consistency_json   text NOT NULL DEFAULT '{}',
  qc_json            text NOT NULL DEFAULT '{}',
  result_json        text NOT NULL,
  created_at         timestamptz NOT NULL DEFAULT now()
);
CREATE INDEX inmotion_runs_device ON inmotion_runs(device_id);
CREATE TABLE coefficient_sets (
  id              bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  device_id       bigint NOT NULL REFERENCES devices(id),
  version         integer NOT NULL CHECK (version >= 1),
  source          text NOT NULL CHECK (source IN ('bench', 'in-motion', 'combined')),
  parent_id       bigint REFERENCES coefficient_sets(id),
  bench_run_id    bigint REFERENCES bench_runs(id),
  inmotion_run_id bigint REFERENCES inmotion_runs(id),
  payload_json    text NOT NULL,
  status          text NOT NULL DEFAULT 'draft'
                  CHECK (status IN ('draft', 'approved', 'provisioned', 'revoked')),
  created_at      timestamptz NOT NULL DEFAULT now(),
  created_by      text NOT NULL,
  created_by_role text NOT NULL DEFAULT session_user,
  UNIQUE (device_id, version)
);
CREATE TABLE coefficient_values (
  set_id bigint NOT NULL REFERENCES coefficient_sets(id),
  name   text NOT NULL,
  value  double precision NOT NULL,
  sigma  double precision,  -- NULL: unknown (not estimated)
  PRIMARY KEY (set_id, name)
);
CREATE TABLE qc_results (
  id              bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  bench_run_id    bigint REFERENCES bench_runs(id),
  inmotion_run_id bigint REFERENCES inmotion_runs(id),
  metric          text NOT NULL,
  value           double precision NOT NULL,
  threshold       double precision,
  pass            boolean NOT NULL,
  unit            text NOT NULL DEFAULT '',
  sample          text NOT NULL DEFAULT ''
                  CHECK (sample IN ('', 'in-sample', 'out-of-sample', 'not applicable')),
  criterion       text NOT NULL DEFAULT '',
  CHECK ((bench_run_id IS NULL) <> (inmotion_run_id IS NULL))
);
CREATE INDEX qc_results_bench ON qc_results(bench_run_id);
CREATE INDEX qc_results_inmotion ON qc_results(inmotion_run_id);
CREATE TABLE provisioning_events (
  id            bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  set_id        bigint NOT NULL REFERENCES coefficient_sets(id),
  device_id     bigint NOT NULL REFERENCES devices(id),
  kind          text NOT NULL CHECK (kind IN ('device', 'export')),
  target        text NOT NULL,
  ok            boolean NOT NULL,
  readback_json text NOT NULL DEFAULT '{}',
  message       text NOT NULL DEFAULT '',
  actor         text NOT NULL,
  db_role       text NOT NULL DEFAULT session_user,
  at            timestamptz NOT NULL DEFAULT now()
);
CREATE INDEX provisioning_device ON provisioning_events(device_id);
CREATE TABLE audit_log (
  id        bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  at        timestamptz NOT NULL DEFAULT now(),
  "user"    text NOT NULL,
  station   text NOT NULL,
  db_role   text NOT NULL DEFAULT session_user,
  entity    text NOT NULL,
  entity_id bigint NOT NULL,
  device_id bigint REFERENCES devices(id),
  action    text NOT NULL,
  detail    text NOT NULL DEFAULT ''
);
CREATE INDEX audit_device ON audit_log(device_id);
CREATE TABLE settings (
  key        text PRIMARY KEY,
  value      text NOT NULL,
  changed_at timestamptz NOT NULL DEFAULT now(),
  changed_by text NOT NULL
);

-- ---- rules that hold for every role ----

-- The role that wrote a row is the session's, not what the client says.
CREATE FUNCTION calbench_stamp_role() RETURNS trigger LANGUAGE plpgsql AS $$
BEGIN
  IF TG_TABLE_NAME = 'coefficient_sets' THEN
    NEW.created_by_role := session_user;
  ELSE
    NEW.db_role := session_user;
  END IF;
  RETURN NEW;
END $$;
CREATE TRIGGER audit_log_role BEFORE INSERT ON audit_log FOR EACH ROW EXECUTE FUNCTION calbench_stamp_role();
CREATE TRIGGER provisioning_role BEFORE INSERT ON provisioning_events FOR EACH ROW EXECUTE FUNCTION calbench_stamp_role();
CREATE TRIGGER coefficient_sets_role BEFORE INSERT ON coefficient_sets FOR EACH ROW EXECUTE FUNCTION calbench_stamp_role();

-- A set is born a draft.
CREATE FUNCTION calbench_set_insert() RETURNS trigger LANGUAGE plpgsql AS $$
BEGIN
  IF NEW.status <> 'draft' THEN
    RAISE EXCEPTION 'a coefficient set is stored as draft (approval is a separate, signed step)'
      USING ERRCODE = 'check_violation';
  END IF;
  RETURN NEW;
END $$;
CREATE TRIGGER coefficient_sets_insert BEFORE INSERT ON coefficient_sets
  FOR EACH ROW EXECUTE FUNCTION calbench_set_insert();

-- Immutable, except the status, which only moves forwards. Every other column is compared, so a
-- column added by a later migration is immutable without editing this function.
CREATE FUNCTION calbench_set_update() RETURNS trigger LANGUAGE plpgsql AS $$
BEGIN
  IF to_jsonb(NEW) - 'status' IS DISTINCT FROM to_jsonb(OLD) - 'status' THEN
    RAISE EXCEPTION 'coefficient sets are immutable' USING ERRCODE = 'integrity_constraint_violation';
  END IF;
  IF NOT ((OLD.status = 'draft' AND NEW.status IN ('approved', 'revoked'))
       OR (OLD.status = 'approved' AND NEW.status IN ('provisioned', 'revoked'))
       OR (OLD.status = 'provisioned' AND NEW.status IN ('provisioned', 'revoked'))) THEN
    RAISE EXCEPTION 'status change not allowed: % -> %', OLD.status, NEW.status
      USING ERRCODE = 'integrity_constraint_violation';
  END IF;
  RETURN NEW;
END $$;
CREATE TRIGGER coefficient_sets_update BEFORE UPDATE ON coefficient_sets
  FOR EACH ROW EXECUTE FUNCTION calbench_set_update();

CREATE FUNCTION calbench_refuse() RETURNS trigger LANGUAGE plpgsql AS $$
BEGIN
  RAISE EXCEPTION '%', TG_ARGV[0] USING ERRCODE = 'integrity_constraint_violation';
END $$;
CREATE TRIGGER coefficient_sets_no_delete BEFORE DELETE ON coefficient_sets
  FOR EACH ROW EXECUTE FUNCTION calbench_refuse('coefficient sets are never deleted (revoke them)');
CREATE TRIGGER coefficient_values_immutable BEFORE UPDATE OR DELETE ON coefficient_values
  FOR EACH ROW EXECUTE FUNCTION calbench_refuse('coefficient values are immutable');
CREATE TRIGGER audit_log_append_only BEFORE UPDATE OR DELETE ON audit_log
  FOR EACH ROW EXECUTE FUNCTION calbench_refuse('the audit log is append-only');
CREATE TRIGGER provisioning_append_only BEFORE UPDATE OR DELETE ON provisioning_events
  FOR EACH ROW EXECUTE FUNCTION calbench_refuse('provisioning events are append-only');
-- TRUNCATE bypasses row triggers: refuse it on the tables that keep the record.
CREATE TRIGGER coefficient_sets_no_truncate BEFORE TRUNCATE ON coefficient_sets
  EXECUTE FUNCTION calbench_refuse('coefficient sets are never deleted (revoke them)');
CREATE TRIGGER coefficient_values_no_truncate BEFORE TRUNCATE ON coefficient_values
  EXECUTE FUNCTION calbench_refuse('coefficient values are immutable');
CREATE TRIGGER audit_log_no_truncate BEFORE TRUNCATE ON audit_log
  EXECUTE FUNCTION calbench_refuse('the audit log is append-only');

INSERT INTO schema_version(version) VALUES (3);
