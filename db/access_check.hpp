// Before a station moves the table (issue 35 item 3): may its credentials store what a station run
// stores at the central PostgreSQL store? Checked at start, so that wrong credentials, an old schema
// or a role without the station's privileges are found before a table cycle, not at its end.
#pragma once
#include <string>

namespace calbench::db {

struct StationAccess {
  enum class State {
    ok,           // logged in, schema current, the role may insert every row a station run inserts
    unreachable,  // the server did not answer: the offline case (the journal takes the run)
    refused,      // wrong credentials, no such database, another schema version, missing privileges
  };
  State state = State::ok;
  std::string reason;  // unreachable / refused: why, naming the URI (without password) and what to do
  std::string role;    // ok / refused after login: the role logged in as
};

// Logs in to `uri` (a PostgreSQL URI, checked by check_target first) and checks the schema version
// and the privileges a station run needs (has_table_privilege: INSERT and SELECT on devices,
// stations, bench_runs, qc_results, coefficient_sets, coefficient_values, audit_log; UPDATE of
// devices.firmware). Reads only; writes nothing.
StationAccess check_station_access(const std::string& uri);

}  // namespace calbench::db
