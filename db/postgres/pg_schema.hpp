// The PostgreSQL schema as data: the base (db/postgres/schema.sql, schema version 3, embedded at
// build time) and the migrations after it, in step with the SQLite migrations (db/schema.cpp).
// The roles (db/postgres/roles.sql) are applied by `calbench db init --roles`.
#pragma once
#include <vector>

namespace calbench::db {
inline constexpr int kPgBaseSchemaVersion = 3;
const char* pg_base_schema();  // schema.sql
// Schema 7's station block (issue 38 item 3): station_progress, station_prompts, their row rules.
const char* pg_schema8_station_progress();
const char* pg_roles_sql();    // roles.sql
// pg_migrations()[i] takes the database from version kPgBaseSchemaVersion + i to + i + 1.
const std::vector<const char*>& pg_migrations();
}  // namespace calbench::db
