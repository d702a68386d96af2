// calbench db …: the coefficient database (docs/database.md). The reading and approving subcommands
// are here with the registration of all; import-inmotion, store-bench and sync in cmd_db_write.cpp.
#include <cmath>
#include <filesystem>
#include <array>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "bench/approval_thresholds.hpp"
#include "bench/cli/db_args.hpp"
#include "bench/io/hdf5_recording.hpp"
#include "bench/cli/operator_option.hpp"
#include "bench/cli/number_options.hpp"
#include "bench/cli/registry.hpp"
#include "common/input_error.hpp"
#include "db/input_errors.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/imu_class_toml.hpp"
#include "calibration/imu_class.hpp"
#include "db/approval.hpp"
#include "db/approval_limits.hpp"
#include "db/fleet.hpp"
#include "db/signer.hpp"
#include "db/store.hpp"

namespace calbench::cli {
namespace {
using nlohmann::json;
using namespace calbench::db;
using namespace calbench::cli::dbcmd;

void add_db_option(CLI::App* sub, DbArgs& a) {
  sub->add_option("--db", a.db, "database: a SQLite file or a postgresql:// URI (default: $CALBENCH_DB, else ./calbench.db)");
}

void add_operator_option(CLI::App* sub, DbArgs& a) {
  cli::add_operator_option(sub, a.op,
                           "who you are, recorded with the change (default: $CALBENCH_OPERATOR, else the OS user, "
                           "which does not sign an approval)");
}

std::string fmt(double v, int prec = 4) {
  if (!std::isfinite(v)) return "unknown";
  std::ostringstream s;
  s << std::setprecision(prec) << v;
  return s.str();
}

json sigma_or_null(double s) { return std::isfinite(s) ? json(s) : json(nullptr); }

json set_json(const CoefficientSetRecord& s) {
  json j = {{"id", s.id},
            {"serial", s.serial},
            {"model", s.model},
            {"version", s.version},
            {"source", to_string(s.source)},
            {"fit_kind", fit_kind(s).empty() ? json(nullptr) : json(fit_kind(s))},
            {"status", to_string(s.status)},
            {"parent", s.parent_id ? json(*s.parent_id) : json(nullptr)},
            {"bench_run", s.bench_run_id ? json(*s.bench_run_id) : json(nullptr)},
            {"inmotion_run", s.inmotion_run_id ? json(*s.inmotion_run_id) : json(nullptr)},
            {"created_at", s.created_at},
            {"created_by", s.created_by}};
  return j;
}

json qc_json(const std::vector<QcResult>& qc) {
  json a = json::array();
  for (const auto& q : qc)
    a.push_back({{"metric", q.metric}, {"value", q.value}, {"threshold", q.threshold ? json(*q.threshold) : json(nullptr)},
                 {"pass", q.pass}, {"unit", q.unit}, {"sample", q.sample}, {"criterion", q.criterion}});
  return a;
}

// Short human summary of a set: bias and scale per axis in display units, with σ.
void print_set_summary(const CoefficientSetRecord& s) {
  for (const char* triad : {"gyro", "accel"}) {
    std::cout << "    " << std::left << std::setw(6) << triad;
    for (const char* ax : {"x", "y", "z"}) {
      const std::string n = std::string(triad) + ".bias." + ax;
      std::string unit;
      double k;
      display_unit(n, unit, k);
      std::cout << " b" << ax << "=" << fmt(coefficient_value(s.errors, n) * k) << "±"
                << fmt(coefficient_sigma(s.errors, n) * k, 2) << " " << unit;
    }
    for (const char* ax : {"xx", "yy", "zz"}) {
      const std::string n = std::string(triad) + ".M." + ax;
      std::cout << " s" << ax[0] << "=" << fmt(coefficient_value(s.errors, n) * 1e6) << "±"
                << fmt(coefficient_sigma(s.errors, n) * 1e6, 2) << " ppm";
    }
    std::cout << "\n";
  }
}

void cmd_init(const DbArgs& a) {
  auto s = open_store(a, true);
  if (a.roles) {
    if (s->connection().dialect() != Dialect::postgres)
      throw arg_error("--roles", "roles are PostgreSQL's (a SQLite file has no users): give --db postgresql://OWNER@HOST/DB");
    s->apply_roles();
  }
  if (s->authenticated()) {  // the device classes' coefficient limits, held by the database itself
    publish_approval_limits(*s, "*", db::default_thresholds(), "built-in ADIS16488A defaults");
    for (const auto& c : builtin_imu_classes()) {
      const db::Thresholds t = approval_thresholds("", c.name);
      for (const auto& m : c.aliases) db::publish_approval_limits(*s, normalized_model_name(m), t, "class " + c.name);
      publish_approval_limits(*s, normalized_model_name(c.name), t, "class " + c.name);
    }
  }
  std::cout << "database " << s->connection().path() << " ready (schema version " << s->schema_version() << ")"
            << (a.roles ? "; roles calbench_station, calbench_qc, calbench_provisioning, calbench_reader in place" : "")
            << "\n";
}

void cmd_devices(const DbArgs& a) {
  auto s = open_store(a);
  const auto list = s->device_summaries();
  if (a.json) {
    json arr = json::array();
    for (const auto& d : list)
      arr.push_back({{"serial", d.device.serial}, {"model", d.device.model}, {"firmware", d.device.firmware},
                     {"sets", d.sets}, {"latest_version", d.latest_version ? json(*d.latest_version) : json(nullptr)},
                     {"latest_status", d.latest_status}, {"latest_source", d.latest_source}});
    print_json(json{{"devices", arr}}.dump(2));
    return;
  }
  // Columns as wide as their widest entry (a long firmware string ran into the next column).
  std::vector<std::array<std::string, 5>> rows{{"SERIAL", "MODEL", "FIRMWARE", "SETS", "LATEST"}};
  for (const auto& d : list)
    rows.push_back({d.device.serial, d.device.model, d.device.firmware.empty() ? "-" : d.device.firmware, std::to_string(d.sets),
                    d.latest_version ? "v" + std::to_string(*d.latest_version) + " " + d.latest_source + " " + d.latest_status
                                     : std::string("-")});
  std::array<std::size_t, 5> w{};
  for (const auto& r : rows)
    for (std::size_t c = 0; c < 5; ++c) w[c] = std::max(w[c], r[c].size());
  for (const auto& r : rows) {
    for (std::size_t c = 0; c < 4; ++c) std::cout << std::left << std::setw(static_cast<int>(w[c] + 2)) << r[c];
    std::cout << r[4] << "\n";
  }
  std::cout << list.size() << " device(s)\n";
}

Device need_device(Store& s, const std::string& serial) {
  auto d = s.find_device(serial);
  if (!d) throw arg_error("SERIAL", "unknown device '" + serial + "' in " + s.connection().path());
  return *d;
}

void cmd_show(const DbArgs& a) {
  auto s = open_store(a);
  const Device d = need_device(*s, a.serial);
  const auto sets = s->sets_of(d.id);
  const auto prov = s->provisioning_of(d.id);
  if (a.json) {
    json js = json::array();
    for (const auto& x : sets) {
      json j = set_json(x);
      j["coefficients"] = json::parse(x.payload_json);
      j["qc"] = qc_json(s->qc_of_set(x));
      js.push_back(j);
    }
    json jp = json::array();
    for (const auto& p : prov)
      jp.push_back({{"id", p.id}, {"set", p.set_id}, {"kind", p.kind}, {"target", p.target}, {"ok", p.ok},
                    {"readback", json::parse(p.readback_json)}, {"message", p.message}, {"actor", p.actor}, {"at", p.at}});
    print_json(json{{"device", {{"serial", d.serial}, {"model", d.model}, {"firmware", d.firmware}, {"created_at", d.created_at}}},
                    {"sets", js},
                    {"provisioning", jp}}
                   .dump(2));
    return;
  }
  std::cout << d.model << " " << d.serial << (d.firmware.empty() ? "" : ", firmware " + d.firmware) << ", since "
            << d.created_at << "\n";
  std::cout << "coefficient sets:\n";
  for (const auto& x : sets) {
    std::cout << "  set " << x.id << "  v" << x.version << "  " << source_label(x) << "  " << to_string(x.status)
              << (x.parent_id ? "  parent " + std::to_string(*x.parent_id) : std::string()) << "  " << x.created_at
              << "  by " << x.created_by << "\n";
    print_set_summary(x);
    for (const auto& q : s->qc_of_set(x))
      std::cout << "    QC " << q.metric << " = " << fmt(q.value) << (q.unit.empty() ? "" : " " + q.unit)
                << (q.threshold ? " (threshold " + fmt(*q.threshold) + ")" : std::string())
                << (q.informative() ? " informative" : q.pass ? " pass" : " FAIL") << (q.sample.empty() ? "" : ", " + q.sample)
                << "\n";
  }
  if (sets.empty()) std::cout << "  (none)\n";
  if (!prov.empty()) std::cout << "provisioning:\n";
  for (const auto& p : prov)
    std::cout << "  " << p.at << "  set " << p.set_id << "  " << p.kind << " " << p.target << "  "
              << (p.ok ? "ok" : "FAILED") << (p.message.empty() ? "" : "  " + p.message) << "\n";
}

void cmd_history(const DbArgs& a) {
  auto s = open_store(a);
  const Device d = need_device(*s, a.serial);
  const auto log = s->audit_of_device(d.id);
  const bool auth = s->authenticated();
  if (a.json) {
    json arr = json::array();
    for (const auto& e : log) {
      json j = {{"id", e.id}, {"at", e.at}, {"user", e.user}, {"station", e.station}, {"entity", e.entity},
                {"entity_id", e.entity_id}, {"action", e.action}, {"detail", e.detail},
                {"login", e.login.empty() ? json(nullptr) : json(e.login)}, {"name", e.user}, {"authenticated", auth}};
      // A bench run: where its recording is (absolute URI) and the digest of all its files.
      if (e.entity == "bench_run")
        if (const auto r = s->bench_run(e.entity_id))
          j["recording"] = {{"path", r->recording_path}, {"uri", r->recording_uri}, {"digest_sha256", r->recording_digest},
                            // The key predates HDF5 recordings: the SHA-256 of the IMU table's file, named by
                            // imu_table_file (null when the recording is not at hand).
                            {"imu_csv_sha256", r->recording_sha256},
                            {"imu_table_file", imu_table_file_name(r->recording_path).empty()
                                                   ? json(nullptr)
                                                   : json(imu_table_file_name(r->recording_path))}};
      // An in-motion run: the same for its drive recording ("" in results written before them).
      if (e.entity == "inmotion_run")
        if (const auto r = s->inmotion_run(e.entity_id))
          j["recording"] = {{"path", r->recording_path}, {"uri", r->recording_uri}, {"digest_sha256", r->recording_digest},
                            {"imu_csv_sha256", r->recording_sha256}};
      arr.push_back(j);
    }
    print_json(json{{"serial", d.serial}, {"authenticated", auth}, {"history", arr}}.dump(2));
    return;
  }
  for (const auto& e : log) {
    const std::string note = signature_note(e.login, auth);
    std::cout << e.at << "  " << e.user << "@" << e.station << "  " << e.entity << " " << e.entity_id << "  "
              << e.action << (e.detail.empty() ? "" : "  " + e.detail) << (note.empty() ? "" : "  [" + note + "]")
              << "\n";
    if (e.entity == "bench_run")
      if (const auto r = s->bench_run(e.entity_id)) {
        if (!r->recording_uri.empty())
          std::cout << "    recording " << r->recording_uri << "  SHA-256 of its files " << r->recording_digest << "\n";
        if (!r->recording_sha256.empty())
          std::cout << "    SHA-256 of " << imu_table_file_label(r->recording_path) << " " << r->recording_sha256 << "\n";
      }
    if (e.entity == "inmotion_run")
      if (const auto r = s->inmotion_run(e.entity_id); r && !r->recording_uri.empty())
        std::cout << "    recording " << r->recording_uri << "  SHA-256 of its files " << r->recording_digest << "\n";
  }
}

void cmd_approve(const DbArgs& a) {
  auto s = open_store(a);
  // Without a file, the defaults of the set's device class (its model).
  const Thresholds t = approval_thresholds(a.thresholds, a.thresholds.empty() ? s->get_set(a.set).model : "");
  const ApprovalCheck r = approve_checked(*s, a.set, t);
  if (a.json)
    print_json(json{{"set", a.set}, {"approved", r.ok}, {"already_approved", r.already}, {"reasons", r.reasons}, {"thresholds", t.source}}
                   .dump(2));
  if (r.already) {
    if (!a.json) std::cout << "set " << a.set << " is already " << to_string(s->get_set(a.set).status) << " (no change)\n";
    return;
  }
  if (r.ok) {
    if (!a.json) std::cout << "set " << a.set << " approved (thresholds: " << t.source << ")\n";
    return;
  }
  if (!a.json) {
    std::cerr << "calbench: set " << a.set << " NOT approved (thresholds: " << t.source << "):\n";
    for (const auto& why : r.reasons) std::cerr << "  - " << why << "\n";
  }
  throw Exit{1};
}

void cmd_revoke(const DbArgs& a) {
  auto s = open_store(a);
  // Revoking a revoked set again changes nothing and is not an error (as approving an approved set).
  if (s->get_set(a.set).status == SetStatus::revoked) {
    std::cout << "set " << a.set << " is already revoked (no change)\n";
    return;
  }
  s->set_status(a.set, SetStatus::revoked, a.reason);
  std::cout << "set " << a.set << " revoked" << (a.reason.empty() ? "" : ": " + a.reason) << "\n";
}

void cmd_settings(const DbArgs& a) {
  auto s = open_store(a);
  if (!a.key.empty() && !a.value.empty()) {
    const std::string before = s->setting(a.key);
    s->set_setting(a.key, a.value);
    std::cout << a.key << ": " << before << " -> " << a.value << " (by " << s->actor().user << ")\n";
    return;
  }
  const auto all = s->settings();
  if (a.json) {
    json arr = json::array();
    for (const auto& x : all)
      if (a.key.empty() || x.key == a.key)
        arr.push_back({{"key", x.key}, {"value", x.value}, {"default", x.changed_at.empty()},
                       {"changed_at", x.changed_at}, {"changed_by", x.changed_by}});
    print_json(json{{"settings", arr}}.dump(2));
    return;
  }
  bool found = false;
  for (const auto& x : all) {
    if (!a.key.empty() && x.key != a.key) continue;
    found = true;
    std::cout << x.key << " = " << x.value
              << (x.changed_at.empty() ? "  (built-in default)" : "  (set by " + x.changed_by + " at " + x.changed_at + ")")
              << "\n";
  }
  if (!found) s->setting(a.key);  // throws: unknown setting, with the list of known ones
}

void cmd_export(const DbArgs& a) {
  auto s = open_store(a);
  const auto set = s->get_set(a.set);
  write_text_atomic(a.out, set.payload_json + "\n");
  std::cout << "set " << set.id << " (" << set.serial << " v" << set.version << ", " << to_string(set.status)
            << ") written to " << a.out << "\n";
}

void cmd_fleet(const DbArgs& a) {
  auto s = open_store(a);
  const auto values = s->fleet();
  const auto stats = fleet_stats(values);
  const auto stations = station_stats(values);
  if (a.json) {
    json arr = json::array();
    for (const auto& c : stats) {
      json outl = json::array();
      for (const auto& p : c.points)
        if (p.outlier) outl.push_back({{"serial", p.serial}, {"set", p.set_id}, {"value", p.value}, {"z", sigma_or_null(p.z)}});
      arr.push_back({{"name", c.name}, {"n", c.n}, {"median", c.median}, {"mad", c.mad}, {"mean", c.mean},
                     {"stddev", c.stddev}, {"min", c.min}, {"max", c.max}, {"outliers", outl}, {"outliers_judged", c.judged}});
    }
    json sts = json::array();
    for (const auto& st : stations) {
      json flagged = json::array();
      for (const auto& c : st.coefficients)
        if (c.offset_flag || c.spread_flag)
          flagged.push_back({{"name", c.name}, {"median", c.median}, {"median_others", c.median_others},
                             {"z", sigma_or_null(c.z)}, {"spread_ratio", sigma_or_null(c.spread_ratio)},
                             {"offset", c.offset_flag}, {"spread", c.spread_flag}});
      sts.push_back({{"station", st.station}, {"devices", st.devices}, {"serials", st.serials}, {"compared", st.tested},
                     {"flagged", st.flagged}, {"coefficients", flagged}});
    }
    print_json(json{{"units", "SI (rad/s, m/s², dimensionless)"}, {"outlier_rule", "|0.6745 (x - median) / MAD| > 3.5, judged from " + std::to_string(kOutlierMinUnits) + " devices"},
                    {"station_rule", "|median here - median elsewhere| / (1.2533 sqrt(s_here^2/n_here + s_else^2/n_else)) > 3.5, "
                                     "s = 1.4826 MAD; or MAD here / MAD elsewhere > 3 with >= 5 units"},
                    {"coefficients", arr}, {"stations", sts}}
                   .dump(2));
    return;
  }
  std::size_t devices = stats.empty() ? 0 : stats.front().n;
  std::cout << "fleet: " << devices << " device(s), newest non-revoked set of each\n";
  if (devices > 0 && devices < kOutlierMinUnits)
    std::cout << "outliers not judged: " << devices << " device(s) are too few for a distribution (" << kOutlierMinUnits
              << " needed)\n";
  std::cout << std::left << std::setw(14) << "COEFFICIENT" << std::setw(7) << "UNIT" << std::right << std::setw(12)
            << "MEDIAN" << std::setw(12) << "MAD" << std::setw(12) << "MIN" << std::setw(12) << "MAX" << "  OUTLIERS\n";
  for (const auto& c : stats) {
    std::string outl;
    for (const auto& p : c.points)
      if (p.outlier) outl += (outl.empty() ? "" : ", ") + p.serial;
    std::cout << std::left << std::setw(14) << c.name << std::setw(7) << c.unit << std::right << std::setw(12)
              << fmt(c.median * c.to_display) << std::setw(12) << fmt(c.mad * c.to_display) << std::setw(12)
              << fmt(c.min * c.to_display) << std::setw(12) << fmt(c.max * c.to_display) << "  "
              << (!c.judged ? "not judged" : outl.empty() ? "-" : outl) << "\n";
  }
  // Which station calibrated what; a station whose units drift apart from the others' is flagged.
  std::cout << "\nstations: each against the others (offset |z| > " << kStationZ << ", spread ratio > " << kStationSpread
            << ")\n";
  for (const auto& st : stations) {
    std::cout << "  " << std::left << std::setw(20) << (st.station.empty() ? "(unknown)" : st.station) << std::right
              << std::setw(4) << st.devices << " unit(s)  "
              << station_verdict(st) << "\n";
    for (const auto& c : st.coefficients)
      if (c.offset_flag || c.spread_flag)
        std::cout << "      " << c.name << ": median " << fmt(c.median * c.to_display) << " here, "
                  << fmt(c.median_others * c.to_display) << " elsewhere " << c.unit << " (z " << fmt(c.z, 3) << ", spread "
                  << fmt(c.spread_ratio, 3) << ")\n";
  }
}

template <class F>
CLI::App* leaf(CLI::App* db, const char* name, const char* help, std::shared_ptr<DbArgs> a, F fn) {
  auto* sub = db->add_subcommand(name, help);
  add_db_option(sub, *a);
  sub->callback([a, fn] { fn(*a); });
  return sub;
}

const bool registered = add_command(70, [](CLI::App& app) {
  auto a = std::make_shared<DbArgs>();
  auto* db = app.add_subcommand("db", "coefficient database: devices, versioned sets, approval, history");
  db->require_subcommand(1);
  auto* init = leaf(db, "init", "create the database (or migrate it to this version's schema)", a, cmd_init);
  add_operator_option(init, *a);
  init->add_flag("--roles", a->roles,
                 "PostgreSQL: also create the roles calbench_station, calbench_qc, calbench_provisioning and "
                 "calbench_reader with their grants and row rules (db/postgres/roles.sql; idempotent)");
  init->footer("--db takes a SQLite file or a PostgreSQL URI (postgresql://USER@HOST[:PORT]/DB[?sslmode=verify-full]);\n"
               "the password comes from PGPASSFILE, ~/.pgpass or PGPASSWORD and is never printed. On PostgreSQL, run\n"
               "init as the database's owner; then give each station and person a login role in one of the groups,\n"
               "e.g. CREATE ROLE station3 LOGIN PASSWORD '...' IN ROLE calbench_station (docs/database.md).");
  leaf(db, "devices", "list devices with their newest coefficient set", a, cmd_devices)
      ->add_flag("--json", a->json, "machine-readable output");
  auto* show = leaf(db, "show", "a device's coefficient sets (with σ, QC) and provisioning events", a, cmd_show);
  show->add_option("SERIAL", a->serial, "device serial number")->required();
  show->add_flag("--json", a->json, "machine-readable output");
  auto* hist = leaf(db, "history", "audit log of a device: every state change, who and when", a, cmd_history);
  hist->add_option("SERIAL", a->serial, "device serial number")->required();
  hist->add_flag("--json", a->json, "machine-readable output");
  auto* appr = leaf(db, "approve", "approve a draft set if it passes the QC thresholds (else list why not, exit 1)", a,
                    cmd_approve);
  appr->add_option("SET", a->set, "coefficient set id")->required()->check(set_id());
  appr->add_option("--thresholds", a->thresholds, "thresholds config (JSON; default: the built-in limits of the set's device class, bench/imu_classes/*.toml; ADIS16488A limits for a model of no class)");
  appr->add_flag("--json", a->json, "machine-readable output");
  add_operator_option(appr, *a);
  appr->footer("The approval is signed: a named operator (--operator or CALBENCH_OPERATOR) other than the one who\n"
               "stored the set (four-eyes; a one-person lab: calbench db settings four_eyes off). On PostgreSQL the\n"
               "signer is the login's person (calbench db user add): --operator may only name that person or the\n"
               "login, and four-eyes compares logins. On SQLite names compare ignoring case and spacing.");
  auto* rev = leaf(db, "revoke", "revoke a set (it can no longer be provisioned)", a, cmd_revoke);
  rev->add_option("SET", a->set, "coefficient set id")->required()->check(set_id());
  rev->add_option("--reason", a->reason, "why (recorded in the audit log)");
  add_operator_option(rev, *a);
  auto* set = leaf(db, "settings", "show or change a setting of this database (four_eyes on|off), audited", a,
                   cmd_settings);
  set->add_option("KEY", a->key, "setting name (four_eyes)");
  set->add_option("VALUE", a->value, "new value (changing needs a named operator)");
  set->add_flag("--json", a->json, "machine-readable output");
  add_operator_option(set, *a);
  auto* exp = leaf(db, "export", "write a set as coefficients.json", a, cmd_export);
  exp->add_option("SET", a->set, "coefficient set id")->required()->check(set_id());
  exp->add_option("--out", a->out, "output file")->required()
      ->check(non_empty());
  leaf(db, "fleet", "distribution of every coefficient across devices, outliers flagged (robust z > 3.5)", a, cmd_fleet)
      ->add_flag("--json", a->json, "machine-readable output");
  auto* imp = leaf(db, "import-inmotion", "store an in-motion fit result (RESULT.json) against its device", a,
                   cmd_import_inmotion);
  imp->add_option("RESULT", a->file,
                  "RESULT.json of `calbench fit drive`, or the --out folder of a multi-unit fit (units.json: every "
                  "fitted unit is stored, each against its device)")
      ->required();
  imp->add_option("--parent", a->parent, "set the fit started from (default: found by composition)")->check(set_id());
  imp->add_flag("--json", a->json, "machine-readable output");
  add_operator_option(imp, *a);
  add_user_commands(db, a);
  add_verify_command(db, a);
  auto* sync = leaf(db, "sync", "forward a station's journal to the central PostgreSQL store (exactly once)", a, cmd_sync);
  sync->add_option("--journal", a->journal, "the station's journal (default: $CALBENCH_JOURNAL, else ./calbench-journal.db)");
  sync->add_flag("--status", a->status, "only list what is pending (nothing is forwarded; exit 0 either way)");
  sync->add_flag("--json", a->json, "machine-readable output");
  add_operator_option(sync, *a);
  sync->footer("With --db postgresql://..., the station and db store-bench write each run and its set to the journal\n"
               "first and forward them at once when the server answers; what the server did not take waits there.\n"
               "Forwarding is idempotent (each run and set has a stable id): interrupted and run again, each item\n"
               "arrives exactly once. Exit 1 while anything stays pending.");
  auto* sb = leaf(db, "store-bench", "store a bench run and its coefficient set (draft)", a, cmd_store_bench);
  sb->add_option("--journal", a->journal,
                 "with a PostgreSQL --db: the local journal written first (default: $CALBENCH_JOURNAL, else ./calbench-journal.db)");
  sb->add_option("--coeffs", a->coeffs, "coefficients.json of the bench fit")->required();
  sb->add_option("--recording", a->recording, "bench recording folder (its imu.csv is hashed)");
  sb->add_option("--sha256", a->sha256, "SHA-256 of the IMU table's file (imu.csv, or recording.h5 for an HDF5 recording) instead of hashing it from --recording")
      ->check(CLI::Validator(
          [](const std::string& v) -> std::string {
            if (v.size() == 64 && v.find_first_not_of("0123456789abcdefABCDEF") == std::string::npos) return {};
            return "expected 64 hexadecimal digits (a SHA-256), got '" + v + "'";
          },
          "HEX64"));
  sb->add_option("--plan", a->plan, "bench plan name or path");
  sb->add_option("--station", a->station, "station name (default: $CALBENCH_STATION, else host name)");
  sb->add_option("--started", a->started, "start time, ISO 8601 UTC (e.g. 2026-11-27T08:30:00Z)")->check(iso8601_utc());
  sb->add_option("--ended", a->ended, "end time, ISO 8601 UTC")->check(iso8601_utc());
  sb->add_option("--outcome", a->outcome, "pass | fail | aborted")->check(CLI::IsMember({"pass", "fail", "aborted"}));
  sb->add_option("--firmware", a->firmware, "device firmware revision");
  sb->add_option("--qc", a->qc, "QC result NAME=VALUE[:THRESHOLD[:UNIT[:SAMPLE]]] (repeatable; SAMPLE in-sample, out-of-sample or \"not applicable\")");
  sb->add_flag("--json", a->json, "machine-readable output");
  add_operator_option(sb, *a);
});

}  // namespace
}  // namespace calbench::cli
