#include "db/access_check.hpp"

#include <memory>

#include "db/connection.hpp"
#include "db/store.hpp"

namespace calbench::db {

StationAccess check_station_access(const std::string& uri) {
  StationAccess a;
  std::unique_ptr<Connection> c;
  try {
    c = open_connection(uri, OpenOptions{});
  } catch (const ConnectionLost& e) {
    a.state = StationAccess::State::unreachable;
    a.reason = e.what();
    return a;
  } catch (const DbError& e) {  // credentials refused, no such database
    a.state = StationAccess::State::refused;
    a.reason = e.what();
    return a;
  }
  a.state = StationAccess::State::refused;
  auto who = c->prepare("SELECT session_user, to_regclass('schema_version') IS NOT NULL");
  who.step();
  a.role = who.text(0);
  int version = 0;
  if (who.int64(1)) {
    auto v = c->prepare("SELECT COALESCE(MAX(version), 0) FROM schema_version");
    v.step();
    version = static_cast<int>(v.int64(0));
  }
  if (version != kSchemaVersion) {
    a.reason = c->path() + ": the database has schema version " + std::to_string(version) + ", this calbench needs " +
               std::to_string(kSchemaVersion) + " (" +
               (version < kSchemaVersion ? "the database owner runs `calbench db init --db URI`"
                                         : "use the calbench that matches the central store") + ")";
    return a;
  }
  // What a station run inserts (Store::store_bench, store_bench_run): the row kinds, and the one column
  // it may update.
  std::string missing;
  for (const char* t : {"devices", "stations", "bench_runs", "qc_results", "coefficient_sets", "coefficient_values"}) {
    auto p = c->prepare("SELECT has_table_privilege(?, 'INSERT'), has_table_privilege(?, 'SELECT')");
    p.bind(1, t).bind(2, t);
    p.step();
    if (!p.int64(0)) missing += std::string(missing.empty() ? "" : ", ") + "INSERT on " + t;
    if (!p.int64(1)) missing += std::string(missing.empty() ? "" : ", ") + "SELECT on " + t;
  }
  auto f = c->prepare("SELECT has_column_privilege('devices', 'firmware', 'UPDATE')");
  f.step();
  if (!f.int64(0)) missing += std::string(missing.empty() ? "" : ", ") + "UPDATE of devices.firmware";
  // Its audit rows: through calbench_audit (schema 9; nobody inserts into audit_log directly).
  auto au = c->prepare("SELECT has_function_privilege('calbench_audit(text, bigint, text, text, text, text)', 'EXECUTE')");
  au.step();
  if (!au.int64(0)) missing += std::string(missing.empty() ? "" : ", ") + "EXECUTE on calbench_audit";
  if (!missing.empty()) {
    a.reason = c->path() + ": role '" + a.role + "' may not store a station run (missing " + missing +
               "): a station logs in as a member of calbench_station (the owner: `calbench db init --roles`, then "
               "GRANT calbench_station TO " + a.role + ")";
    return a;
  }
  a.state = StationAccess::State::ok;
  a.reason.clear();
  return a;
}

}  // namespace calbench::db
