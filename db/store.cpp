// The store: names of statuses and sources, who acts (Actor), opening a database and migrating its
// schema. The writes, status changes and reads are in store_sets.cpp, store_status.cpp and
// store_reads.cpp.
#include "db/store.hpp"

#include <pwd.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>

#include <nlohmann/json.hpp>

#include "common/input_error.hpp"
#include "common/utf8.hpp"
#include "db/input_errors.hpp"
#include "db/audit_chain.hpp"
#include "db/signer.hpp"
#include "db/postgres/pg_connection.hpp"
#include "db/postgres/pg_schema.hpp"
#include "db/schema.hpp"

namespace calbench::db {

std::string to_string(SetSource s) {
  switch (s) {
    case SetSource::bench: return "bench";
    case SetSource::in_motion: return "in-motion";
    case SetSource::combined: return "combined";
  }
  return "?";
}
std::string fit_kind(const CoefficientSetRecord& s) {
  if (s.source != SetSource::bench) return "";
  const nlohmann::json j = nlohmann::json::parse(s.payload_json, nullptr, false);
  if (j.is_object() && j.contains("source") && j["source"].is_object() && j["source"].value("kind", "") == "multipos")
    return "multipos";
  return "";
}

std::string source_label(const CoefficientSetRecord& s) {
  const std::string k = fit_kind(s);
  return to_string(s.source) + (k.empty() ? "" : " (" + k + ")");
}

std::string to_string(SetStatus s) {
  switch (s) {
    case SetStatus::draft: return "draft";
    case SetStatus::approved: return "approved";
    case SetStatus::provisioned: return "provisioned";
    case SetStatus::revoked: return "revoked";
  }
  return "?";
}
SetSource source_from_string(const std::string& s) {
  if (s == "bench") return SetSource::bench;
  if (s == "in-motion") return SetSource::in_motion;
  if (s == "combined") return SetSource::combined;
  throw InputError("unknown coefficient-set source '" + s + "' (bench, in-motion, combined)");
}
SetStatus status_from_string(const std::string& s) {
  if (s == "draft") return SetStatus::draft;
  if (s == "approved") return SetStatus::approved;
  if (s == "provisioned") return SetStatus::provisioned;
  if (s == "revoked") return SetStatus::revoked;
  throw InputError("unknown status '" + s + "' (draft, approved, provisioned, revoked)");
}

std::string operator_name_problem(const std::string& name) {
  const std::string n = "operator name '" + name + "' ";
  if (name.empty() || name.size() > 64) return n + "must be 1 to 64 characters";
  if (name.find('@') != std::string::npos) return n + "must not contain '@' (the station is recorded beside it)";
  // Names are compared to tell people apart (four-eyes), so nothing may make two names look alike
  // and differ: invisible characters and invalid UTF-8 are refused, Unicode spaces count as spaces
  // (normalized_name), and one word must not mix Latin, Greek and Cyrillic letters (the UTS #39
  // mixed-script rule: "Tеss" with a Cyrillic е).
  bool printable = false;
  utf8::Script word_script = utf8::Script::none;
  std::size_t word_start = 0;
  bool edge_space = false;  // the first or the last character is a space (ASCII or Unicode)
  for (std::size_t i = 0; i < name.size();) {
    unsigned cp = 0;
    const std::size_t len = utf8::decode(name, i, cp);
    if (len == 0) return n + "is not valid UTF-8 (byte " + std::to_string(i + 1) + ")";
    if (cp < 0x20 || cp == 0x7f) return n + "contains control characters (" + utf8::code_point_name(cp) + ")";
    if (utf8::invisible(cp))
      return n + "contains the invisible or format character " + utf8::code_point_name(cp) + " (type the name plainly)";
    const bool space = cp == ' ' || utf8::space_like(cp);
    if (space && (i == 0 || i + len == name.size())) edge_space = true;
    if (space) {
      word_script = utf8::Script::none, word_start = i + len;
    } else {
      printable = true;
      const utf8::Script s = utf8::script_of(cp);
      if (s != utf8::Script::none && word_script != utf8::Script::none && s != word_script) {
        std::size_t end = name.find(' ', i);
        return n + "mixes " + utf8::script_name(word_script) + " and " + utf8::script_name(s) + " letters in the word '" +
               name.substr(word_start, end == std::string::npos ? std::string::npos : end - word_start) + "' (" +
               utf8::code_point_name(cp) + "): one script per word";
      }
      if (s != utf8::Script::none) word_script = s;
    }
    i += len;
  }
  if (!printable || edge_space)
    return n + "must not be blank or start or end with a space";
  return {};
}

void check_operator_name(const std::string& name, const std::string& where) {
  if (const std::string p = operator_name_problem(name); !p.empty()) throw arg_error(where, p);
}

Actor Actor::from_environment(const std::string& operator_option) {
  Actor a;
  auto env = [](const char* k) -> std::string {
    const char* v = std::getenv(k);
    return v ? v : "";
  };
  if (!operator_option.empty()) {
    check_operator_name(operator_option, "--operator");
    a.user = operator_option, a.source = "--operator";
  } else if (const std::string o = env("CALBENCH_OPERATOR"); !o.empty()) {
    check_operator_name(o, "CALBENCH_OPERATOR");
    a.user = o, a.source = "CALBENCH_OPERATOR";
  } else if (const std::string u = env("CALBENCH_USER"); !u.empty()) {
    check_operator_name(u, "CALBENCH_USER");
    a.user = u, a.source = "CALBENCH_USER";
  }
  {
    const passwd* pw = ::getpwuid(::geteuid());
    const std::string os = pw && pw->pw_name && *pw->pw_name ? pw->pw_name : env("USER");
    a.os_user = os.empty() ? "unknown" : os;
  }
  if (a.user.empty()) a.user = a.os_user, a.source = "OS user";
  const std::string s = env("CALBENCH_STATION");
  if (!s.empty()) {
    a.station = s;
  } else {
    char host[256] = {};
    a.station = ::gethostname(host, sizeof host - 1) == 0 && host[0] ? host : "unknown";
  }
  return a;
}

std::string new_uid() {
  // Seeded per process: a process forked after a draw (a station's writer workers) would otherwise
  // go on with its parent's generator state and draw the same uids, and one run would be taken for
  // another's already-forwarded copy.
  static thread_local std::mt19937_64 rng;
  static thread_local pid_t seeded_for = 0;
  if (seeded_for != ::getpid()) {
    seeded_for = ::getpid();
    rng.seed(std::random_device{}() ^ (static_cast<std::uint64_t>(seeded_for) << 32) ^
             static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count()));
  }
  char buf[33];
  std::snprintf(buf, sizeof buf, "%016llx%016llx", static_cast<unsigned long long>(rng()),
                static_cast<unsigned long long>(rng()));
  return buf;
}

std::string Store::default_path() {
  const char* p = std::getenv("CALBENCH_DB");
  return (p && *p) ? p : "calbench.db";
}

Store::Store(const std::string& path, const OpenOptions& opt, Actor actor)
    : conn_(open_connection(path, opt)), actor_(std::move(actor)) {
  if (opt.read_only) {
    const int v = schema_version();
    if (v != kSchemaVersion)
      throw DbError(1, path + ": database schema version " + std::to_string(v) + ", this calbench needs " +
                           std::to_string(kSchemaVersion) + " (open it once read-write to migrate)");
  } else {
    migrate();
  }
}

namespace {
// Serialises schema and role changes between processes (a PostgreSQL session advisory lock).
struct PgSchemaLock {
  Connection& c;
  explicit PgSchemaLock(Connection& conn) : c(conn) { c.exec("SELECT pg_advisory_lock(7203518)"); }
  ~PgSchemaLock() {
    try {
      c.exec("SELECT pg_advisory_unlock(7203518)");
    } catch (...) {  // the session ends with the connection: the lock goes with it
    }
  }
};
}  // namespace

int Store::schema_version() {
  if (conn_->dialect() == Dialect::postgres) {
    auto t = conn_->prepare("SELECT to_regclass('schema_version') IS NOT NULL");
    t.step();
    if (t.int64(0) == 0) return 0;
    auto st = conn_->prepare("SELECT COALESCE(MAX(version), 0) FROM schema_version");
    st.step();
    return static_cast<int>(st.int64(0));
  }
  auto st = conn_->prepare("PRAGMA user_version");
  st.step();
  return static_cast<int>(st.int64(0));
}

void Store::audit_migration(int from) {
  insert_audit_locked("schema", kSchemaVersion, std::nullopt, "migrate",
                      "from version " + std::to_string(from) + " to " + std::to_string(kSchemaVersion));
}

void Store::migrate() {
  static_assert(kSchemaVersion >= 1);
  if (conn_->dialect() == Dialect::postgres) return migrate_postgres();
  const auto& m = migrations();
  if (static_cast<int>(m.size()) != kSchemaVersion) throw std::logic_error("schema: kSchemaVersion != migrations");
  if (schema_version() == kSchemaVersion) return;
  conn_->write_transaction([&] {
    const int v = schema_version();  // re-read under the write lock: another process may have migrated
    if (v > kSchemaVersion)
      throw DbError(1, conn_->path() + ": database schema version " + std::to_string(v) +
                           " is newer than this calbench (" + std::to_string(kSchemaVersion) + ")");
    for (int i = v; i < kSchemaVersion; ++i) {
      conn_->exec(m[static_cast<std::size_t>(i)]);
      if (i + 1 == kChainSchemaVersion) {  // the audit rows already there are chained, then sealed
        seal_audit_chain_locked(*conn_);
        conn_->exec(schema9_after_seal());
      }
    }
    // user_version cannot take a bound parameter; the value is a compile-time integer.
    conn_->exec(("PRAGMA user_version = " + std::to_string(kSchemaVersion)).c_str());
    if (v < kSchemaVersion) audit_migration(v);
  });
}

// PostgreSQL: the base schema (db/postgres/schema.sql, version 3) on an empty database, then the
// migrations after it, all in one transaction under an advisory lock, so that two processes
// starting at once migrate once. Only the owner of the tables can migrate: any other role that
// finds an older schema is told to ask for `calbench db init`.
void Store::migrate_postgres() {
  const int v0 = schema_version();
  if (v0 == kSchemaVersion) return;
  if (v0 > kSchemaVersion)
    throw DbError(1, conn_->path() + ": database schema version " + std::to_string(v0) +
                         " is newer than this calbench (" + std::to_string(kSchemaVersion) + ")");
  // calbench's migration lock, taken before the transaction: a SERIALIZABLE transaction's snapshot
  // is taken at its first statement, so a lock taken inside it would not show the other's schema.
  const PgSchemaLock lock(*conn_);
  try {
    conn_->write_transaction([&] {
      const int v = schema_version();
      if (v == kSchemaVersion) return;
      if (v == 0) conn_->exec(pg_base_schema());
      const int base = v == 0 ? kPgBaseSchemaVersion : v;
      const auto& m = pg_migrations();
      for (int i = base; i < kSchemaVersion; ++i) conn_->exec(m[static_cast<std::size_t>(i - kPgBaseSchemaVersion)]);
      audit_migration(v);
    });
  } catch (const PermissionError&) {
    throw DbError(1, conn_->path() + ": the database has schema version " + std::to_string(v0) + ", this calbench needs " +
                         std::to_string(kSchemaVersion) + "; role '" +
                         static_cast<PgConnection&>(*conn_).role() +
                         "' may not change the schema: the database owner runs `calbench db init --db URI`");
  }
}

std::string Store::login() const {
  if (conn_->dialect() == Dialect::postgres) return static_cast<const PgConnection&>(*conn_).role();
  if (!console_login_.empty()) return kConsoleLoginPrefix + console_login_;
  return actor_.os_user;
}

std::string Store::may_record_provisioning() {
  if (conn_->dialect() != Dialect::postgres) return {};
  // Schema 9: provisioning goes through calbench_record_provisioning, for members of the group.
  auto st = conn_->prepare("SELECT CASE WHEN EXISTS (SELECT 1 FROM pg_roles WHERE rolname = 'calbench_provisioning') "
                           "THEN pg_has_role(session_user, 'calbench_provisioning', 'MEMBER') ELSE false END, session_user");
  st.step();
  if (st.int64(0)) return {};
  return conn_->path() + ": the database refused this to role '" + st.text(1) +
         "': it may not record provisioning (a member of calbench_provisioning provisions; nothing was written to the "
         "device)";
}

void Store::apply_roles() {
  if (conn_->dialect() != Dialect::postgres) throw std::logic_error("apply_roles: not PostgreSQL");
  const PgSchemaLock lock(*conn_);
  conn_->exec(pg_roles_sql());  // its own transaction
  conn_->write_transaction([&] { audit_locked("schema", kSchemaVersion, "roles", "calbench_station, calbench_qc, "
                                                                              "calbench_provisioning, calbench_reader"); });
}

}  // namespace calbench::db
