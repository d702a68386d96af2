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
  };
  return m;
}

}  // namespace calbench::db
