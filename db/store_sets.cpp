// Store writes of devices, stations, coefficient sets, bench runs and their QC results, each in one
// transaction with its audit entries; everything is checked before the transaction starts.
#include <cmath>
#include <stdexcept>

#include "common/input_error.hpp"
#include <set>

#include "db/audit_chain.hpp"
#include "db/input_errors.hpp"
#include "db/store.hpp"

namespace calbench::db {

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
  insert_audit_locked(entity, entity_id, device, action, detail);
}

// PostgreSQL (schema 9): a login records only what its own transaction created or answered, through
// calbench_audit, which stamps who it is; signatures are written by the functions that make them
// (calbench_approve, …). Schema changes, roles and the mapping of logins (the owner's) go directly.
// SQLite: the row with its link of the hash chain (db/audit_chain.hpp), under the write lock.
void Store::insert_audit_locked(const std::string& entity, std::int64_t entity_id, std::optional<std::int64_t> device,
                                const std::string& action, const std::string& detail) {
  if (conn_->dialect() == Dialect::postgres) {
    static const std::set<std::string> own = {"create", "firmware", "ask", "answer", "timeout"};
    if (own.count(action)) {
      auto st = conn_->prepare("SELECT calbench_audit(?, ?, ?, ?, ?, ?)");
      st.bind(1, entity).bind(2, entity_id).bind(3, action).bind(4, detail).bind(5, actor_.user).bind(6, actor_.station);
      st.step();
      return;
    }
    auto st = conn_->prepare("INSERT INTO audit_log(\"user\", station, entity, entity_id, device_id, action, detail) "
                             "VALUES (?, ?, ?, ?, ?, ?, ?)");
    st.bind(1, actor_.user).bind(2, actor_.station).bind(3, entity).bind(4, entity_id).bind(5, device)
        .bind(6, action).bind(7, detail);
    st.run();
    return;
  }
  AuditRowFields r;
  std::string prev;  // the last row's chain value
  {
    auto q = conn_->prepare(std::string("SELECT COALESCE(MAX(id), 0) + 1, ") + conn_->now_sql() +
                            ", (SELECT chain FROM audit_log ORDER BY id DESC LIMIT 1) FROM audit_log");
    q.step();
    r.id = q.int64(0);
    r.at = q.text(1);
    if (!q.is_null(2)) prev = q.text(2);
  }
  r.user = actor_.user, r.station = actor_.station, r.db_role = login(), r.entity = entity;
  r.entity_id = entity_id, r.device_id = device, r.action = action, r.detail = detail;
  // (Every store is at schema 9 once opened, and migration 9 adds the chain before its own row.)
  auto st = conn_->prepare("INSERT INTO audit_log(id, at, \"user\", station, entity, entity_id, device_id, action, "
                           "detail, db_role, chain) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  st.bind(1, r.id).bind(2, r.at).bind(3, r.user).bind(4, r.station).bind(5, entity).bind(6, entity_id).bind(7, device)
      .bind(8, action).bind(9, detail).bind(10, r.db_role).bind(11, audit_chain_link(prev, r));
  st.run();
}

void Store::audit(const std::string& entity, std::int64_t entity_id, const std::string& action, const std::string& detail) {
  conn_->write_transaction([&] { audit_locked(entity, entity_id, action, detail); });
}

void Store::audit_security(const std::string& action, const std::string& login, const std::string& detail) {
  if (action != "login-failed" && action != "lockout" && action != "refused")
    throw std::logic_error("audit_security: unknown action " + action);
  check_text(login, "login", false);
  check_text(detail, "detail", false);
  conn_->write_transaction([&] {
    if (conn_->dialect() == Dialect::postgres) {
      auto st = conn_->prepare("SELECT calbench_audit_security(?, ?, ?, ?)");
      st.bind(1, action).bind(2, login).bind(3, detail).bind(4, actor_.station).step();
      return;
    }
    audit_locked("security", 0, action, login + (detail.empty() ? "" : ": " + detail));
  });
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
      "payload_json, status, created_at, created_by, uid, created_by_role, creator) VALUES (?, ?, ?, ?, ?, ?, ?, 'draft', ") +
      conn_->now_sql() + ", ?, ?, ?, ?) RETURNING id");
  ins.bind(1, device_id).bind(2, version).bind(3, to_string(source)).bind(4, parent).bind(5, bench_run)
      .bind(6, inmotion_run).bind(7, canonical_json).bind(8, actor_.user + "@" + actor_.station)
      .bind(9, uid.empty() ? new_uid() : uid).bind(10, login()).bind(11, actor_.user);
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
  for (const auto* f : {&run.plan, &run.recording_path, &run.recording_sha256, &run.started_at, &run.ended_at, &run.slot,
                        &run.table_run, &run.recording_uri, &run.recording_digest})
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
      "outcome, created_at, uid, slot, table_run, recording_uri, recording_digest) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ") +
      c.now_sql() + ", ?, ?, ?, ?, ?) RETURNING id");
  st.bind(1, device_id).bind(2, station).bind(3, run.plan).bind(4, run.recording_path)
      .bind(5, run.recording_sha256).bind(6, run.started_at).bind(7, run.ended_at).bind(8, run.outcome)
      .bind(9, run.uid).bind(10, run.slot).bind(11, run.table_run).bind(12, run.recording_uri)
      .bind(13, run.recording_digest);
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

}  // namespace calbench::db
