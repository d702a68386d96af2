#include "db/postgres/pg_connection.hpp"

#include <libpq-fe.h>

#include <algorithm>
#include <charconv>
#include <iterator>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "common/input_error.hpp"

namespace calbench::db {

namespace {
constexpr Oid kBoolOid = 16, kTimestamptzOid = 1184, kTimestampOid = 1114;

// One line: libpq's messages end in a newline and may continue on tab-indented lines ("…refused\n\t
// Is the server running…" becomes "…refused; Is the server running…").
std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  for (std::size_t p = s.find("\n\t"); p != std::string::npos; p = s.find("\n\t", p)) s.replace(p, 2, "; ");
  for (char& c : s)
    if (c == '\n' || c == '\t') c = ' ';
  std::string out;
  for (char c : s)
    if (!(c == ' ' && !out.empty() && out.back() == ' ')) out += c;
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out;
}

// "2026-11-23 18:21:13.12345+00" → "2026-11-23T18:21:13.123Z"
std::string iso_utc(std::string_view v) {
  if (v.size() < 19) return std::string(v);
  std::string out(v.substr(0, 19));
  out[10] = 'T';
  std::string frac = "000";
  if (v.size() > 20 && v[19] == '.') {
    std::size_t i = 20, k = 0;
    while (i < v.size() && v[i] >= '0' && v[i] <= '9') {
      if (k < 3) frac[k++] = v[i];
      ++i;
    }
  }
  return out + "." + frac + "Z";
}

class PgStatement : public StatementImpl {
 public:
  PgStatement(PgConnection& c, std::string_view sql) : c_(c) {
    int n = 0;
    sql_ = pg_numbered_parameters(sql, &n);
    params_.resize(static_cast<std::size_t>(n));
  }
  ~PgStatement() override { clear(); }
  void bind_int64(int i, std::int64_t v) override { slot(i) = std::to_string(v); }
  void bind_double(int i, double v) override {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest text that reads back exactly
    slot(i) = std::string(buf, r.ptr);
  }
  void bind_text(int i, std::string_view v) override { slot(i) = std::string(v); }
  void bind_null(int i) override { slot(i).reset(); }
  bool step() override {
    if (!res_) {
      std::vector<const char*> values(params_.size());
      for (std::size_t k = 0; k < params_.size(); ++k) values[k] = params_[k] ? params_[k]->c_str() : nullptr;
      res_ = PQexecParams(c_.handle(), sql_.c_str(), static_cast<int>(values.size()), nullptr, values.data(), nullptr,
                          nullptr, 0);
      const ExecStatusType st = res_ ? PQresultStatus(res_) : PGRES_FATAL_ERROR;
      if (st != PGRES_TUPLES_OK && st != PGRES_COMMAND_OK) {
        PGresult* r = res_;
        res_ = nullptr;
        try {
          c_.throw_result(r, "SQL");
        } catch (...) {
          PQclear(r);
          throw;
        }
      }
      row_ = -1;
    }
    ++row_;
    return row_ < PQntuples(res_);
  }
  void reset() override {
    clear();
    for (auto& p : params_) p.reset();
  }
  bool is_null(int col) const override { return PQgetisnull(res_, row_, col) != 0; }
  std::int64_t int64(int col) const override {
    const char* v = PQgetvalue(res_, row_, col);
    if (PQftype(res_, col) == kBoolOid) return v[0] == 't' ? 1 : 0;
    return std::strtoll(v, nullptr, 10);
  }
  double real(int col) const override { return std::strtod(PQgetvalue(res_, row_, col), nullptr); }
  std::string text(int col) const override {
    if (PQgetisnull(res_, row_, col)) return {};
    const char* v = PQgetvalue(res_, row_, col);
    const Oid t = PQftype(res_, col);
    if (t == kTimestamptzOid || t == kTimestampOid) return iso_utc(v);
    if (t == kBoolOid) return v[0] == 't' ? "1" : "0";
    return std::string(v, static_cast<std::size_t>(PQgetlength(res_, row_, col)));
  }

 private:
  std::optional<std::string>& slot(int i) {
    if (i < 1 || i > static_cast<int>(params_.size()))
      throw DbError(0, "bind: parameter " + std::to_string(i) + " of " + std::to_string(params_.size()));
    if (res_) clear();
    return params_[static_cast<std::size_t>(i - 1)];
  }
  void clear() {
    if (res_) PQclear(res_);
    res_ = nullptr;
    row_ = -1;
  }
  PgConnection& c_;
  std::string sql_;
  std::vector<std::optional<std::string>> params_;
  PGresult* res_ = nullptr;
  int row_ = -1;
};
}  // namespace

std::string pg_numbered_parameters(std::string_view sql, int* count) {
  std::string out;
  out.reserve(sql.size() + 16);
  int n = 0;
  char quote = 0;
  for (char ch : sql) {
    if (quote) {
      if (ch == quote) quote = 0;
      out += ch;
    } else if (ch == '\'' || ch == '"') {
      quote = ch;
      out += ch;
    } else if (ch == '?') {
      out += "$" + std::to_string(++n);
    } else {
      out += ch;
    }
  }
  if (count) *count = n;
  return out;
}

void check_target(const std::string& target) {
  if (!is_postgres_uri(target)) return;
  char* err = nullptr;
  PQconninfoOption* o = PQconninfoParse(target.c_str(), &err);
  if (!o) {
    std::string why = err ? trim(err) : "not a valid PostgreSQL URI";
    PQfreemem(err);
    // libpq quotes the offending part, which may be the password: never echo it.
    const auto scheme = target.find("://") + 3;
    const auto at = target.find('@', scheme), colon = target.find(':', scheme);
    if (at != std::string::npos && colon < at && at > colon + 1) {
      const std::string pw = target.substr(colon + 1, at - colon - 1);
      for (auto p = why.find(pw); p != std::string::npos; p = why.find(pw)) why.replace(p, pw.size(), "***");
    }
    if (why.find("password") != std::string::npos) why = "invalid password part";
    throw InputError(redact_uri(target), 0, "", "not a valid PostgreSQL URI (" + why +
                                                   "); expected postgresql://USER@HOST[:PORT]/DATABASE[?sslmode=…]");
  }
  // Values libpq checks only when it connects: checked here, so that a typo is bad input (exit 2)
  // and not an unreachable server.
  std::string bad;
  // No database: libpq would take the user's name for it, and the server's answer ("refused the
  // credentials", or no such database) would hide that the URI lacks a part.
  bool has_db = false;
  for (PQconninfoOption* p = o; p->keyword; ++p)
    if (std::string(p->keyword) == "dbname" && p->val && *p->val) has_db = true;
  if (!has_db) bad = "no database named (the path after HOST[:PORT]/ is empty)";
  for (PQconninfoOption* p = o; p->keyword && bad.empty(); ++p) {
    if (!p->val) continue;
    const std::string k = p->keyword, v = p->val;
    if (k == "port" || k == "connect_timeout") {
      std::string part;
      for (std::size_t i = 0; i <= v.size() && bad.empty(); ++i) {
        if (i == v.size() || (k == "port" && v[i] == ',')) {
          const bool digits = !part.empty() && part.find_first_not_of("0123456789") == std::string::npos;
          if (!digits || (k == "port" && (part.size() > 5 || std::stoi(part) < 1 || std::stoi(part) > 65535)))
            bad = k + " '" + part + "' is not " + (k == "port" ? "a port number (1-65535)" : "a whole number of seconds");
          part.clear();
        } else {
          part += v[i];
        }
      }
    } else if (k == "sslmode") {
      const char* modes[] = {"disable", "allow", "prefer", "require", "verify-ca", "verify-full"};
      if (std::find(std::begin(modes), std::end(modes), v) == std::end(modes))
        bad = "sslmode '" + v + "' is not one of disable, allow, prefer, require, verify-ca, verify-full";
    }
    if (!bad.empty()) break;
  }
  PQconninfoFree(o);
  if (!bad.empty())
    throw InputError(redact_uri(target), 0, "", "not a valid PostgreSQL URI: " + bad +
                                                   " (expected postgresql://USER@HOST[:PORT]/DATABASE[?sslmode=…])");
}

PgConnection::PgConnection(const std::string& uri, const OpenOptions& opt) : Connection(redact_uri(uri), opt), uri_(uri) {
  check_target(uri);
  connect();
}

PgConnection::~PgConnection() {
  if (conn_) PQfinish(conn_);
}

void PgConnection::connect() {
  if (conn_) PQfinish(conn_);
  // Defaults first: the URI's own parameters (expanded from dbname) override them.
  const char* keys[] = {"connect_timeout", "application_name", "dbname", nullptr};
  const char* vals[] = {"10", "calbench", uri_.c_str(), nullptr};
  conn_ = PQconnectdbParams(keys, vals, 1);
  if (!conn_ || PQstatus(conn_) != CONNECTION_OK) {
    std::string why = conn_ ? trim(PQerrorMessage(conn_)) : "out of memory";
    const bool auth = why.find("password authentication failed") != std::string::npos ||
                      why.find("no password supplied") != std::string::npos ||
                      why.find("authentication failed") != std::string::npos;
    if (conn_) PQfinish(conn_);
    conn_ = nullptr;
    if (auth) {
      const bool none = why.find("no password supplied") != std::string::npos;
      throw PermissionError(0, path_ + ": the server refused the credentials (" + why + "; " +
                                   (none ? "no password found: a PGPASSFILE or ~/.pgpass line must match "
                                           "HOST:PORT:DATABASE:USER of the URI (* matches any), or set PGPASSWORD"
                                         : "the password comes from PGPASSFILE, ~/.pgpass or PGPASSWORD") + ")",
                            "28P01");
    }
    if (why.find("does not exist") != std::string::npos) throw DbError(0, path_ + ": " + why, "3D000");
    throw ConnectionLost(0, path_ + ": cannot reach the database server (" + why + ")", "08001");
  }
  // The server's notices and warnings (e.g. "no privileges could be revoked" while roles.sql runs as
  // a role that may not) are not the user's business: errors say what matters.
  PQsetNoticeProcessor(conn_, [](void*, const char*) {}, nullptr);
  // Timestamps in UTC (written and read back as ISO 8601 with Z); messages only when they matter.
  exec("SET TimeZone = 'UTC'; SET DateStyle = 'ISO'; SET client_min_messages = warning");
  PGresult* r = PQexec(conn_, "SELECT session_user");
  if (PQresultStatus(r) == PGRES_TUPLES_OK && PQntuples(r) == 1) role_ = PQgetvalue(r, 0, 0);
  PQclear(r);
}

void PgConnection::reconnect() { connect(); }

void PgConnection::throw_result(PGresult* r, std::string_view context) {
  const char* ss = r ? PQresultErrorField(r, PG_DIAG_SQLSTATE) : nullptr;
  const std::string state = ss ? ss : "";
  // The primary message only (DETAIL and CONTEXT lines follow it), without its severity.
  std::string msg = r ? PQresultErrorMessage(r) : PQerrorMessage(conn_);
  if (const auto nl = msg.find('\n'); nl != std::string::npos && nl > 0) msg = msg.substr(0, nl);
  msg = trim(msg);
  for (const char* sev : {"ERROR: ", "FATAL: "})
    if (msg.rfind(sev, 0) == 0) msg = msg.substr(std::strlen(sev));
  const std::string what = path_ + ": " + std::string(context) + ": " + msg;
  if (PQstatus(conn_) != CONNECTION_OK || state.rfind("08", 0) == 0 || state == "57P01" || state == "57P02" ||
      state == "57P03")
    throw ConnectionLost(0, path_ + ": lost the connection to the database server (" + msg + ")", state.empty() ? "08006" : state);
  if (state == "40001" || state == "40P01" || state == "55P03") throw BusyError(0, what, state);
  if (state == "42501")
    throw PermissionError(0, path_ + ": the database refused this to role '" + role_ + "': " + msg +
                                 " (who may do what: docs/database.md, \"Roles\")", state);
  throw DbError(0, what, state);
}

Statement PgConnection::prepare(std::string_view sql) { return Statement(std::make_unique<PgStatement>(*this, sql)); }

void PgConnection::exec(const char* sql) {
  PGresult* r = PQexec(conn_, sql);
  const ExecStatusType st = r ? PQresultStatus(r) : PGRES_FATAL_ERROR;
  if (st != PGRES_COMMAND_OK && st != PGRES_TUPLES_OK) {
    try {
      throw_result(r, "SQL");
    } catch (...) {
      PQclear(r);
      throw;
    }
  }
  PQclear(r);
}

void PgConnection::begin(bool write) {
  exec(write ? "BEGIN ISOLATION LEVEL SERIALIZABLE" : "BEGIN ISOLATION LEVEL REPEATABLE READ READ ONLY");
}
void PgConnection::commit() { exec("COMMIT"); }
void PgConnection::rollback() noexcept {
  if (conn_ && PQstatus(conn_) == CONNECTION_OK && PQtransactionStatus(conn_) != PQTRANS_IDLE) {
    PGresult* r = PQexec(conn_, "ROLLBACK");
    PQclear(r);
  }
}

}  // namespace calbench::db
