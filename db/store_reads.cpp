// Store reads: devices, sets with their values, runs, QC results, provisioning, audit and the fleet.
#include <cmath>

#include "common/drive_result.hpp"
#include "common/input_error.hpp"
#include "db/input_errors.hpp"
#include "db/store.hpp"

namespace calbench::db {

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
    "s.inmotion_run_id, s.payload_json, s.created_at, s.created_by, s.created_by_role, s.creator FROM coefficient_sets s "
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
  r.created_by_login = st.text(13);
  r.creator = st.text(14);
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
      "r.ended_at, r.outcome, r.created_at, r.slot, r.table_run, r.recording_uri, r.recording_digest FROM bench_runs r "
      "LEFT JOIN stations s ON "
      "s.id = r.station_id WHERE r.id = ?");
  st.bind(1, id);
  if (!st.step()) return std::nullopt;
  return BenchRun{st.int64(0), st.int64(1), st.text(2), st.text(3), st.text(4), st.text(5),
                  st.text(6), st.text(7), st.text(8), st.text(9), st.text(10), st.text(11),
                  st.text(12), st.text(13)};
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
  // The recording's URI and digest live in the stored RESULT.json (no column of their own): read
  // through the one codec; a stored result it no longer reads leaves them "".
  const auto j = nlohmann::json::parse(r.result_json, nullptr, false);
  if (!j.is_discarded()) try {
      const DriveResult d = drive_result_from_json(j, "inmotion_runs.result_json");
      r.recording_uri = d.recording.uri.value_or("");
      r.recording_digest = d.recording.digest.value_or("");
    } catch (const InputError&) {
    }
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

std::vector<Store::SetStatusRow> Store::set_statuses(std::int64_t device_id) {
  std::vector<SetStatusRow> out;
  auto st = conn_->prepare(conn_->dialect() == Dialect::postgres
                               ? "SELECT id, version, status FROM calbench_set_statuses(?)"
                               : "SELECT id, version, status FROM coefficient_sets WHERE device_id = ? ORDER BY version");
  st.bind(1, device_id);
  while (st.step())
    out.push_back(SetStatusRow{st.int64(0), static_cast<int>(st.int64(1)), status_from_string(st.text(2))});
  return out;
}

std::vector<AuditEntry> Store::audit_of_device(std::int64_t device_id) {
  std::vector<AuditEntry> out;
  auto st = conn_->prepare("SELECT id, at, \"user\", station, entity, entity_id, action, detail, db_role FROM audit_log "
                           "WHERE device_id = ? ORDER BY id");
  st.bind(1, device_id);
  while (st.step())
    out.push_back(AuditEntry{st.int64(0), st.text(1), st.text(2), st.text(3), st.text(4), st.int64(5), st.text(6),
                             st.text(7), st.text(8)});
  return out;
}

std::vector<CoefficientSetRecord> Store::sets_with_status(SetStatus status, int limit, std::int64_t offset) {
  std::vector<CoefficientSetRecord> out;
  auto st = conn_->prepare(std::string(kSetColumns) + "WHERE s.status = ? ORDER BY s.id LIMIT ? OFFSET ?");
  st.bind(1, to_string(status)).bind(2, limit).bind(3, offset);
  while (st.step()) out.push_back(read_set_row(st));
  for (auto& r : out) load_values(*conn_, r);
  return out;
}

std::vector<AuditEntry> Store::audit_search(const AuditQuery& q) {
  for (const auto* d : {&q.from, &q.to})
    if (!d->empty() && (d->size() != 10 || (*d)[4] != '-' || (*d)[7] != '-'))
      throw arg_error(d == &q.from ? "from" : "to", "'" + *d + "' is not a date YYYY-MM-DD");
  std::vector<AuditEntry> out;
  // A device's rows through the audit_device index (a serial that names no device: none).
  auto st = conn_->prepare(
      std::string("SELECT a.id, a.at, a.\"user\", a.station, a.entity, a.entity_id, a.action, a.detail, a.db_role FROM audit_log a WHERE ") +
      (q.serial.empty() ? "" : "a.device_id = (SELECT id FROM devices WHERE serial = CAST(? AS TEXT)) AND ") +
      "(CAST(? AS TEXT) = '' OR a.db_role = CAST(? AS TEXT) OR lower(a.\"user\") = lower(CAST(? AS TEXT))) "
      "AND (CAST(? AS TEXT) = '' OR a.action = CAST(? AS TEXT)) "
      "AND (CAST(? AS TEXT) = '' OR substr(CAST(a.at AS TEXT), 1, 10) >= CAST(? AS TEXT)) "
      "AND (CAST(? AS TEXT) = '' OR substr(CAST(a.at AS TEXT), 1, 10) <= CAST(? AS TEXT)) "
      "ORDER BY a.id DESC LIMIT ?");
  int k = 1;
  if (!q.serial.empty()) st.bind(k++, q.serial);
  for (const std::string* v : {&q.who, &q.who, &q.who, &q.action, &q.action, &q.from, &q.from, &q.to, &q.to}) st.bind(k++, *v);
  st.bind(k, q.limit);
  while (st.step())
    out.push_back(AuditEntry{st.int64(0), st.text(1), st.text(2), st.text(3), st.text(4), st.int64(5), st.text(6),
                             st.text(7), st.text(8)});
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

std::int64_t Store::count_sets_with_status(SetStatus status) {
  auto st = conn_->prepare("SELECT COUNT(*) FROM coefficient_sets WHERE status = ?");
  st.bind(1, to_string(status));
  st.step();
  return st.int64(0);
}

std::vector<Store::RunEnd> Store::runs_ended_since(const std::string& iso_from) {
  std::vector<RunEnd> out;
  auto st = conn_->prepare(
      "SELECT COALESCE(sn.name, ''), r.ended_at, r.outcome FROM bench_runs r LEFT JOIN stations sn ON sn.id = r.station_id "
      "WHERE r.ended_at >= ? ORDER BY r.ended_at");
  st.bind(1, iso_from);
  while (st.step()) out.push_back(RunEnd{st.text(0), st.text(1), st.text(2)});
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
