-- Roles of the central coefficient store (issue 18), enforced by PostgreSQL itself: a station's
-- credentials cannot approve a set even through plain psql. Apply after schema.sql, as the
-- owner of the tables (the role that applied schema.sql); idempotent.
--
-- Four group roles (NOLOGIN). People and machines log in as their own roles, members of one:
--   CREATE ROLE station3 LOGIN PASSWORD '…' IN ROLE calbench_station;
--   CREATE ROLE anna     LOGIN PASSWORD '…' IN ROLE calbench_qc;
--
-- | role                   | may                                                                      |
-- |------------------------|--------------------------------------------------------------------------|
-- | calbench_station       | register devices and stations, store bench/in-motion runs, QC results and |
-- |                        | draft sets; read everything; nothing else (no status change, no settings) |
-- | calbench_qc            | read everything; approve (draft → approved) and revoke; change settings   |
-- | calbench_provisioning  | read approved and provisioned sets (and their values) only; mark a set    |
-- |                        | provisioned; record provisioning events                                  |
-- | calbench_reader        | read everything; write nothing                                            |
--
-- Schema 9 (issue 54, calbench_grant_insider() in db/postgres/pg_schema.cpp) takes the direct
-- writes of signatures away from every role: a status changes, a provisioning event or a setting is
-- written, and an audit row is appended, only by the server's functions (calbench_approve,
-- calbench_revoke, calbench_record_provisioning, calbench_set_setting, calbench_audit), which check
-- the group, four-eyes by person and the database's part of the verdict. The grants below are the
-- older schemas'; on schema 9 the call at the end revokes the direct ones. Nobody updates or
-- deletes the audit log (schema.sql), and each row carries the database role that wrote it.

BEGIN;
SET LOCAL client_min_messages = warning;

DO $$
DECLARE r text;
BEGIN
  FOREACH r IN ARRAY ARRAY['calbench_station', 'calbench_qc', 'calbench_provisioning', 'calbench_reader'] LOOP
    IF NOT EXISTS (SELECT 1 FROM pg_roles WHERE rolname = r) THEN
      EXECUTE format('CREATE ROLE %I NOLOGIN', r);
    END IF;
  END LOOP;
END $$;

REVOKE ALL ON ALL TABLES IN SCHEMA public FROM PUBLIC;
REVOKE CREATE ON SCHEMA public FROM PUBLIC;
GRANT USAGE ON SCHEMA public TO calbench_station, calbench_qc, calbench_provisioning, calbench_reader;

-- Reading.
GRANT SELECT ON ALL TABLES IN SCHEMA public TO calbench_station, calbench_qc, calbench_reader;
GRANT SELECT ON devices, stations, coefficient_sets, coefficient_values, provisioning_events, settings,
  schema_version TO calbench_provisioning;
-- Who each login is (schema version 6): every role reads it, to sign as its person.
DO $$
BEGIN
  IF to_regclass('calbench_users') IS NOT NULL THEN
    GRANT SELECT ON calbench_users TO calbench_provisioning;
  END IF;
END $$;

-- The station: new rows only.
GRANT INSERT ON devices, stations, bench_runs, inmotion_runs, coefficient_sets, coefficient_values,
  qc_results, audit_log TO calbench_station;
GRANT UPDATE (firmware) ON devices TO calbench_station;

-- QC: the status (approve, revoke) and the settings.
GRANT UPDATE (status) ON coefficient_sets TO calbench_qc;
GRANT INSERT, UPDATE ON settings TO calbench_qc;
GRANT INSERT ON audit_log TO calbench_qc;

-- Provisioning: the status (provisioned) and its events.
GRANT UPDATE (status) ON coefficient_sets TO calbench_provisioning;
GRANT INSERT ON provisioning_events, audit_log TO calbench_provisioning;

-- Row rules: which sets a role sees and which status it may give. The table owner (migrations)
-- is not subject to them.
ALTER TABLE coefficient_sets ENABLE ROW LEVEL SECURITY;
ALTER TABLE coefficient_values ENABLE ROW LEVEL SECURITY;
DROP POLICY IF EXISTS sets_read_all ON coefficient_sets;
DROP POLICY IF EXISTS sets_station_insert ON coefficient_sets;
DROP POLICY IF EXISTS sets_qc_status ON coefficient_sets;
DROP POLICY IF EXISTS sets_provisioning_read ON coefficient_sets;
DROP POLICY IF EXISTS sets_provisioning_status ON coefficient_sets;
DROP POLICY IF EXISTS values_read ON coefficient_values;
DROP POLICY IF EXISTS values_station_insert ON coefficient_values;
CREATE POLICY sets_read_all ON coefficient_sets FOR SELECT
  TO calbench_station, calbench_qc, calbench_reader USING (true);
CREATE POLICY sets_station_insert ON coefficient_sets FOR INSERT
  TO calbench_station WITH CHECK (status = 'draft');
CREATE POLICY sets_qc_status ON coefficient_sets FOR UPDATE
  TO calbench_qc USING (true) WITH CHECK (status IN ('approved', 'revoked'));
CREATE POLICY sets_provisioning_read ON coefficient_sets FOR SELECT
  TO calbench_provisioning USING (status IN ('approved', 'provisioned'));
CREATE POLICY sets_provisioning_status ON coefficient_sets FOR UPDATE
  TO calbench_provisioning USING (status IN ('approved', 'provisioned')) WITH CHECK (status = 'provisioned');
-- A set's values are visible exactly when the set is (the sets' policies apply in the subquery).
CREATE POLICY values_read ON coefficient_values FOR SELECT
  TO calbench_station, calbench_qc, calbench_provisioning, calbench_reader
  USING (EXISTS (SELECT 1 FROM coefficient_sets s WHERE s.id = set_id));
-- Values go with a draft (a set's values are written with it, before anyone can approve it).
CREATE POLICY values_station_insert ON coefficient_values FOR INSERT
  TO calbench_station WITH CHECK (EXISTS (SELECT 1 FROM coefficient_sets s WHERE s.id = set_id AND s.status = 'draft'));

-- The station's live state and operator prompts (schema version 7): grants and row rules in
-- calbench_grant_station_live() (db/postgres/pg_schema.cpp), one place for both paths.
DO $$
BEGIN
  IF to_regprocedure('calbench_grant_station_live()') IS NOT NULL THEN
    PERFORM calbench_grant_station_live();
  END IF;
END $$;

-- Schema 9: signatures only through the server's functions (revokes the direct writes above).
DO $$
BEGIN
  IF to_regprocedure('calbench_grant_insider()') IS NOT NULL THEN
    PERFORM calbench_grant_insider();
  END IF;
END $$;

COMMIT;
