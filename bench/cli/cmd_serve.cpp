// calbench serve --db URI|FILE --listen ADDR:PORT [--tls-cert F --tls-key F] [limits]: the web console
// (bench/console/server.hpp, docs/console.md).
#include <memory>

#include "bench/cli/registry.hpp"
#include "bench/console/server.hpp"

namespace calbench::cli {
namespace {

const bool registered = add_command(95, [](CLI::App& app) {
  auto o = std::make_shared<console::ServeOptions>();
  auto* sub = app.add_subcommand("serve", "the web console: QC queue, approval, device pages, audit log (docs/console.md)");
  sub->add_option("--db", o->db,
                  "the store: a SQLite file (console accounts: db user add) or postgresql://HOST[:PORT]/DB without user "
                  "or password (each user logs in with their database login)")
      ->required();
  sub->add_option("--listen", o->listen, "ADDR:PORT to listen on, e.g. 127.0.0.1:8080")->required();
  sub->add_option("--tls-cert", o->tls_cert, "PEM certificate: serve HTTPS (cookies then carry Secure); with --tls-key");
  sub->add_option("--tls-key", o->tls_key, "PEM private key of --tls-cert");
  sub->add_option("--thresholds", o->thresholds,
                  "approval thresholds (JSON, as for db approve); default: the built-in limits of each device's class");
  sub->add_option("--session-idle", o->session_idle_s, "seconds without a request after which a session ends (default 1800)")
      ->check(CLI::Range(1, 86400));
  sub->add_option("--db-connections", o->db_connections,
                  "PostgreSQL: database connections the console keeps open at most, all sessions together (default 16); "
                  "a request waits up to 5 s for one, then 503")
      ->check(CLI::Range(1, 1000));
  sub->add_option("--max-connections", o->max_connections,
                  "HTTP connections open at once (default 512), at most half of them from one client address; "
                  "beyond: 503")
      ->check(CLI::Range(8, 20000));
  sub->add_option("--live-streams", o->live_streams,
                  "live-page event streams open at once, all sessions together (default 128; 2 per session, the newest "
                  "replacing the oldest); beyond: 503 and the page retries")
      ->check(CLI::Range(1, 10000));
  sub->footer("Runs until stopped (Ctrl-C). Sessions and lock-outs live in server memory: a restart logs everyone out. "
             "Lock-out: 5 wrong passwords within 15 min lock a login for 15 min; 30 from one address stop that address. "
             "Security behaviour and limits: docs/console.md.");
  sub->callback([o] { console::serve(*o); });
});

}  // namespace
}  // namespace calbench::cli
