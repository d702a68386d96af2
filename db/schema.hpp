// The database schema as a list of migrations; PRAGMA user_version = number applied.
#pragma once
#include <vector>

namespace calbench::db {
// migrations()[i] takes the schema from user_version i to i + 1 (fixed DDL text, no data).
const std::vector<const char*>& migrations();
// Schema 7's station block (issue 38 item 3): station_progress and station_prompts (SQLite DDL).
const char* schema8_station_progress();
// Schema 9's last part, run after the audit rows already there are chained (Store::migrate).
inline constexpr int kChainSchemaVersion = 9;
const char* schema9_after_seal();
// Its trigger that refuses an approval without its signed audit row just before it (a bulk fixture
// that approves by SQL drops it and creates it again with this).
const char* schema9_approval_signed_trigger();
}  // namespace calbench::db
