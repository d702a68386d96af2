// The web console's request handling (internal to bench/console): the route table and pages
// (server.cpp), log-in, per-request authorization and security audit (login.cpp), the live page's
// event streams (live_stream.cpp). Connection handling: http_server.hpp.
#pragma once
#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <regex>
#include <string>
#include <vector>

#include "bench/console/login_guard.hpp"
#include "bench/console/pg_pool.hpp"
#include "bench/console/server.hpp"
#include "bench/console/sessions.hpp"
#include "db/approval.hpp"
#include "db/store.hpp"

namespace httplib {
struct Request;
struct Response;
class Server;
}  // namespace httplib

namespace calbench::console {

inline constexpr int kStreamsPerSession = 2;  // a session's newest live stream replaces its oldest beyond this

struct Page {
  int status = 200;
  std::string html;
  std::string type = "text/html; charset=utf-8";
  bool streamed = false;  // the handler set a content provider (server-sent events)
};

class Console {
 public:
  explicit Console(const ServeOptions& o);
  void install(httplib::Server& srv, bool tls);

 private:
  struct Ctx {
    const httplib::Request& req;
    httplib::Response& res;
    std::smatch m;
    std::shared_ptr<Session> s;
    std::string token;
    std::map<std::string, std::string> form, query, cookies;
    db::Store* st = nullptr;  // the session's store for this request
    PgPool::Lease lease;      // PostgreSQL: the connection lent to this request
  };
  struct Route {
    std::string method, pattern;
    std::function<Page(Ctx&)> fn;
    bool session;
  };

  // server.cpp
  void dispatch(const httplib::Request& req, httplib::Response& res);
  Page run_route(Ctx& c, const Route& r);
  std::shared_ptr<Session> session(Ctx& c);
  std::string cookie(const std::string& name, const std::string& value, bool clear = false) const;
  Page redirect(Ctx& c, const std::string& to);
  std::string shell(Ctx& c, const std::string& title, const std::string& body);
  Page asset(Ctx& c);
  db::Thresholds thresholds(const db::CoefficientSetRecord& set) const;
  Page queue(Ctx& c);
  Page set_page(Ctx& c, const std::string& message, bool ok, int status = 200);
  Page set_action(Ctx& c);
  Page device_page(Ctx& c);
  Page audit_page(Ctx& c);
  Page live_page(Ctx& c, const std::string& message, bool ok, int status = 200);
  Page prompt_action(Ctx& c);
  static bool may_answer(const Session& s) { return s.role != "provisioning"; }

  // login.cpp
  Page login_page(Ctx& c, const std::string& error, int status = 200);
  Page login_post(Ctx& c);
  std::shared_ptr<Session> login_sqlite(const std::string& login, const std::string& password);
  std::shared_ptr<Session> login_pg(const std::string& login, const std::string& password);
  Page logout(Ctx& c);
  std::string login_csrf(const std::string& pre) const;
  bool login_csrf_ok(const std::string& pre, const std::string& token) const;
  db::Actor actor(const std::string& login, const std::string& name) const;
  // Opens the session's store for one request (SQLite: its own; PostgreSQL: a pooled connection in
  // `lease`) and checks the account as it is now: "" when the session still holds, else why it ended.
  std::string open_checked(Session& s, db::Store*& st, PgPool::Lease& lease);
  // A session whose rights changed: all of its login's sessions end (audited as a refusal).
  void end_sessions(const std::string& login, const std::string& why, const std::string& address, db::Store* st);
  // Security events: SQLite through the console's own store, PostgreSQL through `st` (the session's
  // connection) when there is one, else only the server's log.
  void security_event(const std::string& action, const std::string& login, const std::string& detail, db::Store* st);
  void refused(Ctx& c, const std::string& what);

  // live_stream.cpp
  Page live_events(Ctx& c);

  ServeOptions o_;
  bool postgres_ = false;
  bool tls_ = false;
  Sessions sessions_;
  LoginGuard guard_;
  std::unique_ptr<PgPool> pool_;         // PostgreSQL
  std::unique_ptr<db::Store> audit_st_;  // SQLite: the console's own store, for security events
  std::mutex audit_m_;
  unsigned char csrf_key_[32];  // signs the login form's token (a random key per server start)
  std::mutex streams_m_;
  std::atomic<int> streams_open_{0};
  std::vector<Route> routes_;
};

// The client address and login of the request being answered, for the server's log line.
void set_log_login(const std::string& login);

}  // namespace calbench::console
