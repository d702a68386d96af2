#include "bench/console/server.hpp"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <regex>
#include <sstream>
#include <thread>
#include <vector>

#include "bench/approval_thresholds.hpp"
#include "bench/console/live_page.hpp"
#include "bench/console/request_parse.hpp"
#include "bench/console/sessions.hpp"
#include "bench/report/db_report.hpp"
#include "bench/report/html_parts.hpp"
#include "common/input_error.hpp"
#include "common/percent_encode.hpp"
#include "db/approval.hpp"
#include "db/console_accounts.hpp"
#include "db/signer.hpp"
#include "db/station_live.hpp"

// Last: httplib.h brings <resolv.h>, whose macro _res breaks Eigen's headers if they come after it.
#include <httplib.h>

namespace calbench::console {
namespace {
using report::html_escape;
const char* kCookie = "calbench_session";
const char* kPreCookie = "calbench_login";  // the login form's CSRF token (double submit), before a session

const char* kConsoleCss = R"CSS(
body{font-family:DejaVu Sans,Arial,sans-serif;font-size:12px;margin:0;color:#111}
nav{background:#234;color:#fff;padding:6px 12px} nav a,nav button{color:#fff;margin-right:14px;background:none;border:0;font:inherit;cursor:pointer;text-decoration:underline}
nav form{display:inline} main{margin:12px 16px;max-width:1400px}
.msg{padding:6px 10px;margin:8px 0;border:2px solid} .msg.ok{border-color:#070;color:#070} .msg.err{border-color:#b00;color:#b00}
form.act{margin:6px 0;padding:6px;border:1px solid #bbb;display:inline-block;vertical-align:top}
input,button{font:inherit} table.q td,table.q th{border:1px solid #bbb;padding:2px 6px;text-align:left;vertical-align:top}
table.q{border-collapse:collapse}
.prompt{border-color:#a60;background:#fff8e8;overflow-wrap:anywhere} table.live td.why{overflow-wrap:anywhere;max-width:32em} section.run{margin:10px 0 18px} #live-status{color:#666}
)CSS";
constexpr int kQueuePage = 50;          // sets per page of the QC queue
constexpr int kWorkers = 64;             // server threads (pages and live event streams)
constexpr double kStreamS = 300;          // a live page's event stream is renewed (EventSource reconnects) after this

struct Page {
  int status = 200;
  std::string html;
  std::string type = "text/html; charset=utf-8";
  bool streamed = false;  // the handler set a content provider (server-sent events)
};


class Console {
 public:
  explicit Console(const ServeOptions& o) : o_(o), sessions_(std::chrono::seconds(o.session_idle_s)) {
    postgres_ = db::is_postgres_uri(o.db);
    db::check_target(o.db);
    if (!postgres_) {  // the store must exist and be migrated (a console does not create stores)
      db::Store s(o.db, {}, db::Actor::from_environment());
    }
  }

  void install(httplib::Server& srv) {
    // The route table: {method, path pattern, handler, needs a session}.
    routes_ = {
        {"GET", "/", [this](Ctx& c) { return redirect(c, "/queue"); }, false},
        {"GET", "/login", [this](Ctx& c) { return login_page(c, ""); }, false},
        {"POST", "/login", [this](Ctx& c) { return login_post(c); }, false},
        {"POST", "/logout", [this](Ctx& c) { return logout(c); }, true},
        {"GET", "/queue", [this](Ctx& c) { return queue(c); }, true},
        {"GET", R"(/set/(\d{1,18}))", [this](Ctx& c) { return set_page(c, "", true); }, true},
        {"POST", R"(/set/(\d{1,18})/(approve|revoke))", [this](Ctx& c) { return set_action(c); }, true},
        {"GET", R"(/device/([^/]{1,200}))", [this](Ctx& c) { return device_page(c); }, true},
        {"GET", "/audit", [this](Ctx& c) { return audit_page(c); }, true},
        {"GET", "/live", [this](Ctx& c) { return live_page(c, "", true); }, true},
        {"GET", "/fleet", [this](Ctx& c) { return Page{200, shell(c, "Fleet", report::fleet_report_body(*c.s->store))}; }, true},
        {"GET", "/live/events", [this](Ctx& c) { return live_events(c); }, true},
        {"POST", R"(/prompt/(\d{1,18})/(confirm|reject))", [this](Ctx& c) { return prompt_action(c); }, true},
        {"GET", R"(/assets/([a-z]+\.(?:css|js)))", [this](Ctx& c) { return asset(c); }, false},
    };
    const auto handler = [this](const httplib::Request& req, httplib::Response& res) { dispatch(req, res); };
    srv.Get(R"(/.*)", handler);
    srv.Post(R"(/.*)", handler);
    srv.set_payload_max_length(64 * 1024);
    // Each open live page holds a worker for its event stream: room for them beside the pages.
    srv.new_task_queue = [] { return new httplib::ThreadPool(kWorkers); };
    srv.set_logger([](const httplib::Request& req, const httplib::Response& res) {
      // The path only: no query, body or header (passwords, session and CSRF tokens never reach the log).
      std::cerr << "calbench serve: " << req.method << " " << req.path << " " << res.status << "\n";
    });
  }

 private:
  struct Ctx {
    const httplib::Request& req;
    httplib::Response& res;
    std::smatch m;
    std::shared_ptr<Session> s;
    std::string token;
    std::map<std::string, std::string> form, query, cookies;
  };
  struct Route {
    std::string method, pattern;
    std::function<Page(Ctx&)> fn;
    bool session;
  };

  void dispatch(const httplib::Request& req, httplib::Response& res) {
    Ctx c{req, res, {}, nullptr, {}, {}, {}, {}};
    Page p;
    try {
      c.cookies = parse_cookies(req.get_header_value("Cookie"));
      const auto q = req.target.find('?');
      if (q != std::string::npos) c.query = parse_form(std::string_view(req.target).substr(q + 1));
      if (req.method == "POST") c.form = parse_form(req.body);
      const Route* r = nullptr;
      for (const auto& x : routes_)
        if (x.method == req.method && std::regex_match(req.path, c.m, std::regex(x.pattern))) {
          r = &x;
          break;
        }
      if (!r) {
        p = {404, shell(c, "Not found", "<div class=\"msg err\" id=\"error\">no such page: " + html_escape(req.path) + "</div>")};
      } else if (r->session && !(c.s = session(c))) {
        if (req.method == "POST") p = login_page(c, "your session has ended (logged out or expired): log in again; nothing was changed", 401);
        else p = redirect(c, "/login");
      } else if (r->session && req.method == "POST" && !same_token(c.form["csrf"], c.s->csrf)) {
        p = {403, shell(c, "Refused", "<div class=\"msg err\" id=\"error\">refused: the form's CSRF token is missing or "
                                      "wrong (a form from another page or site?); nothing was changed</div>")};
      } else if (r->session) {
        const std::lock_guard<std::mutex> l(c.s->m);
        p = r->fn(c);
      } else {
        p = r->fn(c);
      }
    } catch (const InputError& e) {
      p = {400, shell(c, "Bad request", "<div class=\"msg err\" id=\"error\">refused: " + html_escape(e.what()) + "; nothing was changed</div>")};
    } catch (const db::PermissionError& e) {
      p = {403, shell(c, "Refused", "<div class=\"msg err\" id=\"error\">" + html_escape(e.what()) + "</div>")};
    } catch (const std::exception& e) {
      p = {500, shell(c, "Error", "<div class=\"msg err\" id=\"error\">" + html_escape(e.what()) + "</div>")};
    }
    res.status = p.status;
    if (res.get_header_value("Location").empty() && !p.streamed) res.set_content(p.html, p.type);
    // Script only from the console's own built-in asset (the live view's event stream).
    res.set_header("Content-Security-Policy", "default-src 'none'; script-src 'self'; connect-src 'self'; style-src 'self' "
                                              "'unsafe-inline'; img-src 'self' data:; form-action 'self'; frame-ancestors 'none'");
    res.set_header("X-Content-Type-Options", "nosniff");
    res.set_header("Referrer-Policy", "no-referrer");
    res.set_header("Cache-Control", "no-store");
  }

  std::shared_ptr<Session> session(Ctx& c) {
    const auto it = c.cookies.find(kCookie);
    if (it == c.cookies.end()) return nullptr;
    c.token = it->second;
    return sessions_.find(it->second);
  }

  std::string cookie(const std::string& name, const std::string& value, bool clear = false) const {
    return name + "=" + value + "; Path=/; HttpOnly; SameSite=Strict" + (o_.tls_cert.empty() ? "" : "; Secure") +
           (clear ? "; Max-Age=0" : "");
  }

  Page redirect(Ctx& c, const std::string& to) {
    c.res.set_header("Location", to);
    return {303, ""};
  }

  std::string shell(Ctx& c, const std::string& title, const std::string& body) {
    std::string nav = "<nav><b>calbench console</b> &nbsp; ";
    if (c.s)
      nav += "<a href=\"/queue\">QC queue</a><a href=\"/live\">live stations</a><a href=\"/fleet\">fleet</a><a href=\"/audit\">audit log</a>"
             "<form method=\"get\" action=\"/audit\"><input name=\"serial\" placeholder=\"serial\" size=\"10\"></form> "
             "signed in as <span id=\"who\">" + html_escape(c.s->name + " (" + c.s->login + (c.s->role.empty() ? "" : ", " + c.s->role) + ")") +
             "</span> <form method=\"post\" action=\"/logout\"><input type=\"hidden\" name=\"csrf\" value=\"" + c.s->csrf +
             "\"><button id=\"logout\" type=\"submit\">log out</button></form>";
    nav += "</nav>";
    return "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" + html_escape(title) +
           " — calbench</title><link rel=\"stylesheet\" href=\"/assets/report.css\"><link rel=\"stylesheet\" href=\"/assets/console.css\">"
           "</head><body>" + nav + "<main>\n" + body + "\n</main></body></html>\n";
  }

  Page asset(Ctx& c) {
    const std::string name = c.m[1];
    if (name == "console.css") return {200, kConsoleCss, "text/css"};
    if (name == "report.css") return {200, report::report_css(), "text/css"};
    if (name == "live.js") return {200, live_js(), "text/javascript"};
    return {404, "/* no such asset */", "text/css"};
  }

  Page login_page(Ctx& c, const std::string& error, int status = 200) {
    const std::string pre = random_token();
    c.res.set_header("Set-Cookie", cookie(kPreCookie, pre));
    std::string b = "<h1>Log in</h1>";
    if (!error.empty()) b += "<div class=\"msg err\" id=\"error\">" + html_escape(error) + "</div>";
    b += std::string("<p class=\"note\">") +
         (postgres_ ? "Your PostgreSQL login and password: every page runs as that database role."
                    : "Your console account (calbench db user add on this SQLite store).") +
         "</p><form method=\"post\" action=\"/login\"><input type=\"hidden\" name=\"csrf\" value=\"" + pre +
         "\"><p><label>login <input id=\"login\" name=\"login\" autocomplete=\"username\" maxlength=\"64\"></label></p>"
         "<p><label>password <input id=\"password\" name=\"password\" type=\"password\" autocomplete=\"current-password\"></label></p>"
         "<p><button id=\"submit\" type=\"submit\">log in</button></p></form>";
    c.s = nullptr;
    return {status, shell(c, "Log in", b)};
  }

  Page login_post(Ctx& c) {
    const auto pre = c.cookies.find(kPreCookie);
    if (pre == c.cookies.end() || !same_token(c.form["csrf"], pre->second))
      return login_page(c, "refused: the login form's CSRF token is missing or wrong; reload the page and try again", 403);
    const std::string login = c.form["login"], password = c.form["password"];
    if (login.empty() || login.size() > 64) return login_page(c, "give your login (1 to 64 characters)", 400);
    if (const std::string why = sessions_.locked(login); !why.empty()) return login_page(c, why, 429);
    auto s = std::make_shared<Session>();
    db::Actor who = db::Actor::from_environment();
    who.source = "console login " + login;
    try {
      if (postgres_) {
        const std::string uri = o_.db + (o_.db.find('?') == std::string::npos ? "?" : "&") + "user=" + percent_encode(login) +
                                "&password=" + percent_encode(password);
        who.user = login;  // the login's person, once the store knows it (db::Store::check_signer)
        s->store = std::make_unique<db::Store>(uri, db::OpenOptions{}, who);
        s->login = login;
        auto st = s->store->connection().prepare("SELECT name, role FROM calbench_users WHERE login = session_user");
        if (st.step()) s->name = st.text(0), s->role = st.text(1);
        else s->name = login;
      } else {
        auto store = std::make_unique<db::Store>(o_.db, db::OpenOptions{}, who);
        const auto acct = db::check_console_password(*store, login, password);
        if (!acct) throw db::ConnectionLost(0, "wrong login or password");
        who.user = acct->name;
        store->set_actor(who);
        store->set_console_account(acct->login, acct->role);
        s->store = std::move(store);
        s->login = acct->login, s->name = acct->name, s->role = acct->role;
      }
    } catch (const db::DbError& e) {
      // PostgreSQL refused the credentials (or SQLite's account check failed): one failure.
      sessions_.failed(login);
      std::string why = e.what();
      if (postgres_) {
        // The server's own words (libpq's "FATAL: …"), without the command line's advice on where
        // a password comes from, which does not apply to a form.
        const auto fatal = why.find("FATAL:");
        if (fatal != std::string::npos) {
          why = why.substr(fatal + 6);
          why = why.substr(0, why.find_first_of(";)\n"));
          while (!why.empty() && why.front() == ' ') why.erase(0, 1);
        }
        why = "the database refused the login: " + why;
      }
      // Never echo the password (libpq messages do not contain it; the URI is redacted by the store).
      if (!password.empty())
        for (std::size_t p; (p = why.find(password)) != std::string::npos;) why.replace(p, password.size(), "***");
      return login_page(c, why, 401);
    }
    sessions_.succeeded(login);
    const std::string token = sessions_.add(s);
    c.res.set_header("Set-Cookie", cookie(kCookie, token));
    return redirect(c, "/queue");
  }

  Page logout(Ctx& c) {
    sessions_.remove(c.token);
    c.res.set_header("Set-Cookie", cookie(kCookie, "", true));
    c.s = nullptr;
    return login_page(c, "");
  }

  db::Thresholds thresholds(const db::CoefficientSetRecord& set) const {
    return approval_thresholds(o_.thresholds, o_.thresholds.empty() ? set.model : "");
  }

  Page queue(Ctx& c) {
    db::Store& st = *c.s->store;
    // 50 per page, oldest first: each row's verdict is computed as db approve would (its QC results,
    // parent and fit evidence), so a page is bounded work however long the queue.
    const std::int64_t total = st.count_sets_with_status(db::SetStatus::draft);
    const std::int64_t pages = std::max<std::int64_t>(1, (total + kQueuePage - 1) / kQueuePage);
    std::int64_t page = 1;
    if (const auto q = c.query.find("page"); q != c.query.end()) {
      const std::string& v = q->second;
      const bool digits = !v.empty() && v.size() <= 9 && v.find_first_not_of("0123456789") == std::string::npos;
      const std::int64_t asked = digits ? std::stoll(v) : 0;
      if (asked < 1) throw InputError("page", 0, "", "'" + v + "' is not a page number (1, 2, …)");
      page = std::min(asked, pages);
    }
    const auto drafts = st.sets_with_status(db::SetStatus::draft, kQueuePage, (page - 1) * kQueuePage);
    std::ostringstream b;
    b << "<h1>QC queue</h1><p class=\"note\" id=\"queue-count\">" << total
      << " set(s) awaiting approval, oldest first";
    if (pages > 1) b << "; page " << page << " of " << pages << " (" << kQueuePage << " per page)";
    b << ". The verdict is the one db approve gives (thresholds in force per device class).</p>\n";
    if (pages > 1) {
      b << "<p class=\"pages\">";
      if (page > 1) b << "<a id=\"prev\" href=\"/queue?page=" << page - 1 << "\">← older</a> ";
      if (page < pages) b << "<a id=\"next\" href=\"/queue?page=" << page + 1 << "\">newer →</a>";
      b << "</p>\n";
    }
    b << "<table class=\"q\" id=\"queue\"><tr><th>set</th><th>device</th><th>version</th><th>source</th>"
         "<th>stored by</th><th>verdict</th></tr>\n";
    for (const auto& s : drafts) {
      const db::ApprovalCheck chk = db::check_standing(st, s, thresholds(s));
      b << "<tr data-set=\"" << s.id << "\"><td><a class=\"open\" href=\"/set/" << s.id << "\">set " << s.id << "</a></td><td><a href=\"/device/"
        << html_escape(s.serial) << "\">" << html_escape(s.model + " " + s.serial) << "</a></td><td>" << s.version << "</td><td>"
        << db::source_label(s) << "</td><td>" << html_escape(s.created_by + " (" + s.created_at + ")") << "</td><td class=\""
        << (chk.ok ? "pass\">meets every threshold" : "fail\">would be refused");
      if (!chk.ok) {
        b << "<ul>";
        for (const auto& r : chk.reasons) b << "<li>" << html_escape(r) << "</li>";
        b << "</ul>";
      }
      b << "</td></tr>\n";
    }
    b << "</table>";
    return {200, shell(c, "QC queue", b.str())};
  }

  Page set_page(Ctx& c, const std::string& message, bool ok, int status = 200) {
    db::Store& st = *c.s->store;
    const auto set = st.get_set(std::stoll(c.m[1]));
    std::ostringstream b;
    if (!message.empty())
      b << "<div class=\"msg " << (ok ? "ok\" id=\"done\">" : "err\" id=\"error\">") << html_escape(message) << "</div>\n";
    b << "<h1>Set " << set.id << " of " << html_escape(set.serial) << " (v" << set.version << ", " << db::source_label(set)
      << ", <span id=\"status\">" << db::to_string(set.status) << "</span>)</h1>\n";
    const std::string hidden = "<input type=\"hidden\" name=\"csrf\" value=\"" + c.s->csrf + "\">";
    if (set.status == db::SetStatus::draft)
      b << "<form class=\"act\" method=\"post\" action=\"/set/" << set.id << "/approve\">" << hidden
        << "<button id=\"approve\" type=\"submit\">approve set " << set.id << "</button> as " << html_escape(c.s->name) << "</form>\n";
    if (set.status != db::SetStatus::revoked)
      b << "<form class=\"act\" method=\"post\" action=\"/set/" << set.id << "/revoke\">" << hidden
        << "<label>reason <input id=\"reason\" name=\"reason\" maxlength=\"4096\" size=\"40\" required></label> "
           "<button id=\"revoke\" type=\"submit\">revoke</button></form>\n";
    b << "<div class=\"report\" id=\"report\">" << report::device_report_body(st, set.serial, thresholds(set)) << "</div>";
    return {status, shell(c, "Set " + std::to_string(set.id), b.str())};
  }

  Page set_action(Ctx& c) {
    db::Store& st = *c.s->store;
    const std::int64_t id = std::stoll(c.m[1]);
    const std::string action = c.m[2];
    const auto set = st.get_set(id);
    try {
      if (action == "approve") {
        const db::ApprovalCheck r = db::approve_checked(st, id, thresholds(set));
        if (r.already) return set_page(c, "set " + std::to_string(id) + " was already approved (no change)", true);
        if (r.ok) return set_page(c, "set " + std::to_string(id) + " approved, signed by " + st.actor().user, true);
        std::string why;
        for (const auto& x : r.reasons) why += (why.empty() ? "" : "; ") + x;
        return set_page(c, "set " + std::to_string(id) + " NOT approved: " + why, false, 409);
      }
      const std::string reason = c.form["reason"];
      if (reason.empty()) return set_page(c, "a revocation needs a reason; nothing was changed", false, 400);
      if (set.status == db::SetStatus::revoked) return set_page(c, "set is already revoked (no change)", true);
      st.set_status(id, db::SetStatus::revoked, reason);
      return set_page(c, "set " + std::to_string(id) + " revoked: " + reason, true);
    } catch (const db::PermissionError& e) {
      return set_page(c, std::string("refused by the store: ") + e.what(), false, 403);
    } catch (const InputError& e) {
      return set_page(c, std::string("refused: ") + e.what(), false, 400);
    }
  }

  Page device_page(Ctx& c) {
    db::Store& st = *c.s->store;
    const std::string serial = c.m[1];
    const auto dev = st.find_device(serial);
    if (!dev) return {404, shell(c, "Unknown device", "<div class=\"msg err\" id=\"error\">unknown device '" + html_escape(serial) + "'</div>")};
    const auto latest = st.latest_set(dev->id, std::nullopt);
    const db::Thresholds t = approval_thresholds(o_.thresholds, o_.thresholds.empty() ? dev->model : "");
    std::string b = "<p><a href=\"/audit?serial=" + html_escape(serial) + "\">audit log of this device</a>";
    for (const auto& s : st.set_statuses(dev->id)) b += " · <a href=\"/set/" + std::to_string(s.id) + "\">set " + std::to_string(s.id) + "</a>";
    b += "</p><div class=\"report\" id=\"report\">" + report::device_report_body(st, serial, t) + "</div>";
    (void)latest;
    return {200, shell(c, "Device " + serial, b)};
  }

  Page audit_page(Ctx& c) {
    db::Store& st = *c.s->store;
    db::Store::AuditQuery q{c.query["serial"], c.query["who"], c.query["action"], c.query["from"], c.query["to"], 500};
    const auto rows = st.audit_search(q);
    std::ostringstream b;
    const auto field = [&](const char* name, const std::string& v, const char* hint) {
      b << "<label>" << name << " <input name=\"" << name << "\" value=\"" << html_escape(v) << "\" placeholder=\"" << hint
        << "\" size=\"12\"></label> ";
    };
    b << "<h1>Audit log</h1><form method=\"get\" action=\"/audit\" id=\"search\">";
    field("serial", q.serial, "device serial");
    field("who", q.who, "login or name");
    field("action", q.action, "e.g. status");
    field("from", q.from, "YYYY-MM-DD");
    field("to", q.to, "YYYY-MM-DD");
    b << "<button type=\"submit\">search</button></form><p class=\"note\">" << rows.size()
      << " entr(y/ies), newest first (at most 500)</p><table class=\"q\" id=\"audit\"><tr><th>when</th><th>who</th><th>what</th><th>detail</th></tr>\n";
    for (const auto& a : rows) {
      const std::string note = db::signature_note(a.login, st.authenticated());
      b << "<tr><td>" << html_escape(a.at) << "</td><td>" << html_escape(a.user + "@" + a.station + (note.empty() ? "" : " (" + note + ")"))
        << "</td><td>" << html_escape(a.entity + " " + std::to_string(a.entity_id) + " " + a.action) << "</td><td>"
        << html_escape(a.detail) << "</td></tr>\n";
    }
    b << "</table>";
    return {200, shell(c, "Audit log", b.str())};
  }

  // Station or QC may answer prompts (the store refuses others in any case: PostgreSQL's grants, the
  // SQLite account's role in db::answer_prompt).
  static bool may_answer(const Session& s) { return s.role != "provisioning"; }

  Page live_page(Ctx& c, const std::string& message, bool ok, int status = 200) {
    std::string b = "<h1>Live stations</h1>";
    if (!message.empty())
      b += std::string("<div class=\"msg ") + (ok ? "ok\" id=\"done\">" : "err\" id=\"error\">") + html_escape(message) + "</div>\n";
    b += "<p id=\"live-status\">live updates need script; without it, reload the page</p><div id=\"live\">" +
         live_fragment(*c.s->store, c.s->csrf, may_answer(*c.s)) + "</div><script src=\"/assets/live.js\"></script>";
    return {status, shell(c, "Live stations", b)};
  }

  // Server-sent events: the live fragment again whenever it changes (checked every 0.5 s), a comment
  // every 15 s to keep proxies from closing the stream, "end" when the session has ended. The stream
  // does not keep the session alive and is renewed after kStreamS (the browser reconnects).
  Page live_events(Ctx& c) {
    auto sess = c.s;
    const std::string token = c.token;
    struct State {
      std::string last;
      Clock::time_point start = Clock::now(), said = Clock::now();
    };
    auto state = std::make_shared<State>();
    c.res.set_header("X-Accel-Buffering", "no");
    c.res.set_chunked_content_provider("text/event-stream", [this, sess, token, state](std::size_t, httplib::DataSink& sink) {
      const auto send = [&](const std::string& text) { return sink.write(text.data(), text.size()); };
      if (!sessions_.find(token, false)) {
        send("event: end\ndata: session ended\n\n");
        sink.done();
        return true;
      }
      std::string frag;
      try {
        const std::lock_guard<std::mutex> l(sess->m);
        frag = live_fragment(*sess->store, sess->csrf, may_answer(*sess));
      } catch (const std::exception& e) {
        frag = "<div class=\"msg err\">the store could not be read: " + html_escape(e.what()) + "</div>";
      }
      const auto now = Clock::now();
      if (frag != state->last) {
        state->last = frag;
        std::string ev = "event: live\n";
        std::size_t a = 0;
        while (a <= frag.size()) {  // one data: line per line of the fragment
          const std::size_t e = frag.find('\n', a);
          ev += "data: " + frag.substr(a, e == std::string::npos ? std::string::npos : e - a) + "\n";
          if (e == std::string::npos) break;
          a = e + 1;
        }
        if (!send(ev + "\n")) return false;
        state->said = now;
      } else if (now - state->said > std::chrono::seconds(15)) {
        if (!send(": keep-alive\n\n")) return false;
        state->said = now;
      }
      if (now - state->start > std::chrono::duration<double>(kStreamS)) {
        sink.done();
        return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
      return sink.is_writable();
    });
    Page p;
    p.streamed = true;
    return p;
  }

  Page prompt_action(Ctx& c) {
    db::Store& st = *c.s->store;
    const std::int64_t id = std::stoll(c.m[1]);
    const bool confirm = c.m[2] == "confirm";
    if (!db::find_prompt(st, id)) return live_page(c, "no operator prompt " + std::to_string(id) + "; nothing was changed", false, 404);
    try {
      const db::Prompt p = db::answer_prompt(st, id, confirm, confirm ? std::string() : c.form["reason"]);
      return live_page(c, "prompt " + std::to_string(id) + " " + p.state + " by " + p.answered_by + ": " + p.text, true);
    } catch (const db::PermissionError& e) {
      return live_page(c, std::string("refused by the store: ") + e.what() + "; nothing was changed", false, 403);
    } catch (const InputError& e) {
      return live_page(c, std::string("refused: ") + e.what() + "; nothing was changed", false, 409);
    }
  }

  ServeOptions o_;
  bool postgres_ = false;
  Sessions sessions_;
  std::vector<Route> routes_;
};

}  // namespace

void serve(const ServeOptions& o) {
  const auto colon = o.listen.rfind(':');
  int port = -1;
  if (colon != std::string::npos && colon > 0) {
    try {
      std::size_t used = 0;
      port = std::stoi(o.listen.substr(colon + 1), &used);
      if (used != o.listen.size() - colon - 1) port = -1;
    } catch (const std::exception&) {
    }
  }
  if (port < 1 || port > 65535) throw InputError("--listen: '" + o.listen + "' is not ADDR:PORT (e.g. 127.0.0.1:8080)");
  const std::string host = o.listen.substr(0, colon);
  if (o.tls_cert.empty() != o.tls_key.empty()) throw InputError("--tls-cert and --tls-key go together");
  for (const auto* f : {&o.tls_cert, &o.tls_key})
    if (!f->empty() && !std::ifstream(*f)) throw InputError((f == &o.tls_cert ? "--tls-cert" : "--tls-key") + std::string(": cannot read '") + *f + "'");
  Console console(o);
  std::unique_ptr<httplib::Server> srv;
  if (!o.tls_cert.empty()) {
    auto s = std::make_unique<httplib::SSLServer>(o.tls_cert.c_str(), o.tls_key.c_str());
    if (!s->is_valid()) throw InputError("--tls-cert/--tls-key: '" + o.tls_cert + "' and '" + o.tls_key + "' are not a usable PEM certificate and key");
    srv = std::move(s);
  } else {
    srv = std::make_unique<httplib::Server>();
  }
  console.install(*srv);
  if (!srv->bind_to_port(host.c_str(), port))
    throw InputError("--listen: cannot listen on " + o.listen + " (address not local, or port in use)");
  std::cout << "calbench serve: console on " << (o.tls_cert.empty() ? "http" : "https") << "://" << o.listen << "/ (store "
            << db::redact_uri(o.db) << ")" << std::endl;
  srv->listen_after_bind();
}

}  // namespace calbench::console
