// Migrations of the PostgreSQL store after its base schema, as data. Never edit a released one:
// append. Each records its version in schema_version.
#include "db/postgres/pg_schema.hpp"

#include <string>

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
static const char* const pg_schema9_functions = R"SQL(
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
-- Who a login is, and a person's name as compared (case, surrounding and repeated spaces, Unicode
-- spaces ignored: the SQLite store's normalized_name, db/signer.cpp).
CREATE FUNCTION calbench_person(p_login text) RETURNS text LANGUAGE sql STABLE SECURITY DEFINER
  SET search_path = public, pg_temp AS $f$ SELECT u.name FROM calbench_users u WHERE u.login = p_login $f$;
CREATE FUNCTION calbench_person_key(p_name text) RETURNS text LANGUAGE sql IMMUTABLE AS $f$
  SELECT lower(btrim(regexp_replace(translate(coalesce(p_name, ''),
    chr(160) || chr(5760) || chr(8192) || chr(8193) || chr(8194) || chr(8195) || chr(8196) || chr(8197) || chr(8198) ||
    chr(8199) || chr(8200) || chr(8201) || chr(8202) || chr(8239) || chr(8287) || chr(12288), repeat(' ', 16)),
    '\s+', ' ', 'g')))
$f$;
-- The person who typed the set's operator name is kept in its own column (never parsed out of
-- created_by): immutable with the other columns (calbench_set_update compares them all).
ALTER TABLE coefficient_sets ADD COLUMN creator text NOT NULL DEFAULT '';
-- Older sets: the name before the first '@' (an operator name never holds one), written once here
-- with the immutability rule lifted for this one statement.
ALTER TABLE coefficient_sets DISABLE TRIGGER coefficient_sets_update;
UPDATE coefficient_sets SET creator = split_part(created_by, '@', 1);
ALTER TABLE coefficient_sets ENABLE TRIGGER coefficient_sets_update;

-- A status changes only inside the functions below (SECURITY DEFINER, owned by the tables' owner),
-- for every role, the owner included: a direct UPDATE of status is refused.
CREATE OR REPLACE FUNCTION calbench_set_update() RETURNS trigger LANGUAGE plpgsql AS $f$
BEGIN
  IF to_jsonb(NEW) - 'status' IS DISTINCT FROM to_jsonb(OLD) - 'status' THEN
    RAISE EXCEPTION 'coefficient sets are immutable' USING ERRCODE = 'integrity_constraint_violation';
  END IF;
  IF NEW.status IS DISTINCT FROM OLD.status AND (current_user = session_user OR current_user::text <>
      (SELECT c.relowner::regrole::text FROM pg_class c WHERE c.oid = 'coefficient_sets'::regclass)) THEN
    RAISE EXCEPTION 'a status changes only through calbench_approve, calbench_revoke or calbench_record_provisioning '
                    '(calbench db approve, db revoke, provision): they check the verdict and write the signed audit row'
      USING ERRCODE = 'insufficient_privilege';
  END IF;
  IF NOT ((OLD.status = 'draft' AND NEW.status IN ('approved', 'revoked'))
       OR (OLD.status = 'approved' AND NEW.status IN ('provisioned', 'revoked'))
       OR (OLD.status = 'provisioned' AND NEW.status IN ('provisioned', 'revoked'))) THEN
    RAISE EXCEPTION 'status change not allowed: % -> %', OLD.status, NEW.status
      USING ERRCODE = 'integrity_constraint_violation';
  END IF;
  RETURN NEW;
END $f$;

CREATE FUNCTION calbench_need_group(p_group text, p_what text) RETURNS text LANGUAGE plpgsql STABLE
  SET search_path = public, pg_temp AS $f$
DECLARE who text := calbench_person(session_user);
BEGIN
  IF NOT pg_has_role(session_user, p_group, 'MEMBER') THEN
    RAISE EXCEPTION 'permission denied: only a login in % may %', p_group, p_what USING ERRCODE = 'insufficient_privilege';
  END IF;
  IF who IS NULL THEN
    RAISE EXCEPTION 'login % is not mapped to a person, and a signature names one (calbench db user add)', session_user
      USING ERRCODE = 'insufficient_privilege';
  END IF;
  RETURN who;
END $f$;

-- What every role may record itself: that it created (or, for a device, updated; for a prompt,
-- asked or answered) a row in this very transaction. Who it is, is the server's: the login's
-- person when mapped (else the typed name), db_role = session_user. Signatures (status, approve-
-- refused, provision, export, settings) are written only by the functions that make the change.
CREATE FUNCTION calbench_audit(p_entity text, p_entity_id bigint, p_action text, p_detail text, p_user text,
                               p_station text) RETURNS void
  LANGUAGE plpgsql SECURITY DEFINER SET search_path = public, pg_temp AS $f$
DECLARE dev bigint; fresh boolean; me xid := pg_current_xact_id()::xid;
BEGIN
  IF p_action NOT IN ('create', 'firmware', 'ask', 'answer', 'timeout') THEN
    RAISE EXCEPTION 'an audit row "%" is written only by the function that makes the change', p_action
      USING ERRCODE = 'insufficient_privilege';
  END IF;
  CASE p_entity
    WHEN 'device' THEN SELECT t.id, t.xmin = me INTO dev, fresh FROM devices t WHERE t.id = p_entity_id;
    WHEN 'station' THEN SELECT NULL, t.xmin = me INTO dev, fresh FROM stations t WHERE t.id = p_entity_id;
    WHEN 'coefficient_set' THEN SELECT t.device_id, t.xmin = me INTO dev, fresh FROM coefficient_sets t WHERE t.id = p_entity_id;
    WHEN 'bench_run' THEN SELECT t.device_id, t.xmin = me INTO dev, fresh FROM bench_runs t WHERE t.id = p_entity_id;
    WHEN 'inmotion_run' THEN SELECT t.device_id, t.xmin = me INTO dev, fresh FROM inmotion_runs t WHERE t.id = p_entity_id;
    WHEN 'station_prompt' THEN SELECT NULL, t.xmin = me INTO dev, fresh FROM station_prompts t WHERE t.id = p_entity_id;
    ELSE RAISE EXCEPTION 'no audit row for a %', p_entity USING ERRCODE = 'insufficient_privilege';
  END CASE;
  IF fresh IS NOT TRUE THEN
    RAISE EXCEPTION 'an audit row names a row its own transaction wrote (% % was not)', p_entity, p_entity_id
      USING ERRCODE = 'insufficient_privilege';
  END IF;
  INSERT INTO audit_log("user", station, entity, entity_id, device_id, action, detail)
  VALUES (coalesce(calbench_person(session_user), p_user), p_station, p_entity, p_entity_id, dev, p_action, p_detail);
END $f$;

-- The device classes' coefficient limits (|bias|, |scale|, |skew| per triad, SI), written by the
-- owner (`calbench db init`: the class defaults of bench/imu_classes, model '*' the built-in ones):
-- the floor the database holds every approval to, whatever thresholds file the client used.
CREATE TABLE approval_limits (
  model  text PRIMARY KEY,  -- normalized model name (lower case, no white space), or '*'
  limits jsonb NOT NULL,    -- {"gyro": {"bias": B, "scale": S, "skew": K}, "accel": {...}}
  source text NOT NULL DEFAULT '',
  set_at timestamptz NOT NULL DEFAULT now(),
  set_by text NOT NULL DEFAULT session_user
);
CREATE FUNCTION calbench_limit_reasons(p_set bigint) RETURNS text[] LANGUAGE plpgsql STABLE
  SET search_path = public, pg_temp AS $f$
DECLARE lim jsonb; src text; why text[] := '{}'; v record; kind text; bound double precision;
BEGIN
  SELECT l.limits, l.source INTO lim, src FROM coefficient_sets s JOIN devices d ON d.id = s.device_id
    JOIN approval_limits l ON l.model = lower(regexp_replace(d.model, '\s', '', 'g')) WHERE s.id = p_set;
  IF lim IS NULL THEN SELECT limits, source INTO lim, src FROM approval_limits WHERE model = '*'; END IF;
  IF lim IS NULL THEN RETURN why; END IF;
  FOR v IN SELECT name, value FROM coefficient_values WHERE set_id = p_set ORDER BY name LOOP
    kind := CASE WHEN split_part(v.name, '.', 2) = 'bias' THEN 'bias'
                 WHEN substr(split_part(v.name, '.', 3), 1, 1) = substr(split_part(v.name, '.', 3), 2, 1) THEN 'scale'
                 ELSE 'skew' END;
    bound := (lim -> split_part(v.name, '.', 1) ->> kind)::double precision;
    IF bound IS NOT NULL AND abs(v.value) > bound THEN
      why := why || format('%s = %s exceeds the database''s %s limit %s (%s)', v.name, v.value, kind, bound, src);
    END IF;
  END LOOP;
  RETURN why;
END $f$;

-- The parts of the verdict the database holds (the coefficient limits above; every recorded QC
-- result passes; an in-motion fit whose adaptive noise failed is refused), shared by approval and
-- provisioning. The σ and fit-quality limits of the thresholds file are the client's.
CREATE FUNCTION calbench_db_verdict(p_set bigint) RETURNS text[] LANGUAGE plpgsql STABLE
  SET search_path = public, pg_temp AS $f$
DECLARE s record; why text[] := calbench_limit_reasons(p_set); q record;
BEGIN
  SELECT * INTO s FROM coefficient_sets WHERE id = p_set;
  FOR q IN SELECT metric, value, threshold FROM qc_results
           WHERE NOT pass AND ((s.bench_run_id IS NOT NULL AND bench_run_id = s.bench_run_id)
                            OR (s.inmotion_run_id IS NOT NULL AND inmotion_run_id = s.inmotion_run_id)) LOOP
    why := why || format('QC %s = %s failed%s (the database''s check)', q.metric, q.value,
                         CASE WHEN q.threshold IS NULL THEN '' ELSE format(' (threshold %s)', q.threshold) END);
  END LOOP;
  IF s.inmotion_run_id IS NOT NULL AND EXISTS (SELECT 1 FROM inmotion_runs r WHERE r.id = s.inmotion_run_id
      AND (r.result_json::jsonb #>> '{adaptive_noise,failed}') = 'true') THEN
    why := why || 'in-motion filter: the adaptive noise scale failed (the database''s check)'::text;
  END IF;
  IF s.parent_id IS NOT NULL AND EXISTS (SELECT 1 FROM coefficient_sets p WHERE p.id = s.parent_id
      AND p.status IN ('draft', 'revoked')) THEN
    why := why || format('parent set %s is draft or revoked (the database''s check)', s.parent_id);
  END IF;
  RETURN why;
END $f$;

-- Approval: the client's verdict (its thresholds file) comes in p_client_reasons; the database adds
-- its own checks and four-eyes by person, and either approves (the signed status row) or records
-- the refusal with every reason (approve-refused) and returns the reasons.
CREATE FUNCTION calbench_approve(p_set bigint, p_station text, p_client_reasons text[], p_note text) RETURNS text[]
  LANGUAGE plpgsql SECURITY DEFINER SET search_path = public, pg_temp AS $f$
DECLARE who text := calbench_need_group('calbench_qc', 'approve'); s record; why text[] := coalesce(p_client_reasons, '{}');
        maker text; four_eyes boolean;
BEGIN
  SELECT * INTO s FROM coefficient_sets WHERE id = p_set FOR UPDATE;
  IF NOT FOUND THEN RAISE EXCEPTION 'no coefficient set %', p_set USING ERRCODE = 'no_data_found'; END IF;
  maker := calbench_person(s.created_by_role);
  four_eyes := coalesce((SELECT value FROM settings WHERE key = 'four_eyes'), 'on') = 'on';
  -- The database's own checks decide only where the client found nothing: a refusal stands anyway.
  IF cardinality(why) = 0 AND s.status <> 'draft' THEN
    why := why || format('set %s is %s, only draft sets can be approved', p_set, s.status);
  END IF;
  IF cardinality(why) = 0 THEN why := why || calbench_db_verdict(p_set); END IF;
  IF cardinality(why) = 0 AND four_eyes AND (s.created_by_role = session_user OR calbench_person_key(who) = calbench_person_key(s.creator)
                    OR calbench_person_key(who) = calbench_person_key(maker)) THEN
    why := why || format('four-eyes: set %s was stored by %s (login %s%s); %s (login %s) is the same person: another '
                         'person must approve it', p_set, s.creator, s.created_by_role,
                         CASE WHEN maker IS NULL THEN '' ELSE ', ' || maker END, who, session_user);
  END IF;
  IF cardinality(why) > 0 THEN
    INSERT INTO audit_log("user", station, entity, entity_id, device_id, action, detail)
    VALUES (who, p_station, 'coefficient_set', p_set, s.device_id, 'approve-refused', array_to_string(why, '; '));
    RETURN why;
  END IF;
  INSERT INTO audit_log("user", station, entity, entity_id, device_id, action, detail)
  VALUES (who, p_station, 'coefficient_set', p_set, s.device_id, 'status',
          format('draft -> approved: signed by %s (login %s), stored by %s (login %s%s)%s%s', who, session_user, s.creator,
                 s.created_by_role, CASE WHEN maker IS NULL THEN '' ELSE ', ' || maker END,
                 CASE WHEN four_eyes THEN '' ELSE ', four-eyes off' END,
                 CASE WHEN coalesce(p_note, '') = '' THEN '' ELSE '; ' || p_note END));
  UPDATE coefficient_sets SET status = 'approved' WHERE id = p_set;
  RETURN '{}';
END $f$;

CREATE FUNCTION calbench_revoke(p_set bigint, p_reason text, p_station text) RETURNS void
  LANGUAGE plpgsql SECURITY DEFINER SET search_path = public, pg_temp AS $f$
DECLARE who text := calbench_need_group('calbench_qc', 'revoke'); s record;
BEGIN
  SELECT * INTO s FROM coefficient_sets WHERE id = p_set FOR UPDATE;
  IF NOT FOUND THEN RAISE EXCEPTION 'no coefficient set %', p_set USING ERRCODE = 'no_data_found'; END IF;
  INSERT INTO audit_log("user", station, entity, entity_id, device_id, action, detail)
  VALUES (who, p_station, 'coefficient_set', p_set, s.device_id, 'status',
          s.status || ' -> revoked' || CASE WHEN coalesce(p_reason, '') = '' THEN '' ELSE ': ' || p_reason END);
  UPDATE coefficient_sets SET status = 'revoked' WHERE id = p_set;
END $f$;

-- Provisioning: only a set with its signed approval row (another person than its creator, unless
-- four-eyes was off), whose database verdict still holds. Asked before anything is written to a
-- unit or a file, and again when the event is recorded.
CREATE FUNCTION calbench_provisioning_refusals(p_set bigint) RETURNS text[] LANGUAGE plpgsql STABLE SECURITY DEFINER
  SET search_path = public, pg_temp AS $f$
DECLARE s record; a record; why text[] := '{}';
BEGIN
  SELECT * INTO s FROM coefficient_sets WHERE id = p_set;
  IF NOT FOUND OR s.status NOT IN ('approved', 'provisioned') THEN
    RETURN ARRAY[format('set %s is not approved: only approved sets are provisioned', p_set)];
  END IF;
  SELECT * INTO a FROM audit_log l WHERE l.entity = 'coefficient_set' AND l.entity_id = p_set AND l.action = 'status'
    AND l.detail LIKE 'draft -> approved%' ORDER BY l.id DESC LIMIT 1;
  IF NOT FOUND THEN
    why := why || format('set %s has no signed approval row in the audit log', p_set);
  ELSIF a.detail NOT LIKE '%, four-eyes off%' AND (a.db_role = s.created_by_role
        OR calbench_person_key(a."user") = calbench_person_key(s.creator)
        OR calbench_person_key(calbench_person(a.db_role)) = calbench_person_key(calbench_person(s.created_by_role))) THEN
    why := why || format('set %s was approved by %s (login %s), the person who stored it, with four-eyes on', p_set,
                         a."user", a.db_role);
  END IF;
  RETURN why || calbench_db_verdict(p_set);
END $f$;

CREATE FUNCTION calbench_record_provisioning(p_set bigint, p_kind text, p_target text, p_ok boolean, p_readback text,
                                             p_message text, p_station text) RETURNS bigint
  LANGUAGE plpgsql SECURITY DEFINER SET search_path = public, pg_temp AS $f$
DECLARE who text := calbench_need_group('calbench_provisioning', 'provision'); s record; ev bigint; why text[];
BEGIN
  SELECT * INTO s FROM coefficient_sets WHERE id = p_set FOR UPDATE;
  IF NOT FOUND OR s.status NOT IN ('approved', 'provisioned') THEN
    RAISE EXCEPTION 'set % is not approved: only approved sets are provisioned', p_set USING ERRCODE = 'check_violation';
  END IF;
  why := calbench_provisioning_refusals(p_set);
  IF cardinality(why) > 0 THEN
    RAISE EXCEPTION 'set % is not provisioned: %', p_set, array_to_string(why, '; ') USING ERRCODE = 'check_violation';
  END IF;
  INSERT INTO provisioning_events(set_id, device_id, kind, target, ok, readback_json, message, actor)
  VALUES (p_set, s.device_id, p_kind, p_target, p_ok, coalesce(nullif(p_readback, ''), '{}'), coalesce(p_message, ''),
          who || '@' || coalesce(p_station, '')) RETURNING id INTO ev;
  INSERT INTO audit_log("user", station, entity, entity_id, device_id, action, detail)
  VALUES (who, p_station, 'coefficient_set', p_set, s.device_id, CASE WHEN p_kind = 'device' THEN 'provision' ELSE 'export' END,
          format('%s to %s (event %s)%s', CASE WHEN p_ok THEN 'ok' ELSE 'FAILED' END, p_target, ev,
                 CASE WHEN coalesce(p_message, '') = '' THEN '' ELSE ': ' || p_message END));
  IF p_kind = 'device' AND p_ok THEN
    IF s.status <> 'provisioned' THEN
      INSERT INTO audit_log("user", station, entity, entity_id, device_id, action, detail)
      VALUES (who, p_station, 'coefficient_set', p_set, s.device_id, 'status', 'approved -> provisioned');
    END IF;
    UPDATE coefficient_sets SET status = 'provisioned' WHERE id = p_set;
  END IF;
  RETURN ev;
END $f$;

CREATE FUNCTION calbench_set_setting(p_key text, p_value text, p_station text) RETURNS void
  LANGUAGE plpgsql SECURITY DEFINER SET search_path = public, pg_temp AS $f$
DECLARE who text := calbench_need_group('calbench_qc', 'change a setting'); before text;
BEGIN
  IF NOT (p_key = 'four_eyes' AND p_value IN ('on', 'off')) THEN
    RAISE EXCEPTION 'unknown setting %=%', p_key, p_value USING ERRCODE = 'check_violation';
  END IF;
  before := coalesce((SELECT value FROM settings WHERE key = p_key), 'on');
  INSERT INTO settings(key, value, changed_at, changed_by) VALUES (p_key, p_value, now(), who || '@' || coalesce(p_station, ''))
  ON CONFLICT (key) DO UPDATE SET value = excluded.value, changed_at = excluded.changed_at, changed_by = excluded.changed_by;
  INSERT INTO audit_log("user", station, entity, entity_id, action, detail)
  VALUES (who, p_station, 'setting', 0, 'set', p_key || ': ' || before || ' -> ' || p_value);
END $f$;

DO $$
DECLARE f text;
BEGIN
  FOREACH f IN ARRAY ARRAY['calbench_audit(text, bigint, text, text, text, text)', 'calbench_approve(bigint, text, text[], text)',
                           'calbench_revoke(bigint, text, text)',
                           'calbench_record_provisioning(bigint, text, text, boolean, text, text, text)',
                           'calbench_set_setting(text, text, text)', 'calbench_audit_security(text, text, text, text)',
                           'calbench_provisioning_refusals(bigint)'] LOOP
    EXECUTE format('REVOKE ALL ON FUNCTION %s FROM PUBLIC', f);
  END LOOP;
END $$;
)SQL";

// Schema 9's grants (also called by roles.sql): nobody writes audit rows, statuses, provisioning
// events or settings directly; each role executes the functions that make its changes.
static const char* const pg_schema9_grants = R"SQL(
CREATE FUNCTION calbench_grant_insider() RETURNS void LANGUAGE plpgsql AS $f$
BEGIN
  IF NOT EXISTS (SELECT 1 FROM pg_roles WHERE rolname = 'calbench_station') THEN
    RETURN;  -- roles.sql, run later, calls this again
  END IF;
  REVOKE INSERT ON audit_log FROM calbench_station, calbench_qc, calbench_provisioning, calbench_reader;
  REVOKE UPDATE ON coefficient_sets FROM calbench_qc, calbench_provisioning;
  REVOKE INSERT, UPDATE ON settings FROM calbench_qc;
  REVOKE INSERT ON provisioning_events FROM calbench_provisioning;
  GRANT EXECUTE ON FUNCTION calbench_audit(text, bigint, text, text, text, text) TO calbench_station, calbench_qc;
  GRANT EXECUTE ON FUNCTION calbench_approve(bigint, text, text[], text) TO calbench_qc;
  GRANT EXECUTE ON FUNCTION calbench_revoke(bigint, text, text) TO calbench_qc;
  GRANT EXECUTE ON FUNCTION calbench_set_setting(text, text, text) TO calbench_qc;
  GRANT EXECUTE ON FUNCTION calbench_record_provisioning(bigint, text, text, boolean, text, text, text)
    TO calbench_provisioning;
  GRANT EXECUTE ON FUNCTION calbench_provisioning_refusals(bigint)
    TO calbench_station, calbench_qc, calbench_provisioning, calbench_reader;
  GRANT SELECT ON approval_limits TO calbench_station, calbench_qc, calbench_provisioning, calbench_reader;
  GRANT EXECUTE ON FUNCTION calbench_audit_security(text, text, text, text)
    TO calbench_station, calbench_qc, calbench_provisioning, calbench_reader;
END $f$;
)SQL";

const char* pg_schema9_insider() {
  static const std::string m = std::string(pg_schema9_functions) + pg_schema9_grants +
                               "SELECT calbench_grant_insider();\nINSERT INTO schema_version(version) VALUES (9);\n";
  return m.c_str();
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
