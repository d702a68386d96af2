#include "bench/console/server.hpp"

#include <sodium.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <functional>
#include <iostream>
#include <regex>
#include <sstream>
#include <vector>

#include "bench/approval_thresholds.hpp"
#include "bench/console/console_app.hpp"
#include "bench/console/live_page.hpp"
#include "bench/console/request_parse.hpp"
#include "bench/report/db_report.hpp"
#include "bench/report/html_parts.hpp"
#include "common/input_error.hpp"
#include "db/approval.hpp"
#include "db/signer.hpp"
#include "db/station_live.hpp"

// Last: httplib.h brings <resolv.h>, whose macro _res breaks Eigen's headers if they come after it.
#include "bench/console/http_server.hpp"

namespace calbench::console {
namespace {
using report::html_escape;
const char* kCookie = "calbench_session";

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
constexpr int kQueuePage = 50;         // sets per page of the QC queue
thread_local std::string t_log_login;  // the login of the request this thread answers (server log)

// What may go into a log line: printable ASCII without spaces, at most 64 characters.
std::string loggable(const std::string& s) {
  std::string out;
  for (const char ch : s.substr(0, 64)) out += (ch > 0x20 && ch < 0x7f) ? ch : '?';
  return out.empty() ? "-" : out;
}

}  // namespace

void set_log_login(const std::string& login) { t_log_login = login; }

Console::Console(const ServeOptions& o) : o_(o), sessions_(std::chrono::seconds(o.session_idle_s)) {
  postgres_ = db::is_postgres_uri(o.db);
  db::check_target(o.db);
  if (sodium_init() < 0) throw std::runtime_error("libsodium could not be initialised");
  randombytes_buf(csrf_key_, sizeof csrf_key_);
  if (postgres_) {
    pool_ = std::make_unique<PgPool>(o.db, static_cast<std::size_t>(o.db_connections), std::chrono::seconds(60),
                                     std::chrono::milliseconds(5000));
  } else {  // the store must exist and be migrated (a console does not create stores)
    db::Actor who = db::Actor::from_environment();
    who.source = "calbench serve";
    audit_st_ = std::make_unique<db::Store>(o.db, db::OpenOptions{}, who);
  }
}

void Console::install(httplib::Server& srv, bool tls) {
  tls_ = tls;
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
      {"GET", "/fleet", [this](Ctx& c) { return Page{200, shell(c, "Fleet", report::fleet_report_body(*c.st))}; }, true},
      {"GET", "/live/events", [this](Ctx& c) { return live_events(c); }, true},
      {"POST", R"(/prompt/(\d{1,18})/(confirm|reject))", [this](Ctx& c) { return prompt_action(c); }, true},
      {"GET", R"(/assets/([a-z]+\.(?:css|js)))", [this](Ctx& c) { return asset(c); }, false},
  };
  const auto handler = [this](const httplib::Request& req, httplib::Response& res) { dispatch(req, res); };
  srv.Get(R"(/.*)", handler);
  srv.Post(R"(/.*)", handler);
  srv.set_payload_max_length(64 * 1024);
  srv.set_logger([](const httplib::Request& req, const httplib::Response& res) {
    // Address, login, method, path, status: no query, body or header (passwords, session and CSRF
    // tokens never reach the log). The login is the session's, or the one a login form tried.
    // One write per line: threads do not interleave.
    std::cerr << ("calbench serve: " + loggable(req.remote_addr) + " " + loggable(t_log_login) + " " + req.method + " " +
                  req.path + " " + std::to_string(res.status) + "\n");
    t_log_login.clear();
  });
}

void Console::dispatch(const httplib::Request& req, httplib::Response& res) {
  Ctx c{req, res, {}, nullptr, {}, {}, {}, {}, nullptr, {}};
  t_log_login.clear();
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
    if (!r) p = {404, shell(c, "Not found", "<div class=\"msg err\" id=\"error\">no such page: " + html_escape(req.path) + "</div>")};
    else p = run_route(c, *r);
  } catch (const InputError& e) {
    p = {400, shell(c, "Bad request", "<div class=\"msg err\" id=\"error\">refused: " + html_escape(e.what()) + "; nothing was changed</div>")};
  } catch (const PoolBusy& e) {
    res.set_header("Retry-After", "5");
    p = {503, shell(c, "Busy", "<div class=\"msg err\" id=\"error\">" + html_escape(e.what()) + ": try again in a moment</div>")};
  } catch (const db::PermissionError& e) {
    if (c.s) refused(c, req.method + " " + req.path + ": " + e.what());
    p = {403, shell(c, "Refused", "<div class=\"msg err\" id=\"error\">" + html_escape(e.what()) + "</div>")};
  } catch (const db::ConnectionLost& e) {
    c.lease.broken();
    res.set_header("Retry-After", "5");
    p = {503, shell(c, "Busy", "<div class=\"msg err\" id=\"error\">the database is not answering (" + html_escape(e.what()) +
                                   "): try again in a moment</div>")};
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
  if (tls_) res.set_header("Strict-Transport-Security", "max-age=31536000");
}

// A route that needs a session: the session, its CSRF token on a POST, its account as it is now
// (open_checked), then the page, one request of the session at a time.
Page Console::run_route(Ctx& c, const Route& r) {
  if (!r.session) return r.fn(c);
  if (!(c.s = session(c))) {
    if (c.req.method == "POST") return login_page(c, "your session has ended (logged out or expired): log in again; nothing was changed", 401);
    return redirect(c, "/login");
  }
  t_log_login = c.s->login;
  if (c.req.method == "POST" && !same_token(c.form["csrf"], c.s->csrf))
    return {403, shell(c, "Refused", "<div class=\"msg err\" id=\"error\">refused: the form's CSRF token is missing or "
                                     "wrong (a form from another page or site?); nothing was changed</div>")};
  const std::lock_guard<std::mutex> l(c.s->m);
  if (const std::string why = open_checked(*c.s, c.st, c.lease); !why.empty()) {
    end_sessions(c.s->login, why, c.req.remote_addr, c.st);
    c.res.set_header("Set-Cookie", cookie(kCookie, "", true));
    return login_page(c, "your session has ended: " + why + "; log in again; nothing was changed", 401);
  }
  return r.fn(c);
}

std::shared_ptr<Session> Console::session(Ctx& c) {
  const auto it = c.cookies.find(kCookie);
  if (it == c.cookies.end()) return nullptr;
  c.token = it->second;
  return sessions_.find(it->second);
}

std::string Console::cookie(const std::string& name, const std::string& value, bool clear) const {
  return name + "=" + value + "; Path=/; HttpOnly; SameSite=Strict" + (tls_ ? "; Secure" : "") + (clear ? "; Max-Age=0" : "");
}

Page Console::redirect(Ctx& c, const std::string& to) {
  c.res.set_header("Location", to);
  return {303, ""};
}

db::Thresholds Console::thresholds(const db::CoefficientSetRecord& set) const {
  return approval_thresholds(o_.thresholds, o_.thresholds.empty() ? set.model : "");
}

std::string Console::shell(Ctx& c, const std::string& title, const std::string& body) {
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

Page Console::asset(Ctx& c) {
  const std::string name = c.m[1];
  if (name == "console.css") return {200, kConsoleCss, "text/css"};
  if (name == "report.css") return {200, report::report_css(), "text/css"};
  if (name == "live.js") return {200, live_js(), "text/javascript"};
  return {404, "/* no such asset */", "text/css"};
}

Page Console::queue(Ctx& c) {
  db::Store& st = *c.st;
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

Page Console::set_page(Ctx& c, const std::string& message, bool ok, int status) {
  db::Store& st = *c.st;
  const auto set = st.get_set(std::stoll(c.m[1]));
  std::ostringstream b;
  if (!message.empty())
    b << "<div class=\"msg " << (ok ? "ok\" id=\"done\">" : "err\" id=\"error\">") << html_escape(message) << "</div>\n";
  b << "<h1>Set " << set.id << " of " << html_escape(set.serial) << " (v" << set.version << ", " << db::source_label(set)
    << ", <span id=\"status\">" << db::to_string(set.status) << "</span>)</h1>\n";
  const std::string hidden = "<input type=\"hidden\" name=\"csrf\" value=\"" + c.s->csrf + "\">";
  // Only a QC account signs: the others see no button to be refused after (issue 56 item 13); the
  // store refuses a forged request all the same.
  const bool signer = c.s->role == "qc";
  if (!signer && set.status != db::SetStatus::revoked)
    b << "<p class=\"note\" id=\"no-sign\">approving and revoking are a QC account's: you are signed in as "
      << html_escape(c.s->role.empty() ? std::string("an account without a role") : "a " + c.s->role + " account") << "</p>\n";
  if (signer && set.status == db::SetStatus::draft)
    b << "<form class=\"act\" method=\"post\" action=\"/set/" << set.id << "/approve\">" << hidden
      << "<button id=\"approve\" type=\"submit\">approve set " << set.id << "</button> as " << html_escape(c.s->name) << "</form>\n";
  if (signer && set.status != db::SetStatus::revoked)
    b << "<form class=\"act\" method=\"post\" action=\"/set/" << set.id << "/revoke\">" << hidden
      << "<label>reason <input id=\"reason\" name=\"reason\" maxlength=\"4096\" size=\"40\" required></label> "
         "<button id=\"revoke\" type=\"submit\">revoke</button></form>\n";
  b << "<div class=\"report\" id=\"report\">" << report::device_report_body(st, set.serial, thresholds(set)) << "</div>";
  return {status, shell(c, "Set " + std::to_string(set.id), b.str())};
}

Page Console::set_action(Ctx& c) {
  db::Store& st = *c.st;
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
    refused(c, "set " + std::to_string(id) + " " + action + ": " + e.what());
    return set_page(c, std::string("refused by the store: ") + e.what(), false, 403);
  } catch (const InputError& e) {
    return set_page(c, std::string("refused: ") + e.what(), false, 400);
  }
}

Page Console::device_page(Ctx& c) {
  db::Store& st = *c.st;
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

Page Console::audit_page(Ctx& c) {
  db::Store& st = *c.st;
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

Page Console::live_page(Ctx& c, const std::string& message, bool ok, int status) {
  std::string b = "<h1>Live stations</h1>";
  if (!message.empty())
    b += std::string("<div class=\"msg ") + (ok ? "ok\" id=\"done\">" : "err\" id=\"error\">") + html_escape(message) + "</div>\n";
  b += "<p id=\"live-status\">live updates need script; without it, reload the page</p><div id=\"live\">" +
       live_fragment(*c.st, c.s->csrf, may_answer(*c.s)) + "</div><script src=\"/assets/live.js\"></script>";
  return {status, shell(c, "Live stations", b)};
}

Page Console::prompt_action(Ctx& c) {
  db::Store& st = *c.st;
  const std::int64_t id = std::stoll(c.m[1]);
  const bool confirm = c.m[2] == "confirm";
  if (!db::find_prompt(st, id)) return live_page(c, "no operator prompt " + std::to_string(id) + "; nothing was changed", false, 404);
  try {
    const db::Prompt p = db::answer_prompt(st, id, confirm, confirm ? std::string() : c.form["reason"]);
    return live_page(c, "prompt " + std::to_string(id) + " " + p.state + " by " + p.answered_by + ": " + p.text, true);
  } catch (const db::PermissionError& e) {
    refused(c, "prompt " + std::to_string(id) + (confirm ? " confirm: " : " reject: ") + e.what());
    return live_page(c, std::string("refused by the store: ") + e.what() + "; nothing was changed", false, 403);
  } catch (const InputError& e) {
    return live_page(c, std::string("refused: ") + e.what() + "; nothing was changed", false, 409);
  }
}

namespace {

// A TLS server context from the PEM files (TLS 1.2 or newer), or InputError.
SSL_CTX* tls_context(const std::string& cert, const std::string& key) {
  SSL_CTX* ctx = SSL_CTX_new(TLS_server_method());
  const bool ok = ctx && SSL_CTX_set_min_proto_version(ctx, TLS1_2_VERSION) == 1 &&
                  SSL_CTX_use_certificate_chain_file(ctx, cert.c_str()) == 1 &&
                  SSL_CTX_use_PrivateKey_file(ctx, key.c_str(), SSL_FILETYPE_PEM) == 1 && SSL_CTX_check_private_key(ctx) == 1;
  if (!ok) {
    if (ctx) SSL_CTX_free(ctx);
    throw InputError("--tls-cert/--tls-key: '" + cert + "' and '" + key + "' are not a usable PEM certificate and key");
  }
  SSL_CTX_set_mode(ctx, SSL_MODE_ENABLE_PARTIAL_WRITE | SSL_MODE_ACCEPT_MOVING_WRITE_BUFFER);
  return ctx;
}

// Each connection is a file descriptor: room for --max-connections of them beside the stores.
void raise_open_files(int connections) {
  rlimit r{};
  if (getrlimit(RLIMIT_NOFILE, &r) != 0) return;
  const rlim_t want = static_cast<rlim_t>(connections) * 2 + 256;
  if (r.rlim_cur < want) {
    r.rlim_cur = std::min(want, r.rlim_max);
    setrlimit(RLIMIT_NOFILE, &r);
  }
}

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
  SSL_CTX* tls = o.tls_cert.empty() ? nullptr : tls_context(o.tls_cert, o.tls_key);
  HttpLimits limits;
  limits.max_connections = static_cast<std::size_t>(o.max_connections);
  limits.per_address = std::max<std::size_t>(1, limits.max_connections / 2);
  auto srv = std::make_unique<ConsoleHttpServer>(limits, tls);
  Console console(o);
  console.install(*srv, tls != nullptr);
  raise_open_files(o.max_connections);
  if (!srv->bind(host, port))
    throw InputError("--listen: cannot listen on " + o.listen + " (address not local, or port in use)");
  std::cout << "calbench serve: console on " << (o.tls_cert.empty() ? "http" : "https") << "://" << o.listen << "/ (store "
            << db::redact_uri(o.db) << ")" << std::endl;
  srv->listen_after_bind();
}

}  // namespace calbench::console
