// `calbench serve` (issue 38): the web console over the coefficient store — login, QC queue, set
// page with approve/revoke, device page, audit search — a thin layer over the store's queries, the
// verdict code (db::check_standing / approve_checked) and the device report's sections. Pages are
// server-side HTML; the style sheets and the live page's script are built into the binary.
// Security behaviour and its limits (issue 54): docs/console.md.
#pragma once
#include <string>

namespace calbench::console {

struct ServeOptions {
  std::string db;      // SQLite file or postgresql:// URI (without user and password: the login gives them)
  std::string listen;  // ADDR:PORT
  std::string tls_cert, tls_key;
  std::string thresholds;  // approval thresholds file ("" = the built-in ones of the device's class)
  int session_idle_s = 1800;
  int db_connections = 16;   // PostgreSQL: database connections open at most, all sessions together
  int max_connections = 512; // HTTP connections open at once (half of them from one address)
  int live_streams = 128;    // live-page event streams open at once (then 503 with a retry)
};

// Runs until the process is stopped. Bad options (address, port in use, unreadable certificate, no
// store) throw InputError before anything listens.
void serve(const ServeOptions& o);

}  // namespace calbench::console
