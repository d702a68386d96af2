#include "db/store.hpp"

#include <pwd.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <cmath>
#include <cstdlib>

#include "common/input_error.hpp"
#include "db/input_errors.hpp"
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
  bool printable = false;
  for (unsigned char c : name) {
    if (c < 0x20 || c == 0x7f) return n + "contains control characters";
    if (c != ' ') printable = true;
  }
  if (!printable || name.front() == ' ' || name.back() == ' ') return n + "must not be blank or start or end with a space";
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
  } else {
    const passwd* pw = ::getpwuid(::geteuid());
    std::string os = pw && pw->pw_name && *pw->pw_name ? pw->pw_name : env("USER");
    a.user = os.empty() ? "unknown" : os;
    a.source = "OS user";
  }
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
  static thread_local std::mt19937_64 rng(std::random_device{}() ^ (static_cast<std::uint64_t>(::getpid()) << 32) ^
                                          static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count()));
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
  auto st = conn_->prepare(std::string("INSERT INTO audit_log(at, \"user\", station, entity, entity_id, action, detail) "
                                       "VALUES (") + conn_->now_sql() + ", ?, ?, 'schema', ?, 'migrate', ?)");
  st.bind(1, actor_.user).bind(2, actor_.station).bind(3, kSchemaVersion)
      .bind(4, "from version " + std::to_string(from) + " to " + std::to_string(kSchemaVersion));
  st.run();
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
    for (int i = v; i < kSchemaVersion; ++i) conn_->exec(m[static_cast<std::size_t>(i)]);
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

std::string Store::may_record_provisioning() {
  if (conn_->dialect() != Dialect::postgres) return {};
  auto st = conn_->prepare("SELECT has_table_privilege('provisioning_events', 'INSERT') AND "
                           "has_column_privilege('coefficient_sets', 'status', 'UPDATE'), session_user");
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

// ---------------------------------------------------------------- writes

void Store::audit_locked(const std::string& entity, std::int64_t entity_id, const std::string& action,
                         const std::string& detail) {
  std::optional<std::int64_t> device;
  if (entity == "device") {
    device = entity_id;
  } else if (entity == "coefficient_set") {
    auto st = conn_->prepare("SELECT device_id FROM coefficient_sets WHERE id = ?");
    st.bind(1, entity_id);
    if (st.step()) device = st.int64(0);
  } else if (entity == "bench_run" || entity == "inmotion_run") {
    auto st = conn_->prepare(entity == "bench_run" ? "SELECT device_id FROM bench_runs WHERE id = ?"
                                                   : "SELECT device_id FROM inmotion_runs WHERE id = ?");
    st.bind(1, entity_id);
    if (st.step()) device = st.int64(0);
  }
  auto st = conn_->prepare(std::string("INSERT INTO audit_log(at, \"user\", station, entity, entity_id, device_id, action, detail) "
                                       "VALUES (") + conn_->now_sql() + ", ?, ?, ?, ?, ?, ?, ?)");
  st.bind(1, actor_.user).bind(2, actor_.station).bind(3, entity).bind(4, entity_id).bind(5, device)
      .bind(6, action).bind(7, detail);
  st.run();
}

void Store::audit(const std::string& entity, std::int64_t entity_id, const std::string& action, const std::string& detail) {
  conn_->write_transaction([&] { audit_locked(entity, entity_id, action, detail); });
}

static void check_text(const std::string& v, const char* field, bool required) {
  if (required && v.empty()) throw arg_error(field, "must not be empty");
  if (v.size() > 4096) throw arg_error(field, "longer than 4096 characters");
  for (unsigned char c : v)
    if (c < 0x20 && c != '\t') throw arg_error(field, "contains control characters");
}

std::int64_t Store::ensure_device_locked(const DeviceInfo& d) {
  check_text(d.serial, "device.serial", true);
  check_text(d.model, "device.model", true);
  check_text(d.firmware, "device.firmware", false);
  auto st = conn_->prepare("SELECT id, model, firmware FROM devices WHERE serial = ?");
  st.bind(1, d.serial);
  if (st.step()) {
    const std::int64_t id = st.int64(0);
    if (st.text(1) != d.model)
      throw arg_error("device.model",
                       "device " + d.serial + " is a " + st.text(1) + " in the database, not a " + d.model);
    const std::string fw = st.text(2);
    if (!d.firmware.empty() && fw != d.firmware) {
      auto up = conn_->prepare("UPDATE devices SET firmware = ? WHERE id = ?");
      up.bind(1, d.firmware).bind(2, id).run();
      audit_locked("device", id, "firmware", "'" + fw + "' -> '" + d.firmware + "'");
    }
    return id;
  }
  auto ins = conn_->prepare(std::string("INSERT INTO devices(model, serial, firmware, created_at) VALUES (?, ?, ?, ") + conn_->now_sql() + ") RETURNING id");
  ins.bind(1, d.model).bind(2, d.serial).bind(3, d.firmware).step();
  const std::int64_t id = ins.int64(0);
  audit_locked("device", id, "create", d.model + " " + d.serial);
  return id;
}

std::int64_t Store::ensure_device(const DeviceInfo& d) {
  std::int64_t id = 0;
  conn_->write_transaction([&] { id = ensure_device_locked(d); });
  return id;
}

static std::int64_t ensure_station_locked(Store& s, Connection& c, const std::string& name, const std::string& desc) {
  check_text(name, "station", true);
  auto st = c.prepare("SELECT id FROM stations WHERE name = ?");
  st.bind(1, name);
  if (st.step()) return st.int64(0);
  auto ins = c.prepare(std::string("INSERT INTO stations(name, description, created_at) VALUES (?, ?, ") + c.now_sql() + ") RETURNING id");
  ins.bind(1, name).bind(2, desc).step();
  const std::int64_t id = ins.int64(0);
  s.audit_locked("station", id, "create", name);
  return id;
}

std::int64_t Store::ensure_station(const std::string& name, const std::string& description) {
  std::int64_t id = 0;
  conn_->write_transaction([&] { id = ensure_station_locked(*this, *conn_, name, description); });
  return id;
}

std::int64_t Store::insert_set_locked(std::int64_t device_id, SetSource source, const std::string& canonical_json,
                                      const SensorErrors& e, std::optional<std::int64_t> parent,
                                      std::optional<std::int64_t> bench_run, std::optional<std::int64_t> inmotion_run,
                                      int* version_out, const std::string& uid, bool* existed) {
  if (existed) *existed = false;
  if (!uid.empty()) {  // forwarded again (e.g. after a crash between the two stores): the one already there
    auto q = conn_->prepare("SELECT id, version FROM coefficient_sets WHERE uid = ?");
    q.bind(1, uid);
    if (q.step()) {
      if (version_out) *version_out = static_cast<int>(q.int64(1));
      if (existed) *existed = true;
      return q.int64(0);
    }
  }
  if (parent) {
    auto p = conn_->prepare("SELECT device_id FROM coefficient_sets WHERE id = ?");
    p.bind(1, *parent);
    if (!p.step()) throw arg_error("parent", "no coefficient set " + std::to_string(*parent));
    if (p.int64(0) != device_id)
      throw arg_error("parent", "set " + std::to_string(*parent) + " belongs to another device");
  }
  auto v = conn_->prepare("SELECT COALESCE(MAX(version), 0) + 1 FROM coefficient_sets WHERE device_id = ?");
  v.bind(1, device_id);
  v.step();
  const int version = static_cast<int>(v.int64(0));
  auto ins = conn_->prepare(std::string(
      "INSERT INTO coefficient_sets(device_id, version, source, parent_id, bench_run_id, inmotion_run_id, "
      "payload_json, status, created_at, created_by, uid) VALUES (?, ?, ?, ?, ?, ?, ?, 'draft', ") + conn_->now_sql() +
      ", ?, ?) RETURNING id");
  ins.bind(1, device_id).bind(2, version).bind(3, to_string(source)).bind(4, parent).bind(5, bench_run)
      .bind(6, inmotion_run).bind(7, canonical_json).bind(8, actor_.user + "@" + actor_.station)
      .bind(9, uid.empty() ? new_uid() : uid);
  ins.step();
  const std::int64_t id = ins.int64(0);
  if (hook_) hook_("set-row");
  auto val = conn_->prepare("INSERT INTO coefficient_values(set_id, name, value, sigma) VALUES (?, ?, ?, ?)");
  for (const auto& name : coefficient_names()) {
    val.reset();
    val.bind(1, id).bind(2, name).bind(3, coefficient_value(e, name)).bind(4, coefficient_sigma(e, name));
    val.run();
    if (hook_ && name == "gyro.M.zz") hook_("set-values");
  }
  audit_locked("coefficient_set", id, "create",
               "version " + std::to_string(version) + ", source " + to_string(source) +
                   (parent ? ", parent set " + std::to_string(*parent) : std::string()) + ", status draft");
  if (version_out) *version_out = version;
  return id;
}

void Store::insert_qc_locked(const std::vector<QcResult>& qc, std::optional<std::int64_t> bench_run,
                             std::optional<std::int64_t> inmotion_run) {
  auto st = conn_->prepare("INSERT INTO qc_results(bench_run_id, inmotion_run_id, metric, value, threshold, pass, unit, "
                           "sample, criterion) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)");
  for (const auto& q : qc) {
    check_text(q.metric, "qc.metric", true);
    check_text(q.unit, "qc.unit", false);
    check_text(q.criterion, "qc.criterion", false);
    if (!q.sample.empty() && q.sample != kInSample && q.sample != kOutOfSample && q.sample != kSampleNotApplicable)
      throw arg_error("qc." + q.metric + ".sample", "'" + q.sample + "' is not in-sample, out-of-sample or not applicable");
    if (!std::isfinite(q.value)) throw arg_error("qc." + q.metric, "NaN or infinity is not allowed");
    if (q.threshold && !std::isfinite(*q.threshold))
      throw arg_error("qc." + q.metric + ".threshold", "NaN or infinity is not allowed");
    st.reset();
    st.bind(1, bench_run).bind(2, inmotion_run).bind(3, q.metric).bind(4, q.value).bind(5, q.threshold)
        .bind(6, q.pass ? 1 : 0).bind(7, q.unit).bind(8, q.sample).bind(9, q.criterion);
    st.run();
  }
}

// The fields of a bench run, checked before any transaction (nothing is written on bad input).
static void check_bench_run(const BenchRunInput& run) {
  if (run.outcome != "pass" && run.outcome != "fail" && run.outcome != "aborted")
    throw arg_error("outcome", "expected pass, fail or aborted, got '" + run.outcome + "'");
  for (const auto* f : {&run.plan, &run.recording_path, &run.recording_sha256, &run.started_at, &run.ended_at})
    check_text(*f, "bench_run", false);
}

// The bench run's row, its audit entry (`detail`) and its QC results, inside the caller's transaction.
// A run whose uid is already stored is not stored again: its id is returned with *existed = true.
// run.uid is set (the callers draw it before their transaction).
static std::int64_t insert_bench_run_locked(Store& store, Connection& c, std::int64_t device_id, const BenchRunInput& run,
                                            const std::string& detail, bool* existed = nullptr) {
  if (existed) *existed = false;
  {
    auto q = c.prepare("SELECT id FROM bench_runs WHERE uid = ?");
    q.bind(1, run.uid);
    if (q.step()) {
      if (existed) *existed = true;
      return q.int64(0);
    }
  }
  std::optional<std::int64_t> station;
  if (!run.station.empty()) station = ensure_station_locked(store, c, run.station, "");
  auto st = c.prepare(std::string(
      "INSERT INTO bench_runs(device_id, station_id, plan, recording_path, recording_sha256, started_at, ended_at, "
      "outcome, created_at, uid) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ") + c.now_sql() + ", ?) RETURNING id");
  st.bind(1, device_id).bind(2, station).bind(3, run.plan).bind(4, run.recording_path)
      .bind(5, run.recording_sha256).bind(6, run.started_at).bind(7, run.ended_at).bind(8, run.outcome)
      .bind(9, run.uid);
  st.step();
  const std::int64_t id = st.int64(0);
  store.audit_locked("bench_run", id, "create", detail);
  store.insert_qc_locked(run.qc, id, std::nullopt);
  return id;
}

StoredSet Store::store_bench(const DeviceInfo& d, const BenchRunInput& run, const std::string& coefficients_json) {
  // Validate everything before the transaction: nothing is written on bad input.
  const ParsedCoefficients p = parse_coefficients(coefficients_json, "coefficients", d.serial);
  if (p.device.model != d.model)
    throw InputError("coefficients", 0, "device.model", "model '" + p.device.model + "' is not '" + d.model + "'");
  check_bench_run(run);
  // The uid is drawn once, before the transaction: a transaction re-run after a lost reply to its
  // COMMIT then finds the run it already stored instead of storing it again.
  BenchRunInput r = run;
  if (r.uid.empty()) r.uid = new_uid();
  StoredSet out;
  conn_->write_transaction([&] {
    out = StoredSet{};
    out.device_id = ensure_device_locked(d);
    out.run_id = insert_bench_run_locked(*this, *conn_, out.device_id, r, "plan " + r.plan + ", outcome " + r.outcome,
                                         &out.existed);
    if (out.existed) {  // the same run again (forwarded twice): its set, not a second one
      auto q = conn_->prepare("SELECT id, version FROM coefficient_sets WHERE bench_run_id = ? ORDER BY id LIMIT 1");
      q.bind(1, out.run_id);
      if (q.step()) {
        out.set_id = q.int64(0);
        out.version = static_cast<int>(q.int64(1));
        return;
      }
    }
    out.set_id = insert_set_locked(out.device_id, SetSource::bench, p.canonical_json, p.errors, std::nullopt,
                                   out.run_id, std::nullopt, &out.version, r.uid + "/set");
  });
  return out;
}

StoredSet Store::store_set(const DeviceInfo& d, SetSource source, const std::string& coefficients_json,
                           std::optional<std::int64_t> parent, const std::string& uid) {
  const ParsedCoefficients p = parse_coefficients(coefficients_json, "coefficients", d.serial);
  const std::string u = uid.empty() ? new_uid() : uid;  // once, before the transaction (see store_bench)
  StoredSet out;
  conn_->write_transaction([&] {
    out = StoredSet{};
    out.device_id = ensure_device_locked(d);
    out.set_id = insert_set_locked(out.device_id, source, p.canonical_json, p.errors, parent, std::nullopt,
                                   std::nullopt, &out.version, u, &out.existed);
  });
  return out;
}

std::int64_t Store::store_bench_run(const DeviceInfo& d, const BenchRunInput& run, const std::string& reason,
                                    bool* existed) {
  if (run.outcome != "fail" && run.outcome != "aborted")
    throw arg_error("outcome", "a run without a set is 'fail' or 'aborted', got '" + run.outcome + "'");
  check_bench_run(run);
  // The reason is an exception's text: keep it on one line and bounded.
  std::string why;
  for (char c : reason.substr(0, 2000)) why += (static_cast<unsigned char>(c) < 0x20) ? ' ' : c;
  BenchRunInput r = run;
  if (r.uid.empty()) r.uid = new_uid();  // once, before the transaction (see store_bench)
  std::int64_t id = 0;
  conn_->write_transaction([&] {
    id = insert_bench_run_locked(*this, *conn_, ensure_device_locked(d), r,
                                 "plan " + run.plan + ", outcome " + run.outcome + (why.empty() ? "" : ": " + why) +
                                     (run.recording_path.empty() ? "" : "; partial recording " + run.recording_path),
                                 existed);
  });
  return id;
}

namespace {
struct KnownSetting {
  const char* key;
  const char* fallback;
  std::vector<std::string> values;
};
const std::vector<KnownSetting>& known_settings() {
  static const std::vector<KnownSetting> k = {{kFourEyes, "on", {"on", "off"}}};
  return k;
}
const KnownSetting& known_setting(const std::string& key) {
  std::string all;
  for (const auto& k : known_settings()) {
    if (key == k.key) return k;
    all += (all.empty() ? "" : ", ") + std::string(k.key);
  }
  throw arg_error("setting", "unknown setting '" + key + "' (settings: " + all + ")");
}
}  // namespace

void Store::set_setting(const std::string& key, const std::string& value) {
  const KnownSetting& k = known_setting(key);
  if (std::find(k.values.begin(), k.values.end(), value) == k.values.end()) {
    std::string vals;
    for (const auto& v : k.values) vals += (vals.empty() ? "" : ", ") + v;
    throw arg_error(key, "'" + value + "' is not one of: " + vals);
  }
  if (!actor_.named())
    throw DbError(1, "changing a setting needs a named operator (--operator NAME or CALBENCH_OPERATOR); the OS "
                     "user '" + actor_.user + "' is not a signature");
  conn_->write_transaction([&] {
    const std::string before = setting(key);
    auto st = conn_->prepare(std::string("INSERT INTO settings(key, value, changed_at, changed_by) VALUES (?, ?, ") +
                             conn_->now_sql() + ", ?) ON CONFLICT(key) DO UPDATE SET value = excluded.value, "
                             "changed_at = excluded.changed_at, changed_by = excluded.changed_by");
    st.bind(1, key).bind(2, value).bind(3, actor_.user + "@" + actor_.station).run();
    audit_locked("setting", 0, "set", key + ": " + before + " -> " + value);
  });
}

std::string Store::setting(const std::string& key) {
  const KnownSetting& k = known_setting(key);
  auto st = conn_->prepare("SELECT value FROM settings WHERE key = ?");
  st.bind(1, key);
  return st.step() ? st.text(0) : std::string(k.fallback);
}

std::vector<Setting> Store::settings() {
  std::vector<Setting> out;
  for (const auto& k : known_settings()) {
    Setting s{k.key, k.fallback, "", ""};
    auto st = conn_->prepare("SELECT value, changed_at, changed_by FROM settings WHERE key = ?");
    st.bind(1, std::string(k.key));
    if (st.step()) s.value = st.text(0), s.changed_at = st.text(1), s.changed_by = st.text(2);
    out.push_back(s);
  }
  return out;
}

void Store::set_status(std::int64_t set_id, SetStatus to, const std::string& reason) {
  check_text(reason, "reason", false);
  conn_->write_transaction([&] {
    auto st = conn_->prepare("SELECT status FROM coefficient_sets WHERE id = ?");
    st.bind(1, set_id);
    if (!st.step()) throw arg_error("set", "no coefficient set " + std::to_string(set_id));
    const SetStatus from = status_from_string(st.text(0));
    const bool ok = (from == SetStatus::draft && (to == SetStatus::approved || to == SetStatus::revoked)) ||
                    (from == SetStatus::approved && (to == SetStatus::provisioned || to == SetStatus::revoked)) ||
                    (from == SetStatus::provisioned && (to == SetStatus::provisioned || to == SetStatus::revoked));
    if (!ok)
      throw arg_error("status", "set " + std::to_string(set_id) + " is " + to_string(from) +
                                            "; it cannot become " + to_string(to));
    auto up = conn_->prepare("UPDATE coefficient_sets SET status = ? WHERE id = ?");
    up.bind(1, to_string(to)).bind(2, set_id).run();
    audit_locked("coefficient_set", set_id, "status",
                 to_string(from) + " -> " + to_string(to) + (reason.empty() ? "" : ": " + reason));
  });
}

void Store::record_provisioning(std::int64_t set_id, const std::string& kind, const std::string& target, bool ok,
                                const std::string& readback_json, const std::string& message) {
  if (kind != "device" && kind != "export") throw arg_error("kind", "expected device or export");
  check_text(target, "target", true);
  conn_->write_transaction([&] {
    auto st = conn_->prepare("SELECT device_id, status FROM coefficient_sets WHERE id = ?");
    st.bind(1, set_id);
    if (!st.step()) throw arg_error("set", "no coefficient set " + std::to_string(set_id));
    const std::int64_t device = st.int64(0);
    const SetStatus status = status_from_string(st.text(1));
    if (status != SetStatus::approved && status != SetStatus::provisioned)
      throw arg_error("set", "set " + std::to_string(set_id) + " is " + to_string(status) +
                                         "; only approved sets are provisioned");
    auto ins = conn_->prepare(std::string(
        "INSERT INTO provisioning_events(set_id, device_id, kind, target, ok, readback_json, message, actor, at) "
        "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ") + conn_->now_sql() + ") RETURNING id");
    ins.bind(1, set_id).bind(2, device).bind(3, kind).bind(4, target).bind(5, ok ? 1 : 0)
        .bind(6, readback_json.empty() ? std::string("{}") : readback_json).bind(7, message)
        .bind(8, actor_.user + "@" + actor_.station);
    ins.step();
    const std::int64_t ev = ins.int64(0);
    audit_locked("coefficient_set", set_id, kind == "device" ? "provision" : "export",
                 std::string(ok ? "ok" : "FAILED") + " to " + target + " (event " + std::to_string(ev) + ")" +
                     (message.empty() ? "" : ": " + message));
    if (kind == "device" && ok) {
      auto up = conn_->prepare("UPDATE coefficient_sets SET status = 'provisioned' WHERE id = ?");
      up.bind(1, set_id).run();
      if (status != SetStatus::provisioned)
        audit_locked("coefficient_set", set_id, "status", "approved -> provisioned");
    }
  });
}

// ---------------------------------------------------------------- reads

std::optional<Device> Store::find_device(const std::string& serial) {
  auto st = conn_->prepare("SELECT id, model, serial, firmware, created_at FROM devices WHERE serial = ?");
  st.bind(1, serial);
  if (!st.step()) return std::nullopt;
  return Device{st.int64(0), st.text(1), st.text(2), st.text(3), st.text(4)};
}

std::vector<Device> Store::devices() {
  std::vector<Device> out;
  auto st = conn_->prepare("SELECT id, model, serial, firmware, created_at FROM devices ORDER BY serial");
  while (st.step()) out.push_back(Device{st.int64(0), st.text(1), st.text(2), st.text(3), st.text(4)});
  return out;
}

std::vector<DeviceSummary> Store::device_summaries() {
  std::vector<DeviceSummary> out;
  auto st = conn_->prepare(
      "SELECT d.id, d.model, d.serial, d.firmware, d.created_at, "
      "(SELECT COUNT(*) FROM coefficient_sets s WHERE s.device_id = d.id), s.version, s.status, s.source "
      "FROM devices d LEFT JOIN coefficient_sets s ON s.device_id = d.id AND s.version = "
      "(SELECT MAX(version) FROM coefficient_sets x WHERE x.device_id = d.id) ORDER BY d.serial");
  while (st.step()) {
    DeviceSummary s{Device{st.int64(0), st.text(1), st.text(2), st.text(3), st.text(4)},
                    static_cast<int>(st.int64(5)), std::nullopt, st.text(7), st.text(8)};
    if (!st.is_null(6)) s.latest_version = static_cast<int>(st.int64(6));
    out.push_back(std::move(s));
  }
  return out;
}

static const char* kSetColumns =
    "SELECT s.id, s.device_id, d.serial, d.model, s.version, s.source, s.status, s.parent_id, s.bench_run_id, "
    "s.inmotion_run_id, s.payload_json, s.created_at, s.created_by FROM coefficient_sets s "
    "JOIN devices d ON d.id = s.device_id ";

CoefficientSetRecord Store::read_set_row(Statement& st) {
  CoefficientSetRecord r;
  r.id = st.int64(0);
  r.device_id = st.int64(1);
  r.serial = st.text(2);
  r.model = st.text(3);
  r.version = static_cast<int>(st.int64(4));
  r.source = source_from_string(st.text(5));
  r.status = status_from_string(st.text(6));
  r.parent_id = st.opt_int64(7);
  r.bench_run_id = st.opt_int64(8);
  r.inmotion_run_id = st.opt_int64(9);
  r.payload_json = st.text(10);
  r.created_at = st.text(11);
  r.created_by = st.text(12);
  return r;
}

static void load_values(Connection& c, CoefficientSetRecord& r) {
  auto st = c.prepare("SELECT name, value, sigma FROM coefficient_values WHERE set_id = ?");
  st.bind(1, r.id);
  SensorErrors& e = r.errors;
  while (st.step()) {
    const std::string name = st.text(0);
    const double v = st.real(1);
    const double s = st.is_null(2) ? kUnknownSigma : st.real(2);
    TriadErrors& t = name.rfind("gyro.", 0) == 0 ? e.gyro : e.accel;
    const auto dot = name.rfind('.');
    const std::string axes = name.substr(dot + 1);
    auto ax = [](char ch) { return ch == 'x' ? 0 : ch == 'y' ? 1 : 2; };
    if (name.find(".bias.") != std::string::npos) {
      t.bias(ax(axes[0])) = v;
      t.sigma_bias(ax(axes[0])) = s;
    } else {
      t.M(ax(axes[0]), ax(axes[1])) = v;
      t.sigma_M(ax(axes[0]), ax(axes[1])) = s;
    }
  }
}

std::optional<CoefficientSetRecord> Store::find_set(std::int64_t set_id) {
  auto st = conn_->prepare(std::string(kSetColumns) + "WHERE s.id = ?");
  st.bind(1, set_id);
  if (!st.step()) return std::nullopt;
  CoefficientSetRecord r = read_set_row(st);
  load_values(*conn_, r);
  return r;
}

CoefficientSetRecord Store::get_set(std::int64_t set_id) {
  auto r = find_set(set_id);
  if (!r) throw arg_error("set", "no coefficient set " + std::to_string(set_id) + " in " + conn_->path());
  return *r;
}

std::vector<CoefficientSetRecord> Store::sets_of(std::int64_t device_id) {
  std::vector<CoefficientSetRecord> out;
  auto st = conn_->prepare(std::string(kSetColumns) + "WHERE s.device_id = ? ORDER BY s.version");
  st.bind(1, device_id);
  while (st.step()) out.push_back(read_set_row(st));
  for (auto& r : out) load_values(*conn_, r);
  return out;
}

std::optional<CoefficientSetRecord> Store::latest_set(std::int64_t device_id, std::optional<SetStatus> status) {
  auto st = conn_->prepare(std::string(kSetColumns) +
                           "WHERE s.device_id = ? AND (CAST(? AS TEXT) IS NULL OR s.status = CAST(? AS TEXT)) ORDER BY s.version DESC LIMIT 1");
  std::optional<std::string> s;
  if (status) s = to_string(*status);
  st.bind(1, device_id).bind(2, s).bind(3, s);
  if (!st.step()) return std::nullopt;
  CoefficientSetRecord r = read_set_row(st);
  load_values(*conn_, r);
  return r;
}

std::optional<BenchRun> Store::bench_run(std::int64_t id) {
  auto st = conn_->prepare(
      "SELECT r.id, r.device_id, COALESCE(s.name, ''), r.plan, r.recording_path, r.recording_sha256, r.started_at, "
      "r.ended_at, r.outcome, r.created_at FROM bench_runs r LEFT JOIN stations s ON s.id = r.station_id WHERE r.id = ?");
  st.bind(1, id);
  if (!st.step()) return std::nullopt;
  return BenchRun{st.int64(0), st.int64(1), st.text(2), st.text(3), st.text(4), st.text(5),
                  st.text(6), st.text(7), st.text(8), st.text(9)};
}

std::optional<InMotionRun> Store::inmotion_run(std::int64_t id) {
  auto st = conn_->prepare(
      "SELECT id, device_id, recording_path, recording_sha256, reference_system, mounting_roll_deg, "
      "mounting_pitch_deg, mounting_yaw_deg, mounting_roll_sigma_deg, mounting_pitch_sigma_deg, "
      "mounting_yaw_sigma_deg, consistency_json, qc_json, result_json, created_at FROM inmotion_runs WHERE id = ?");
  st.bind(1, id);
  if (!st.step()) return std::nullopt;
  InMotionRun r;
  r.id = st.int64(0);
  r.device_id = st.int64(1);
  r.recording_path = st.text(2);
  r.recording_sha256 = st.text(3);
  r.reference_system = st.text(4);
  for (int i = 0; i < 3; ++i) {
    r.mounting_rpy_deg[static_cast<std::size_t>(i)] = st.real(5 + i);
    r.mounting_sigma_deg[static_cast<std::size_t>(i)] = st.is_null(8 + i) ? kUnknownSigma : st.real(8 + i);
  }
  r.consistency_json = st.text(11);
  r.qc_json = st.text(12);
  r.result_json = st.text(13);
  r.created_at = st.text(14);
  return r;
}

static std::vector<QcResult> read_qc(Statement& st) {
  std::vector<QcResult> out;
  while (st.step())
    out.push_back(QcResult{st.text(0), st.real(1), st.opt_real(2), st.int64(3) != 0, st.text(4), st.text(5), st.text(6)});
  return out;
}

std::vector<QcResult> Store::qc_of_bench_run(std::int64_t id) {
  auto st = conn_->prepare("SELECT metric, value, threshold, pass, unit, sample, criterion FROM qc_results WHERE bench_run_id = ? ORDER BY id");
  st.bind(1, id);
  return read_qc(st);
}

std::vector<QcResult> Store::qc_of_inmotion_run(std::int64_t id) {
  auto st = conn_->prepare("SELECT metric, value, threshold, pass, unit, sample, criterion FROM qc_results WHERE inmotion_run_id = ? ORDER BY id");
  st.bind(1, id);
  return read_qc(st);
}

std::vector<QcResult> Store::qc_of_set(const CoefficientSetRecord& s) {
  std::vector<QcResult> out;
  if (s.bench_run_id) out = qc_of_bench_run(*s.bench_run_id);
  if (s.inmotion_run_id) {
    auto m = qc_of_inmotion_run(*s.inmotion_run_id);
    out.insert(out.end(), m.begin(), m.end());
  }
  return out;
}

std::vector<ProvisioningEvent> Store::provisioning_of(std::int64_t device_id) {
  std::vector<ProvisioningEvent> out;
  auto st = conn_->prepare("SELECT id, set_id, device_id, kind, target, ok, readback_json, message, actor, at "
                           "FROM provisioning_events WHERE device_id = ? ORDER BY id");
  st.bind(1, device_id);
  while (st.step())
    out.push_back(ProvisioningEvent{st.int64(0), st.int64(1), st.int64(2), st.text(3), st.text(4), st.int64(5) != 0,
                                    st.text(6), st.text(7), st.text(8), st.text(9)});
  return out;
}

std::vector<AuditEntry> Store::audit_of_device(std::int64_t device_id) {
  std::vector<AuditEntry> out;
  auto st = conn_->prepare("SELECT id, at, \"user\", station, entity, entity_id, action, detail FROM audit_log "
                           "WHERE device_id = ? ORDER BY id");
  st.bind(1, device_id);
  while (st.step())
    out.push_back(AuditEntry{st.int64(0), st.text(1), st.text(2), st.text(3), st.text(4), st.int64(5), st.text(6),
                             st.text(7)});
  return out;
}

std::vector<FleetValue> Store::fleet() {
  std::vector<FleetValue> out;
  auto st = conn_->prepare(
      "WITH latest AS (SELECT device_id, MAX(version) AS version FROM coefficient_sets "
      "                WHERE status <> 'revoked' GROUP BY device_id) "
      "SELECT d.serial, s.id, s.version, s.status, v.name, v.value, v.sigma, COALESCE(sn.name, '') FROM latest l "
      "JOIN coefficient_sets s ON s.device_id = l.device_id AND s.version = l.version "
      "JOIN devices d ON d.id = s.device_id JOIN coefficient_values v ON v.set_id = s.id "
      "LEFT JOIN coefficient_sets p ON p.id = s.parent_id "
      "LEFT JOIN bench_runs r ON r.id = COALESCE(s.bench_run_id, p.bench_run_id) "
      "LEFT JOIN stations sn ON sn.id = r.station_id "
      "ORDER BY d.serial, v.name");
  while (st.step())
    out.push_back(FleetValue{st.text(0), st.int64(1), static_cast<int>(st.int64(2)), st.text(3), st.text(4),
                             st.real(5), st.is_null(6) ? kUnknownSigma : st.real(6), st.text(7)});
  return out;
}

std::int64_t Store::count(const char* table) {
  static const char* const known[] = {"devices", "stations", "bench_runs", "inmotion_runs", "coefficient_sets",
                                      "coefficient_values", "qc_results", "provisioning_events", "audit_log"};
  for (const char* k : known)
    if (std::string(k) == table) {
      auto st = conn_->prepare(std::string("SELECT COUNT(*) FROM ") + k);  // table name from the fixed list
      st.step();
      return st.int64(0);
    }
  throw std::invalid_argument(std::string("unknown table ") + table);
}

}  // namespace calbench::db
