// A throw-away PostgreSQL server for C++ tests and benchmarks: tests/support/pg_server.sh (initdb
// in a folder of the caller's, a free loopback port, superuser calbench_admin over the Unix socket
// in that folder with trust auth), wrapped for one process. Nothing is mocked.
#pragma once
#include <sys/wait.h>

#include <cstdio>
#include <stdexcept>
#include <string>

#include "db/connection.hpp"

namespace calbench::db::test {

class PgServer {
 public:
  // Starts a server in `dir` (created if needed). available() is false when PostgreSQL is not
  // installed (pg_server.sh exit 77); any other failure throws.
  explicit PgServer(std::string dir) : dir_(std::move(dir)) { start(); }
  ~PgServer() { stop(); }
  PgServer(const PgServer&) = delete;
  PgServer& operator=(const PgServer&) = delete;

  bool available() const { return available_; }
  const std::string& dir() const { return dir_; }
  const std::string& port() const { return port_; }
  const std::string& why() const { return why_; }
  // The libpq URI of database `db` through the Unix socket, as the superuser.
  std::string uri(const std::string& db = "calbench") const {
    return "postgresql:///" + db + "?host=" + dir_ + "&port=" + port_ + "&user=calbench_admin";
  }
  // CREATE DATABASE `db` (a fixed name from the caller, not data).
  void create_database(const std::string& db = "calbench") {
    OpenOptions o;
    auto c = open_connection(uri("postgres"), o);
    c->exec(("CREATE DATABASE \"" + db + "\"").c_str());
  }
  // pg_server.sh start again (after kill): same data, same port when free. Returns the port.
  std::string start() {
    const std::string out = run("start");
    if (status_ == 77) {
      available_ = false;
      why_ = "no PostgreSQL server binaries (pg_server.sh exit 77)";
      return "";
    }
    if (status_ != 0 || out.empty()) throw std::runtime_error("pg_server.sh start " + dir_ + " failed: " + out);
    available_ = true;
    port_ = out;
    return port_;
  }
  // SIGKILL of the whole server (postmaster and every process of it), waiting until they are gone.
  void kill() { run("kill"); }
  void stop() {
    if (available_) run("stop");
  }

 private:
  std::string run(const char* cmd) {
    const std::string line = std::string(CALBENCH_SOURCE_DIR "/tests/support/pg_server.sh ") + cmd + " '" + dir_ + "'";
    FILE* p = ::popen(line.c_str(), "r");
    if (!p) throw std::runtime_error("popen " + line);
    std::string out;
    char buf[256];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
    const int st = ::pclose(p);
    status_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128;
    while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
    return out;
  }
  std::string dir_, port_, why_;
  bool available_ = false;
  int status_ = 0;
};

}  // namespace calbench::db::test
