// Store settings (four-eyes), the status of a set (approve, revoke, provisioned) and provisioning
// events: the changes made to what is already stored, each audited.
#include <algorithm>

#include <stdexcept>

#include "db/input_errors.hpp"
#include "db/store.hpp"

namespace calbench::db {

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
  check_signer();
  if (!actor_.named())
    throw DbError(1, "changing a setting needs a named operator (--operator NAME or CALBENCH_OPERATOR); the OS "
                     "user '" + actor_.user + "' is not a signature");
  if (conn_->dialect() == Dialect::postgres) {
    conn_->write_transaction([&] {  // the server checks the group and writes the audit row
      auto st = conn_->prepare("SELECT calbench_set_setting(?, ?, ?)");
      st.bind(1, key).bind(2, value).bind(3, actor_.station).step();
    });
    return;
  }
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
  check_signer();
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
    if (conn_->dialect() == Dialect::postgres) {
      // Schema 9: a revocation through the server (group, person, audit row); an approval only
      // through approve_checked (calbench_approve runs the database's verdict and four-eyes).
      if (to != SetStatus::revoked)
        throw std::logic_error("Store::set_status on PostgreSQL: only revocations (approve_checked, record_provisioning)");
      auto f = conn_->prepare("SELECT calbench_revoke(?, ?, ?)");
      f.bind(1, set_id).bind(2, reason).bind(3, actor_.station).step();
      return;
    }
    // The audit row first: an approval's signed row must precede the change (SQLite schema 9's
    // trigger coefficient_sets_approval_signed).
    audit_locked("coefficient_set", set_id, "status",
                 to_string(from) + " -> " + to_string(to) + (reason.empty() ? "" : ": " + reason));
    auto up = conn_->prepare("UPDATE coefficient_sets SET status = ? WHERE id = ?");
    up.bind(1, to_string(to)).bind(2, set_id).run();
  });
}

void Store::record_provisioning(std::int64_t set_id, const std::string& kind, const std::string& target, bool ok,
                                const std::string& readback_json, const std::string& message) {
  if (kind != "device" && kind != "export") throw arg_error("kind", "expected device or export");
  check_text(target, "target", true);
  check_signer("provisioning");
  if (conn_->dialect() == Dialect::postgres) {
    // The server checks the group, the signed approval row and its verdict, and writes the event,
    // the audit rows and the status together.
    conn_->write_transaction([&] {
      auto f = conn_->prepare("SELECT calbench_record_provisioning(?, ?, ?, ?, ?, ?, ?)");
      f.bind(1, set_id).bind(2, kind).bind(3, target).bind(4, ok).bind(5, readback_json).bind(6, message)
          .bind(7, actor_.station).step();
    });
    return;
  }
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

}  // namespace calbench::db
