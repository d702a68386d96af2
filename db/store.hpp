// The coefficient store: devices, stations, bench runs, versioned coefficient sets, in-motion runs,
// QC results, provisioning events and an audit log, in one SQLite file (schema: db/schema.cpp,
// user documentation: docs/database.md).
//
// This is the API the station, the CLI and the reports use. Coefficient payloads cross it as the
// text of a `coefficients.json` document (spec: ../shared/spec/recording-format.md); the store
// validates it, keeps it verbatim (extra model terms included) and indexes every coefficient and
// σ so that fleet statistics are plain SQL. bench/io/coefficients_json.hpp converts that text
// to and from calbench::CoefficientSet.
//
// Every method that changes anything runs in one BEGIN IMMEDIATE transaction (all or nothing) and
// writes its audit-log entry in that same transaction. Bad input throws calbench::InputError
// before anything is written.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/coefficients_codec.hpp"  // the 24 indexed coefficients, CoefficientSet
#include "db/connection.hpp"

namespace calbench::db {

inline constexpr int kSchemaVersion = 9;

enum class SetSource { bench, in_motion, combined };
enum class SetStatus { draft, approved, provisioned, revoked };
std::string to_string(SetSource s);  // "bench" | "in-motion" | "combined"
std::string to_string(SetStatus s);  // "draft" | "approved" | "provisioned" | "revoked"
SetSource source_from_string(const std::string& s);
SetStatus status_from_string(const std::string& s);

// Who makes a change: the operator's name and the station, recorded with every audit entry, every
// set (created_by) and every provisioning event.
struct Actor {
  std::string user;
  std::string station;
  // Where `user` came from: "--operator", "CALBENCH_OPERATOR", "CALBENCH_USER" (older name of
  // CALBENCH_OPERATOR) — a named operator, a signature — or "OS user" (the login name, which
  // records who ran the command but does not sign an approval).
  std::string source = "OS user";
  // The OS user running the command (getpwuid(geteuid())), whatever name was typed: recorded beside
  // it on SQLite, where nothing is authenticated.
  std::string os_user;
  bool named() const { return source != "OS user"; }
  // The operator: `operator_option` (the CLI's --operator) if given, else $CALBENCH_OPERATOR, else
  // $CALBENCH_USER, else the OS user. Station: $CALBENCH_STATION, else the host name. A name must
  // be 1–64 printable characters without '@' (InputError naming where it came from).
  static Actor from_environment(const std::string& operator_option = "");
};
// What is wrong with an operator name (see Actor::from_environment), or "" when it is fine;
// check_operator_name throws it as an InputError naming `where` (the option or variable).
std::string operator_name_problem(const std::string& name);
void check_operator_name(const std::string& name, const std::string& where);

// Settings of one database (table `settings`), changed only through Store::set_setting (audited).
// "four_eyes": "on" (default) — an approval must be signed by a named operator other than the one
// who stored the set; "off" — a one-person lab: the same named operator may approve.
inline constexpr const char* kFourEyes = "four_eyes";
struct Setting {
  std::string key, value, changed_at, changed_by;  // changed_* empty: the built-in default
};

struct DeviceInfo {
  std::string model = "ADIS16488A";
  std::string serial;
  std::string firmware;  // may be empty (unknown); a later non-empty value updates the record
};

struct Device {
  std::int64_t id = 0;
  std::string model, serial, firmware, created_at;
};

// Which data a QC figure was computed on, relative to the data the set was fitted on.
inline constexpr const char* kInSample = "in-sample";
inline constexpr const char* kOutOfSample = "out-of-sample";
inline constexpr const char* kSampleNotApplicable = "not applicable";  // e.g. samples lost while recording

struct QcResult {
  std::string metric;
  double value = 0;
  std::optional<double> threshold;  // absent: informative only (pass is then true and means nothing)
  bool pass = true;
  std::string unit;
  std::string sample;     // kInSample, kOutOfSample, kSampleNotApplicable, or "" (not recorded)
  std::string criterion;  // how pass follows from value and threshold, e.g. "|value| ≤ threshold"
  // A figure to read, not a check: no threshold and no criterion (and so nothing that can fail).
  bool informative() const { return pass && !threshold && criterion.empty(); }
};

struct BenchRunInput {
  std::string station;          // station name; created on first use
  std::string plan;             // plan name or path
  std::string recording_path;   // the bench recording folder, as given
  std::string recording_sha256; // SHA-256 of the IMU table's file: imu.csv, or recording.h5 (or as the station defines it)
  std::string recording_uri;    // file://HOST/absolute/path of the folder (HOST: the station's host name)
  std::string recording_digest; // SHA-256 of every file of the folder (bench/io/recording_location.hpp)
  std::string started_at, ended_at;  // ISO 8601 UTC
  std::string outcome = "pass";  // "pass" | "fail" | "aborted"
  // Stable id of the run (forwarding from a station's journal): a run whose uid is already stored
  // is not stored again. Empty: a new random one. The run's set gets uid + "/set".
  std::string uid;
  std::vector<QcResult> qc;     // bench residuals and checks
  std::string slot;             // the unit's slot on a multi-unit fixture (empty: one unit)
  std::string table_run;        // the table cycle's id, shared by the units run together (may be empty)
};

struct BenchRun {
  std::int64_t id = 0, device_id = 0;
  std::string station, plan, recording_path, recording_sha256, started_at, ended_at, outcome, created_at;
  std::string slot, table_run;
  std::string recording_uri, recording_digest;  // "" before schema version 6
};

struct InMotionRun {
  std::int64_t id = 0, device_id = 0;
  std::string recording_path, recording_sha256, reference_system;
  std::array<double, 3> mounting_rpy_deg{}, mounting_sigma_deg{};
  std::string consistency_json, qc_json, result_json, created_at;
  // Where the drive recording is, as bench_runs.recording_uri / recording_digest: read from
  // result_json's recording.uri and recording.digest_sha256 ("" for results written before them).
  std::string recording_uri, recording_digest;
};

struct CoefficientSetRecord {
  std::int64_t id = 0, device_id = 0;
  std::string serial, model;
  int version = 0;
  SetSource source = SetSource::bench;
  SetStatus status = SetStatus::draft;
  std::optional<std::int64_t> parent_id, bench_run_id, inmotion_run_id;
  std::string payload_json;  // coefficients.json text
  std::string created_at, created_by;
  // The person who stored it (the operator name typed or signed in), in its own field (schema 9;
  // never parsed out of created_by "NAME@STATION").
  std::string creator;
  // The login that stored it: PostgreSQL's session_user (authenticated), SQLite's OS user (not);
  // "" for a set stored before schema version 6 on SQLite.
  std::string created_by_login;
  SensorErrors errors;  // the indexed coefficients (σ = +inf when unknown)
};

struct ProvisioningEvent {
  std::int64_t id = 0, set_id = 0, device_id = 0;
  std::string kind;    // "device" | "export"
  std::string target;  // IMU URI or file path
  bool ok = false;
  std::string readback_json, message, actor, at;
};

struct AuditEntry {
  std::int64_t id = 0;
  std::string at, user, station, entity;
  std::int64_t entity_id = 0;
  std::string action, detail;
  // The login that wrote it (PostgreSQL: session_user, authenticated; SQLite: the OS user, not
  // authenticated; "" before schema version 6 on SQLite).
  std::string login;
};

struct DeviceSummary {
  Device device;
  int sets = 0;
  std::optional<int> latest_version;
  std::string latest_status, latest_source;
};

// How a set is shown: its source, and for a bench-source set fitted from a multipos recording (no
// rate table: payload "source": {"kind": "multipos"}) "bench (multipos)".
std::string source_label(const CoefficientSetRecord& s);
// "multipos" for such a set, else "" (the JSON's "fit_kind").
std::string fit_kind(const CoefficientSetRecord& s);

struct StoredSet {
  std::int64_t device_id = 0, run_id = 0, set_id = 0;
  int version = 0;
  bool existed = false;  // the uid was already stored: these are the ids of that earlier store
};

// One row of the fleet view: one coefficient of the newest non-revoked set of one device.
struct FleetValue {
  std::string serial;
  std::int64_t set_id = 0;
  int version = 0;
  std::string status;
  std::string name;  // e.g. "gyro.bias.x", "accel.M.yz"
  double value = 0;
  double sigma = 0;  // +inf when unknown
  std::string station;  // the station of the bench run behind the set (or its parent's); "" unknown
};

// The 24 indexed coefficients (coefficient_names, coefficient_value, coefficient_sigma) are named
// by the codec, common/coefficients_codec.hpp.
// A new random id for a run or set (32 hex digits).
std::string new_uid();

// Parse and validate a coefficients.json text (spec schema; σ null = unknown). Throws InputError
// naming `file` and the key. `expect_serial` (if not empty) must equal device.serial.
struct ParsedCoefficients {
  DeviceInfo device;
  SensorErrors errors;
  std::string canonical_json;  // re-serialised, extra keys kept
};
ParsedCoefficients parse_coefficients(const std::string& text, const std::string& file,
                                      const std::string& expect_serial = "");
// A coefficients.json text for `errors` (spec schema), with `extra_json` (a JSON object text or
// empty) supplying extra keys.
std::string coefficients_json_text(const DeviceInfo& device, const SensorErrors& errors,
                                   const std::string& extra_json = "");

class Store {
 public:
  // $CALBENCH_DB if set, else "calbench.db" in the working directory.
  static std::string default_path();

  // Opens (and with create = true creates) the database and migrates its schema to
  // kSchemaVersion. A database of a newer schema is refused.
  Store(const std::string& path, const OpenOptions& opt = {}, Actor actor = Actor::from_environment());
  int schema_version();
  Connection& connection() { return *conn_; }
  // Fault injection for the crash-safety tests: called with a point name ("set-row",
  // "set-values") in the middle of writing a set. Not for production use.
  void set_test_hook(std::function<void(const char* point)> hook) { hook_ = std::move(hook); }
  const Actor& actor() const { return actor_; }
  // The login of this connection: PostgreSQL's session_user (authenticated), else the OS user.
  std::string login() const;
  bool authenticated() const { return conn_->dialect() == Dialect::postgres; }
  // The signer of an approval, revocation, setting change or provisioning (db/signer.cpp): on
  // PostgreSQL the login's person (db user add); an --operator that is not that person, or a login
  // mapped to nobody, is refused (InputError). Sets the actor's name to the person's.
  // `role`: the group that signs this kind of change ("qc": approvals, revocations, settings;
  // "provisioning": provisioning). SQLite with a console account (set_console_account): an account
  // of another role is refused here, as PostgreSQL's grants refuse the login.
  void check_signer(const char* role = "qc");
  // The web console's local account on a SQLite store (db/console_accounts.hpp), checked by its
  // password: login() becomes "console:LOGIN" and check_signer() enforces the account's role.
  const std::string& console_role() const { return console_role_; }  // "" without a console account
  void set_console_account(const std::string& login, const std::string& role) {
    console_login_ = login;
    console_role_ = role;
  }
  // Who the next changes are by (forwarding from a journal writes as the operator who ran the station).
  void set_actor(Actor a) { actor_ = std::move(a); }
  // "" when this connection may record provisioning events and mark sets provisioned, else why not
  // (PostgreSQL privileges of the session's role; SQLite: always).
  std::string may_record_provisioning();
  // PostgreSQL: create/refresh the four roles with their grants and row rules (roles.sql), audited.
  void apply_roles();

  // ---- writes (each one transaction, audited) ----
  // Creates the device if unknown (model/serial), updates firmware when given. Returns its id.
  std::int64_t ensure_device(const DeviceInfo& d);
  std::int64_t ensure_station(const std::string& name, const std::string& description = "");
  // A bench run and the coefficient set fitted from it (source bench, status draft), atomically.
  StoredSet store_bench(const DeviceInfo& d, const BenchRunInput& run, const std::string& coefficients_json);
  // A coefficient set without a run (e.g. imported from a file), source as given.
  StoredSet store_set(const DeviceInfo& d, SetSource source, const std::string& coefficients_json,
                      std::optional<std::int64_t> parent = std::nullopt, const std::string& uid = "");
  // Status changes. approve() does not check thresholds: use approve_checked() (db/approval.hpp).
  void set_status(std::int64_t set_id, SetStatus to, const std::string& reason);
  void record_provisioning(std::int64_t set_id, const std::string& kind, const std::string& target, bool ok,
                           const std::string& readback_json, const std::string& message);
  void audit(const std::string& entity, std::int64_t entity_id, const std::string& action, const std::string& detail);
  // A security event that changed nothing: a failed log-in ("login-failed"), a lock-out ("lockout"),
  // a request refused for the account's role ("refused"). Audited as entity "security" naming the
  // login tried, never a password; on PostgreSQL through calbench_audit_security(), the only way a
  // login writes such a row (it cannot write a signature's).
  void audit_security(const std::string& action, const std::string& login, const std::string& detail);
  // A bench run that produced no set (outcome "aborted" or "fail"), with why, so that `db history`
  // shows it. Returns the run id.
  // *existed (if given): the run's uid was already stored (the id is that run's).
  std::int64_t store_bench_run(const DeviceInfo& d, const BenchRunInput& run, const std::string& reason,
                               bool* existed = nullptr);
  // Settings (see kFourEyes). set_setting() needs a named operator and a known key and value.
  void set_setting(const std::string& key, const std::string& value);
  std::string setting(const std::string& key);  // the value, or the built-in default
  std::vector<Setting> settings();               // every known key, default or set

  // ---- reads ----
  std::optional<Device> find_device(const std::string& serial);
  std::vector<Device> devices();
  std::vector<DeviceSummary> device_summaries();
  std::optional<CoefficientSetRecord> find_set(std::int64_t set_id);
  CoefficientSetRecord get_set(std::int64_t set_id);  // InputError when missing
  std::vector<CoefficientSetRecord> sets_of(std::int64_t device_id);  // by version
  // Every set of the device with its status, by version, whatever this role may read of the sets
  // themselves (PostgreSQL: provisioning sees no draft, but is told that one waits).
  struct SetStatusRow {
    std::int64_t id = 0;
    int version = 0;
    SetStatus status = SetStatus::draft;
  };
  std::vector<SetStatusRow> set_statuses(std::int64_t device_id);
  // Newest set of the device with the given status (e.g. approved), if any.
  std::optional<CoefficientSetRecord> latest_set(std::int64_t device_id, std::optional<SetStatus> status);
  std::optional<BenchRun> bench_run(std::int64_t id);
  std::optional<InMotionRun> inmotion_run(std::int64_t id);
  std::vector<QcResult> qc_of_bench_run(std::int64_t id);
  std::vector<QcResult> qc_of_inmotion_run(std::int64_t id);
  // QC results that speak for a set: those of its bench run or in-motion run.
  std::vector<QcResult> qc_of_set(const CoefficientSetRecord& s);
  std::vector<ProvisioningEvent> provisioning_of(std::int64_t device_id);
  std::vector<AuditEntry> audit_of_device(std::int64_t device_id);
  std::vector<FleetValue> fleet();
  // Bench runs that ended at or after `iso_from` (ISO 8601 UTC, as the store writes them): the fleet
  // dashboard's units per hour.
  struct RunEnd {
    std::string station, ended_at, outcome;
  };
  std::vector<RunEnd> runs_ended_since(const std::string& iso_from);
  // The web console's reads (issue 38): the sets of one status, oldest first (the QC queue: drafts),
  // and the audit log searched by device serial, login or typed name, action and date range
  // (YYYY-MM-DD, inclusive; empty fields: any), newest first.
  std::vector<CoefficientSetRecord> sets_with_status(SetStatus status, int limit, std::int64_t offset = 0);
  std::int64_t count_sets_with_status(SetStatus status);
  struct AuditQuery {
    std::string serial, who, action, from, to;
    int limit = 200;
  };
  std::vector<AuditEntry> audit_search(const AuditQuery& q);
  std::int64_t count(const char* table);  // rows of a known table (for checks and tests)

  // Internal helpers shared by the import code.
  std::int64_t insert_set_locked(std::int64_t device_id, SetSource source, const std::string& canonical_json,
                                 const SensorErrors& e, std::optional<std::int64_t> parent,
                                 std::optional<std::int64_t> bench_run, std::optional<std::int64_t> inmotion_run,
                                 int* version_out, const std::string& uid = "", bool* existed = nullptr);
  void insert_qc_locked(const std::vector<QcResult>& qc, std::optional<std::int64_t> bench_run,
                        std::optional<std::int64_t> inmotion_run);
  std::int64_t ensure_device_locked(const DeviceInfo& d);
  void audit_locked(const std::string& entity, std::int64_t entity_id, const std::string& action,
                    const std::string& detail);
  // The audit row itself (SQLite: with its hash-chain link; PostgreSQL: through the server's
  // functions where a login may write it), inside the caller's transaction.
  void insert_audit_locked(const std::string& entity, std::int64_t entity_id, std::optional<std::int64_t> device,
                           const std::string& action, const std::string& detail);

 private:
  CoefficientSetRecord read_set_row(Statement& st);
  void migrate();
  void migrate_postgres();
  void audit_migration(int from);
  std::unique_ptr<Connection> conn_;
  Actor actor_;
  std::function<void(const char*)> hook_;
  std::string console_login_, console_role_;
};

}  // namespace calbench::db
