// The console's log-in, log-out, per-request check of the account and security audit (issue 54
// items 7, 8, 9, 11). docs/console.md "Security behaviour".
#include <sodium.h>

#include <chrono>
#include <iostream>

#include "bench/console/console_app.hpp"
#include "bench/report/html_parts.hpp"
#include "common/input_error.hpp"
#include "db/console_accounts.hpp"

// Last: httplib.h brings <resolv.h>, whose macro _res breaks Eigen's headers if they come after it.
#include <httplib.h>

namespace calbench::console {
namespace {
using report::html_escape;
const char* kCookie = "calbench_session";
const char* kPreCookie = "calbench_login";  // the login form's cookie, before a session
constexpr long long kLoginFormS = 2 * 3600;  // a login form's token is good this long

long long unix_now() {
  return std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// The PostgreSQL server's own words from libpq's message ("FATAL: …"), without the command line's
// advice on where a password comes from, which does not apply to a form.
std::string server_words(std::string why) {
  const auto fatal = why.find("FATAL:");
  if (fatal != std::string::npos) {
    why = why.substr(fatal + 6);
    why = why.substr(0, why.find_first_of(";)\n"));
    while (!why.empty() && why.front() == ' ') why.erase(0, 1);
  }
  return why;
}

bool is_auth_failure(const db::DbError& e) { return e.sqlstate() == "28P01" || e.sqlstate() == "28000"; }
}  // namespace

// The login form's token: an HMAC (key per server start) of the form's cookie and the time the form
// was made, so a token is good only with the cookie it was given with, and for kLoginFormS.
std::string Console::login_csrf(const std::string& pre) const {
  const std::string t = std::to_string(unix_now());
  const std::string msg = "calbench-login|" + pre + "|" + t;
  unsigned char mac[crypto_auth_hmacsha256_BYTES];
  crypto_auth_hmacsha256(mac, reinterpret_cast<const unsigned char*>(msg.data()), msg.size(), csrf_key_);
  char hex[2 * sizeof mac + 1];
  sodium_bin2hex(hex, sizeof hex, mac, sizeof mac);
  return t + "." + hex;
}

bool Console::login_csrf_ok(const std::string& pre, const std::string& token) const {
  const auto dot = token.find('.');
  if (pre.empty() || dot == std::string::npos || dot == 0 || dot > 12) return false;
  const std::string t = token.substr(0, dot);
  if (t.find_first_not_of("0123456789") != std::string::npos) return false;
  const long long age = unix_now() - std::stoll(t);
  if (age < -60 || age > kLoginFormS) return false;
  const std::string msg = "calbench-login|" + pre + "|" + t;
  const std::string mac = token.substr(dot + 1);
  if (mac.size() != 2 * crypto_auth_hmacsha256_BYTES) return false;
  unsigned char bin[crypto_auth_hmacsha256_BYTES];
  if (sodium_hex2bin(bin, sizeof bin, mac.data(), mac.size(), nullptr, nullptr, nullptr) != 0) return false;
  return crypto_auth_hmacsha256_verify(bin, reinterpret_cast<const unsigned char*>(msg.data()), msg.size(), csrf_key_) == 0;
}

Page Console::login_page(Ctx& c, const std::string& error, int status) {
  const std::string pre = random_token();
  c.res.set_header("Set-Cookie", cookie(kPreCookie, pre));
  std::string b = "<h1>Log in</h1>";
  if (!error.empty()) b += "<div class=\"msg err\" id=\"error\">" + html_escape(error) + "</div>";
  b += std::string("<p class=\"note\">") +
       (postgres_ ? "Your PostgreSQL login and password: every page runs as that database role."
                  : "Your console account (calbench db user add on this SQLite store).") +
       "</p><form method=\"post\" action=\"/login\"><input type=\"hidden\" name=\"csrf\" value=\"" + login_csrf(pre) +
       "\"><p><label>login <input id=\"login\" name=\"login\" autocomplete=\"username\" maxlength=\"64\"></label></p>"
       "<p><label>password <input id=\"password\" name=\"password\" type=\"password\" autocomplete=\"current-password\"></label></p>"
       "<p><button id=\"submit\" type=\"submit\">log in</button></p></form>";
  c.s = nullptr;
  return {status, shell(c, "Log in", b)};
}

db::Actor Console::actor(const std::string& login, const std::string& name) const {
  db::Actor who = db::Actor::from_environment();
  who.source = "console login " + login;
  who.user = name;
  return who;
}

std::shared_ptr<Session> Console::login_sqlite(const std::string& login, const std::string& password) {
  auto store = std::make_unique<db::Store>(o_.db, db::OpenOptions{}, actor(login, login));
  const auto acct = db::check_console_password(*store, login, password);
  if (!acct) return nullptr;
  store->set_actor(actor(acct->login, acct->name));
  store->set_console_account(acct->login, acct->role);
  auto s = std::make_shared<Session>();
  s->store = std::move(store);
  s->login = acct->login, s->name = acct->name, s->role = acct->role, s->credential = acct->credential;
  return s;
}

// Opens a new pooled connection with the credentials (the password check); throws the connect's
// DbError (SQLSTATE 28P01/28000: refused credentials) or PoolBusy.
std::shared_ptr<Session> Console::login_pg(const std::string& login, const std::string& password) {
  auto lease = pool_->acquire(login, password, actor(login, login), true);
  auto s = std::make_shared<Session>();
  s->login = login, s->name = login;
  auto st = lease.store().connection().prepare("SELECT name, role FROM calbench_users WHERE login = session_user");
  if (st.step()) s->name = st.text(0), s->role = st.text(1);
  s->password = std::make_unique<Secret>(password);
  return s;
}

Page Console::login_post(Ctx& c) {
  const auto pre = c.cookies.find(kPreCookie);
  if (pre == c.cookies.end() || !login_csrf_ok(pre->second, c.form["csrf"]))
    return login_page(c, "refused: the login form's token is missing, wrong or too old; reload the page and try again", 403);
  const std::string login = c.form["login"], password = c.form["password"];
  set_log_login(login);
  if (login.empty() || login.size() > 64) return login_page(c, "give your login (1 to 64 characters)", 400);
  const std::string addr = c.req.remote_addr;
  if (const std::string why = guard_.begin(login, addr); !why.empty()) return login_page(c, why, 429);
  auto outcome = LoginGuard::Outcome::no_verdict;
  std::shared_ptr<Session> s;
  std::string why = "wrong login or password";
  try {
    s = postgres_ ? login_pg(login, password) : login_sqlite(login, password);
    outcome = s ? LoginGuard::Outcome::success : LoginGuard::Outcome::failure;
  } catch (const db::DbError& e) {
    // Only the server's refusal of the credentials is a failed login; anything else (too many
    // connections, the server down, a missing database) is the server's trouble, not a guess.
    if (postgres_ && is_auth_failure(e)) outcome = LoginGuard::Outcome::failure;
    why = postgres_ && is_auth_failure(e) ? "the database refused the login: " + server_words(e.what()) : e.what();
  } catch (const PoolBusy& e) {
    why = e.what();
  }
  set_log_login(login);  // (the store's messages above may have logged nothing; the line is ours)
  const auto settled = guard_.finish(login, addr, outcome);
  if (outcome == LoginGuard::Outcome::no_verdict) {
    std::cerr << ("calbench serve: " + addr + " login attempt not checked (server error): " + why + "\n");
    c.res.set_header("Retry-After", "5");
    return login_page(c, "the store could not check the login (" + why + "); try again in a moment: this did not count "
                         "as a failed login", 503);
  }
  if (outcome == LoginGuard::Outcome::failure) {
    // Never echo the password (libpq messages do not contain it; the URI is redacted by the store).
    if (!password.empty())
      for (std::size_t p; (p = why.find(password)) != std::string::npos;) why.replace(p, password.size(), "***");
    security_event("login-failed", login, "from " + addr, nullptr);
    if (settled.locked_now) security_event("lockout", login, "locked for 15 min after 5 failed logins (last from " + addr + ")", nullptr);
    if (settled.address_blocked_now) security_event("lockout", "", "address " + addr + ": too many failed logins, refused for 15 min", nullptr);
    return login_page(c, why, 401);
  }
  const std::string token = sessions_.add(s);
  c.res.set_header("Set-Cookie", cookie(kCookie, token));
  return redirect(c, "/queue");
}

Page Console::logout(Ctx& c) {
  sessions_.remove(c.token);
  c.res.set_header("Set-Cookie", cookie(kCookie, "", true));
  c.s = nullptr;
  return login_page(c, "");
}

std::string Console::open_checked(Session& s, db::Store*& st, PgPool::Lease& lease) {
  if (!postgres_) {
    st = s.store.get();
    const auto acct = db::find_console_account(*st, s.login);
    if (!acct) return "the account '" + s.login + "' was removed";
    if (acct->role != s.role) return "the account's role was changed (" + s.role + " to " + acct->role + ")";
    if (acct->credential != s.credential) return "the account's password was changed";
    return "";
  }
  try {
    lease = pool_->acquire(s.login, s.password->view(), actor(s.login, s.name), false);
  } catch (const db::DbError& e) {
    if (is_auth_failure(e)) return "the database no longer accepts your password";
    throw;
  }
  st = &lease.store();
  // The login's person and role now, and whether the login is still in its role's group.
  auto q = st->connection().prepare(
      "SELECT name, role, CASE WHEN EXISTS (SELECT 1 FROM pg_roles WHERE rolname = 'calbench_' || role) "
      "THEN pg_has_role(session_user, 'calbench_' || role, 'MEMBER') ELSE false END FROM calbench_users WHERE login = session_user");
  if (!q.step()) return s.role.empty() ? "" : "the login is no longer mapped to a person (db user add)";
  if (q.text(1) != s.role) return "the login's role was changed (" + (s.role.empty() ? "none" : s.role) + " to " + q.text(1) + ")";
  if (q.int64(2) == 0) return "the login is no longer a member of calbench_" + s.role;
  s.name = q.text(0);
  return "";
}

void Console::end_sessions(const std::string& login, const std::string& why, const std::string& address, db::Store* st) {
  const int n = sessions_.remove_login(login);
  security_event("refused", login, "session ended (" + std::to_string(n) + " of this login): " + why + "; from " + address, st);
}

void Console::refused(Ctx& c, const std::string& what) {
  security_event("refused", c.s ? c.s->login : "", what + "; from " + c.req.remote_addr, c.st);
}

void Console::security_event(const std::string& action, const std::string& login, const std::string& detail, db::Store* st) {
  // The server's log in any case (with the login, never a password).
  std::string shown;
  for (const char ch : login.substr(0, 64)) shown += (ch > 0x20 && ch < 0x7f) ? ch : '?';
  std::cerr << ("calbench serve: security " + action + " login " + (shown.empty() ? "-" : shown) + ": " + detail + "\n");
  try {
    if (!postgres_) {
      const std::lock_guard<std::mutex> l(audit_m_);
      audit_st_->audit_security(action, login, detail);
    } else if (st) {  // a failed PostgreSQL login has no connection: the server's log (and PostgreSQL's own)
      st->audit_security(action, login, detail);
    }
  } catch (const std::exception& e) {
    std::cerr << ("calbench serve: could not audit the " + action + " of '" + shown + "': " + e.what() + "\n");
  }
}

}  // namespace calbench::console
