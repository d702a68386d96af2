// Migrations of the PostgreSQL store after its base schema, as data. Never edit a released one:
// append. Each records its version in schema_version.
#include "db/postgres/pg_schema.hpp"

#include "db/postgres/pg_schema_sql.hpp"

namespace calbench::db {

const char* pg_base_schema() { return generated::kPgSchemaSql; }
const char* pg_roles_sql() { return generated::kPgRolesSql; }

const std::vector<const char*>& pg_migrations() {
  static const std::vector<const char*> m = {
      // ---- 4: a stable id per run and set (forwarding from a station's journal is idempotent) ----
      R"SQL(
ALTER TABLE bench_runs ADD COLUMN uid text UNIQUE;
ALTER TABLE inmotion_runs ADD COLUMN uid text UNIQUE;
ALTER TABLE coefficient_sets ADD COLUMN uid text UNIQUE;
CREATE OR REPLACE FUNCTION calbench_set_update() RETURNS trigger LANGUAGE plpgsql AS $$
BEGIN
  IF (NEW.payload_json, NEW.device_id, NEW.version, NEW.source, NEW.parent_id, NEW.bench_run_id,
      NEW.inmotion_run_id, NEW.created_at, NEW.created_by, NEW.created_by_role, NEW.id, NEW.uid)
     IS DISTINCT FROM
     (OLD.payload_json, OLD.device_id, OLD.version, OLD.source, OLD.parent_id, OLD.bench_run_id,
      OLD.inmotion_run_id, OLD.created_at, OLD.created_by, OLD.created_by_role, OLD.id, OLD.uid) THEN
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
INSERT INTO schema_version(version) VALUES (4);
)SQL",
  };
  return m;
}

}  // namespace calbench::db
