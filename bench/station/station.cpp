#include "bench/station/station.hpp"
#include "bench/multipos/fit_multipos_run.hpp"
#include "common/noise_spec.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <optional>
#include <ostream>
#include <vector>

#include "bench/bench_recording.hpp"
#include "bench/io/coefficients_json.hpp"
#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/plan_toml.hpp"
#include "bench/io/recording.hpp"
#include "bench/io/recording_location.hpp"
#include "bench/station/fixture.hpp"
#include "bench/station/live.hpp"
#include "bench/station/run_summary.hpp"
#include "bench/station/step_runner.hpp"
#include "bench/station/unit.hpp"
#include "calibration/bench_fit.hpp"
#include "calibration/bench_kinematics.hpp"
#include "calibration/earth.hpp"
#include "common/imu_error_sim.hpp"
#include "common/json_fields.hpp"
#include "common/units.hpp"
#include "db/access_check.hpp"
#include "db/journal.hpp"
#include "db/store.hpp"
#include "devices/adis16488a.hpp"
#include "devices/adis16488a_emulator.hpp"
#include "devices/imu_open.hpp"
#include "devices/table_client.hpp"
#include "devices/table_emulator.hpp"

namespace calbench::station {
namespace {
using namespace devices;
constexpr int kInner = 1;  // the table's inner axis

std::string iso_utc(std::chrono::system_clock::time_point tp) {
  const std::time_t t = std::chrono::system_clock::to_time_t(tp);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char b[32];
  std::strftime(b, sizeof b, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return b;
}

// The fit of a positions plan's recording (kind "multipos"): the one place the station calls the
// multi-position estimator (fit_multipos_set, bench/multipos/fit_multipos_run.hpp; docs/multipos.md).
// A recording whose poses do not determine the coefficients is an InputError naming what to add.
CoefficientSet fit_positions_recording(const fs::path& rec_dir, nlohmann::json& report) {
  FitMultiposArgs a;
  a.dir = rec_dir.string();
  MultiposSetResult r = fit_multipos_set(a);
  const auto& m = r.set.extra["multipos"];
  report = {{"method", "multipos"},
            {"poses", m["statics"].size()},
            {"rotations", m["rotations"].size()},
            {"g_spread_raw_m_s2", m["g_spread_raw_m_s2"]},
            {"g_spread_m_s2", m["g_spread_m_s2"]},
            {"rotation_rms_deg", m["rotation_rms_deg"]},
            {"accel_chi2_dof", m["accel_chi2_dof"]},
            {"gyro_chi2_dof", m["gyro_chi2_dof"]}};
  return std::move(r.set);
}

// The station: setup (fixture, units, table, checks before anything moves), the plan through its step
// runner, the fit and store of each unit, and every path out — which stops the table.
class Station {
 public:
  Station(const Options& o, std::ostream& log, const std::atomic<bool>& stop) : o_(o), log_(log), stop_(stop) {}
  ~Station() {
    if (runner_) runner_->stop_readers();
  }
  Result run();

 private:
  void setup();
  void make_units();
  void connect_unit(Unit& u);
  void finish_unit(Unit& u);
  void record_aborted(Unit& u, const std::string& outcome, const std::string& why, Result& res);
  RunFacts facts() const {
    return {fixture_, fixture_mode_, units_, o_.out_dir, plan_.steps.size(), run_id_,
            clock_ ? clock_->now() : (wall_clock_ ? wall_clock_->now() : 0.0),
            std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count()};
  }
  // The store and the bench-run record of this run (the done and the aborted run share them).
  std::unique_ptr<db::Store> open_store() const;
  std::string station_label() const;  // the station's name in the store
  std::string store_path() const;  // the SQLite file written: --db, or the journal of a central --db
  void forward(db::Store& journal, nlohmann::json& summary, const std::string& uid);
  db::BenchRunInput bench_run_record(const Unit& u, const std::string& outcome,
                                     const std::string& recording) const;

  const Options& o_;
  std::ostream& log_;
  const std::atomic<bool>& stop_;
  StationPlan plan_;
  Fixture fixture_;
  bool fixture_mode_ = false;             // a fixture (file or --units): one folder per slot
  std::string run_id_ = db::new_uid();    // ties the units of one table cycle
  std::unique_ptr<SiteEarth> earth_;
  std::shared_ptr<VirtualClock> clock_;   // emulated time (the table's; several units: the slowest unit's)
  std::shared_ptr<WallClock> wall_clock_;
  std::unique_ptr<TableEmulator> table_emu_;
  std::unique_ptr<TableClient> table_;
  Units units_;
  std::unique_ptr<LiveView> live_;        // the slots' progress rows and the prompts (with --db)
  std::unique_ptr<StepRunner> runner_;    // from setup on (the emulated units' physics read its mount)
  std::chrono::steady_clock::time_point wall0_ = std::chrono::steady_clock::now();
  std::string started_ = iso_utc(std::chrono::system_clock::now());
};

void Station::make_units() {
  // Which fixture: --fixture, else --units N (emulated), else the plan's [plan] fixture, else one unit.
  fs::path ffile = o_.fixture_file;
  if (ffile.empty() && o_.units == 0 && !plan_.fixture_file.empty()) ffile = plan_.fixture_file;
  if (o_.units > 0 && !o_.emulated)
    throw InputError("--units", 0, "", "an emulated fixture needs --emulated (a real fixture is a --fixture file)");
  if (o_.units > 0 && !o_.fixture_file.empty())
    throw InputError("--units", 0, "", "either --units (emulated units) or --fixture FILE, not both");
  if (!ffile.empty()) fixture_ = load_fixture(ffile);
  else if (o_.units > 0) fixture_ = emulated_fixture(o_.units);
  else fixture_ = single_unit_fixture(o_.emulated ? std::string() : o_.imu_uri);
  fixture_mode_ = !ffile.empty() || o_.units > 0;
  if (fixture_mode_ && !o_.imu_uri.empty())
    throw std::invalid_argument("--imu: the fixture names each slot's IMU (" + (ffile.empty() ? "--units" : ffile.string()) + ")");
  if (!fixture_mode_ && !o_.emulated && o_.imu_uri.empty()) throw std::invalid_argument("--imu is required without --emulated");
  // Bus arbitration (one bridge per unit) and the slots' IMUs were checked with the fixture
  // (bench/station/fixture.hpp), the same for an emulated and a real run.
  for (const auto& [name, _] : o_.inject.slot)
    if (!fixture_.has_slot(name))
      throw InputError("--inject", 0, name, "no slot '" + name + "' in the fixture (slots: " + fixture_.slot_names() + ")");
  const bool several = fixture_.slots.size() > 1;
  for (std::size_t k = 0; k < fixture_.slots.size(); ++k) {
    auto u = std::make_unique<Unit>();
    u->slot = fixture_.slots[k];
    u->at_centre = u->slot.pose.C_f_s.isIdentity(0) && u->slot.pose.r_f.isZero(0);
    u->out = fixture_mode_ ? o_.out_dir / u->slot.name : o_.out_dir;
    u->rec_dir = u->out / "recording";
    u->seed = o_.seed + k;
    const auto it = o_.inject.slot.find(u->slot.name);
    u->inj = it != o_.inject.slot.end() ? it->second : o_.inject.imu;
    if (o_.emulated && clock_ && several) u->clock = std::make_shared<VirtualClock>(clock_->now());
    units_.push_back(std::move(u));
  }
}

void Station::setup() {
  plan_ = load_plan(o_.plan_file);
  if (plan_.steps.empty()) throw std::runtime_error(o_.plan_file.string() + ": the plan has no steps");
  std::string table_uri = o_.table_uri;
  if (o_.emulated) {
    if (table_uri.empty()) clock_ = std::make_shared<VirtualClock>();
    // External table (e.g. `calbench emulate table`): real time, and the emulated IMUs' physics follow
    // the table's reported encoder states (last poll, extrapolated with the reported rate).
    else wall_clock_ = std::make_shared<WallClock>(1.0);
  } else if (table_uri.empty()) {
    throw std::invalid_argument("--table is required without --emulated");
  }
  make_units();
  // A prompt about one slot names a slot of this fixture (found before anything moves).
  if (fixture_mode_)
    for (const PlanPrompt& p : plan_.prompts)
      if (!p.slot.empty() && !fixture_.has_slot(p.slot))
        throw InputError(o_.plan_file.string(), p.line, "slot",
                         "the prompt names slot '" + p.slot + "', not a slot of fixture " + fixture_.name + " (slots: " +
                             fixture_.slot_names() + ")");
  // Where the results go is checked before anything moves (a wrong --out or --db found after the
  // plan costs a table cycle); nothing is written yet: a missing database is created at the end.
  check_output_folder(o_.out_dir);
  if (!o_.db.empty()) {
    db::check_target(o_.db);
    // A central store: its credentials, schema version and the role's privileges are checked before
    // anything moves (found at the end, they cost a table cycle). A server that does not answer is the
    // offline case: the journal takes the run, said here, and forwards it at the end if it answers then.
    if (db::is_postgres_uri(o_.db)) {
      const db::StationAccess acc = db::check_station_access(o_.db);
      if (acc.state == db::StationAccess::State::refused)
        throw InputError("--db", 0, "", acc.reason);
      if (acc.state == db::StationAccess::State::unreachable)
        log_ << "central store not reached at start (" << acc.reason << "): the run goes to the journal "
             << store_path() << ", forwarded at the end if the server answers then, else by `calbench db sync`\n";
      else
        log_ << "central store " << db::redact_uri(o_.db) << ": role " << acc.role
             << " may store the run (schema current)\n";
    }
    const std::string local = store_path();
    if (fs::exists(local)) db::Store check(local);  // a calbench database (named InputError otherwise)
    else check_output_path(local);
  }
  earth_ = std::make_unique<SiteEarth>(plan_.site);
  const double plan_s = plan_duration_s(plan_);
  // What the run will write, before anything moves: imu.csv and reference.csv at 17 significant
  // digits take about 337 bytes per sample together (measured on the factory plan: 413 MB for
  // 1,225,118 samples), at the ADIS16488A's 2460 Hz, per unit. Refused when the disk cannot hold it
  // (with 20 % to spare): a full disk in the middle of a plan costs a table cycle.
  {
    constexpr double kBytesPerSample = 337, kMargin = 1.2;
    double recorded_s = 0;  // the steps' data time (moves and re-mounts record nothing)
    for (const auto& st : plan_.steps) recorded_s += st.dwell_s;
    const double bytes =
        recorded_s * adis16488a_noise().output_rate_hz * kBytesPerSample * static_cast<double>(units_.size());
    fs::path probe = o_.out_dir;
    while (!probe.empty() && !fs::exists(probe)) probe = probe.parent_path();
    if (probe.empty()) probe = ".";
    std::error_code ec;
    const fs::space_info sp = fs::space(probe, ec);
    char line[240];
    std::snprintf(line, sizeof line, "plan %s: %zu steps, about %.1f min, about %.0f MB to write into %s", plan_.name.c_str(),
                  plan_.steps.size(), plan_s / 60.0, bytes / 1e6, o_.out_dir.string().c_str());
    log_ << line;
    if (!ec) log_ << " (" << static_cast<long long>(static_cast<double>(sp.available) / 1e6) << " MB free)";
    log_ << "\n";
    if (fixture_mode_)
      log_ << "fixture " << fixture_.name << ": " << units_.size() << " unit" << (units_.size() > 1 ? "s" : "")
           << ", one bridge each, run " << run_id_ << "\n";
    if (!ec && static_cast<double>(sp.available) < kMargin * bytes)
      throw std::runtime_error("not enough free disk space for the recording: the plan writes about " +
                               std::to_string(std::llround(bytes / 1e6)) + " MB, " +
                               std::to_string(static_cast<long long>(static_cast<double>(sp.available) / 1e6)) + " MB are free at " +
                               probe.string());
  }
  runner_ = std::make_unique<StepRunner>(o_, log_, stop_, plan_, *earth_, units_, fixture_mode_, clock_, wall0_);
  live_ = std::make_unique<LiveView>(o_.db, run_id_, station_label(), log_);
  runner_->attach_live(*live_);
  if (o_.emulated && clock_) {
    TableEmulatorConfig tc;
    tc.watchdog_s = 0.5;
    tc.max_rate = std::max(tc.max_rate, plan_.table.max_rate * 1.2);
    tc.kill_at_s = o_.inject.table_kill_at_s;
    tc.position_only = plan_.position_only;  // a positions plan: the emulated table has no rate mode  // injected: the controller dies at this emulated time
    table_emu_ = std::make_unique<TableEmulator>(tc, clock_);
    table_emu_->start();
    table_uri = table_emu_->uri();
  }
  TableUri table_at;  // a malformed URI is bad input, found before any device is opened
  try {
    table_at = parse_table_uri(table_uri);
  } catch (const std::invalid_argument& e) {
    throw InputError("--table", 0, "", e.what());
  }
  for (auto& u : units_) {
    if (o_.emulated) {
      u->truth = draw_random_unit(u->seed);
      Adis16488aEmulatorConfig ic;
      ic.seed = u->seed;
      ic.serial = static_cast<std::uint16_t>(1000 + u->seed % 60000);
      // Injected faults (--inject): a wrong part, a failing self-test, or a unit that fails in service
      // (error flags, lost samples: once it has passed its self-test).
      ic.faults = u->inj;
      ic.faults.after_self_test = true;
      std::shared_ptr<EmuClock> imu_clock = wall_clock_ ? std::shared_ptr<EmuClock>(wall_clock_)
                                            : u->clock  ? std::shared_ptr<EmuClock>(u->clock)
                                                        : std::shared_ptr<EmuClock>(clock_);
      Unit* up = u.get();
      auto emu = std::make_unique<Adis16488aEmulator>(
          imu_clock,
          [this, up](double t) {
            std::array<AxisState, 2> s;
            if (table_emu_) {
              s = table_emu_->axis_states(t);
            } else {
              for (int a = 0; a < 2; ++a) s[a] = runner_->reported(a, t);
            }
            BenchKinematics k = bench_kinematics(*earth_, s[0], s[1], runner_->mount());
            if (!up->at_centre) k = slot_kinematics(k, up->slot.pose);
            return EmuTruth{k.w_ib_b, k.f_b};
          },
          u->truth, adis16488a_noise(), ic);
      u->bus = std::move(emu);
    } else {
      u->bus = open_imu(u->slot.uri);
    }
  }
  table_ = std::make_unique<TableClient>(table_at);
  table_->connect();
  runner_->attach_table(*table_);
  log_ << "table: " << table_uri << "\n";
  for (auto& u : units_) connect_unit(*u);
  if (live_units(units_) == 0) throw Aborted("no unit passed identification and self-test");
  for (int a = 0; a < 2; ++a) {
    // A positions plan moves both axes at the slew rate (the rotations the gyros must follow).
    table_->set_limits(a, plan_.table.max_accel,
                       a == kInner && !plan_.position_only ? std::max(plan_.table.max_rate, plan_.table.slew_rate)
                                                           : plan_.table.slew_rate);
    table_->set_mode(a, table::Mode::position);
    table_->command_position(a, table_->status(a).position);
    table_->enable(a);
  }
  table_->heartbeat();
}

// Identify (PROD_ID, serial) and self-test one unit. With one unit a failure ends the run (nothing has
// moved); on a fixture the unit is marked failed and the others go on.
void Station::connect_unit(Unit& u) {
  const std::string who = fixture_mode_ ? u.label() + ": " : "";
  try {
    u.imu = std::make_unique<Adis16488a>(*u.bus);
    const auto id = u.imu->connect();  // DeviceError on a wrong PROD_ID
    u.identified = true;
    log_ << who << "IMU: ADIS16488A serial " << id.serial_string() << ", firmware " << id.firmware() << ", "
         << id.output_rate_hz << " Hz (" << u.bus->describe() << ")\n";
    for (const auto& o : units_)
      if (o.get() != &u && o->identified && !o->failed && o->imu->identity().serial_string() == id.serial_string())
        throw DeviceError("the same unit (serial " + id.serial_string() + ") as " + o->label() +
                          ": two slots reach one IMU");
    const auto st = u.imu->self_test();
    if (!st.passed) throw DeviceError("IMU self-test failed: " + st.message);
    log_ << who << "IMU self-test passed\n";
  } catch (const std::exception& e) {
    if (!fixture_mode_) throw;
    runner_->fail_unit(u, e.what());
  }
}

std::string Station::station_label() const {
  // An emulated run is "calbench-emulated" unless the station is named ($CALBENCH_STATION).
  const char* named = std::getenv("CALBENCH_STATION");
  return o_.emulated && !(named && *named) ? "calbench-emulated" : db::Actor::from_environment(o_.operator_name).station;
}

std::string Station::store_path() const {
  return db::is_postgres_uri(o_.db) ? db::journal_path(o_.journal) : o_.db;
}

std::unique_ptr<db::Store> Station::open_store() const {
  db::OpenOptions dbo;
  dbo.create = true;
  return std::make_unique<db::Store>(store_path(), dbo, db::Actor::from_environment(o_.operator_name));
}

// With a central store: forward what the journal holds (this run and any earlier one that waited).
// An unreachable server is not an error of the run: the journal keeps it for `calbench db sync`.
void Station::forward(db::Store& journal, nlohmann::json& summary, const std::string& uid) {
  if (!db::is_postgres_uri(o_.db)) return;
  try {
    const db::SyncOutcome so = db::sync_journal(journal, o_.db);
    summary["central"] = {{"uri", db::redact_uri(o_.db)}, {"reached", so.reached}, {"forwarded", so.forwarded + so.already},
                          {"pending", so.pending_after}};
    for (const auto& it : so.items)
      if (it.uid == uid) {
        summary["central"]["bench_run"] = it.central_run;
        if (it.central_set) summary["central"]["set"] = it.central_set, summary["central"]["version"] = it.version;
      }
    for (const auto& l : so.lines) log_ << "forwarded to " << db::redact_uri(o_.db) << ": " << l << "\n";
    if (!so.reached || so.pending_after > 0)
      log_ << "central store not reached (" << so.error << "): " << so.pending_after
           << " run(s) wait in the journal " << journal.connection().path() << "; `calbench db sync` forwards them\n";
  } catch (const std::exception& e) {  // e.g. refused by the server: the run stays in the journal
    summary["central"] = {{"uri", db::redact_uri(o_.db)}, {"reached", false}, {"error", e.what()}};
    log_ << "could not forward to " << db::redact_uri(o_.db) << ": " << e.what() << " (the run stays in the journal "
         << journal.connection().path() << ")\n";
  }
}

db::BenchRunInput Station::bench_run_record(const Unit& u, const std::string& outcome,
                                            const std::string& recording) const {
  db::BenchRunInput run;
  run.station = station_label();
  run.plan = plan_.name;
  run.recording_path = recording;
  run.started_at = started_;
  run.ended_at = iso_utc(std::chrono::system_clock::now());
  run.outcome = outcome;
  run.uid = db::new_uid();  // stable across forwarding from the journal
  run.slot = fixture_mode_ ? u.slot.name : "";
  run.table_run = run_id_;
  run.qc.push_back({"samples_lost", static_cast<double>(u.lost), 0.0, u.lost == 0, "samples", db::kSampleNotApplicable,
                    "no IMU sample lost while recording: value ≤ 0"});
  return run;
}

// After the table cycle: the unit's recording is closed, fitted, its coefficients written and stored.
void Station::finish_unit(Unit& u) {
  nlohmann::json& js = u.summary;
  u.writer->finish();
  u.writer.reset();
  CoefficientSet cs;
  nlohmann::json fit_report;
  if (plan_.position_only) {
    cs = fit_positions_recording(u.rec_dir, fit_report);
  } else {
    BenchFitOptions fo;
    fo.table = plan_.table;
    const BenchRecordingData data = load_bench_blocks(u.rec_dir, 1.0);
    const BenchFitResult fr = fit_bench(data.blocks, fo);
    cs = bench_result_to_coefficients(fr, fo, data.meta, u.rec_dir.string());
    fit_report = bench_result_json(fr, cs);
  }
  write_coefficients(u.out / "COEFFS.json", cs);
  if (!o_.db.empty()) {  // the coefficient store: bench run + draft set, one transaction
    const std::unique_ptr<db::Store> store = open_store();
    db::BenchRunInput run = bench_run_record(u, "pass", u.rec_dir.string());
    run.recording_sha256 = sha256_file(u.rec_dir / "imu.csv");
    describe_recording(run, u.rec_dir);  // a central store's view: file://HOST/path and the digest of its files
    run.qc.push_back({"step_repeats", static_cast<double>(u.repeats), std::nullopt, true, "", db::kSampleNotApplicable, ""});
    const auto& id = u.imu->identity();
    const db::StoredSet st = store->store_bench({"ADIS16488A", id.serial_string(), id.firmware()}, run,
                                               coefficients_to_json(cs).dump(2));
    js["db"] = {{"path", store->connection().path()}, {"set", st.set_id}, {"version", st.version}, {"bench_run", st.run_id}};
    log_ << (fixture_mode_ ? u.label() + ": " : "") << "stored in " << store->connection().path() << ": set "
         << st.set_id << " (v" << st.version << ", draft)\n";
    forward(*store, js["db"], run.uid);
  }
  if (o_.emulated) {
    // In the spec's coefficients.json schema, so every tool (compare, simulate drive) reads it.
    CoefficientSet t;
    t.device = {"ADIS16488A", u.imu->identity().serial_string()};
    t.errors = u.truth;
    t.extra["note"] = "the emulated unit's true errors (for checking the station; never read by the fit)";
    write_coefficients(u.out / "EMULATED_TRUTH.json", t);
  }
  js["coefficients"] = (u.out / "COEFFS.json").string();
  js["fit"] = fit_report;
}

// A run that did not give the unit coefficients is part of its history: recorded (with why) once the
// unit is known, so `db history SERIAL` shows it. Best effort: the outcome itself is what counts.
void Station::record_aborted(Unit& u, const std::string& outcome, const std::string& why, Result& res) {
  if (o_.db.empty() || !u.imu || u.imu->identity().prod_id == 0) return;
  try {
    const std::unique_ptr<db::Store> store = open_store();
    const db::BenchRunInput run = bench_run_record(u, outcome, fs::exists(u.rec_dir) ? u.rec_dir.string() : "");
    const auto& id = u.imu->identity();
    const std::int64_t run_id = store->store_bench_run({"ADIS16488A", id.serial_string(), id.firmware()}, run,
                                                      why + " (after " + std::to_string(u.samples) + " samples)");
    u.summary["db"] = {{"path", store->connection().path()}, {"bench_run", run_id}, {"outcome", outcome}};
    if (!fixture_mode_)
      res.message += "; recorded as aborted bench run " + std::to_string(run_id) + " in " + store->connection().path();
    forward(*store, u.summary["db"], run.uid);
  } catch (const std::exception& w) {
    log_ << "could not record the " << outcome << " run" << (fixture_mode_ ? " of " + u.label() : "") << " in "
         << store_path() << ": " << w.what() << "\n";
  }
}

Result Station::run() {
  Result res;
  bool table_done = false;
  try {
    setup();
    fs::create_directories(o_.out_dir);
    for (auto& up : units_) {
      Unit& u = *up;
      if (u.failed) continue;
      fs::create_directories(u.out);
      RecordingMeta meta;
      // A positions plan: no reference (the table's angles are nominal only); spec kind "multipos".
      meta.kind = plan_.position_only ? RecordingKind::multipos : RecordingKind::bench;
      meta.device = DeviceId{"ADIS16488A", u.imu->identity().serial_string()};
      meta.site = plan_.site;
      meta.imu_rate_hz = u.imu->identity().output_rate_hz;
      meta.notes = "recorded by calbench station run" + std::string(o_.emulated ? " --emulated" : "");
      meta.extra["bench"] = {{"plan", plan_.name}, {"table", table_spec_json(plan_.table)}};
      meta.extra["station"] = {{"firmware", u.imu->identity().firmware()}, {"emulated", o_.emulated}};
      if (fixture_mode_)
        meta.extra["station"].update({{"run_id", run_id_},
                                      {"fixture", fixture_.name},
                                      {"slot", u.slot.name},
                                      {"rotation_deg", to_json(u.slot.rotation_deg)},
                                      {"offset_mm", to_json(Vec3(u.slot.pose.r_f * 1e3))}});
      if (fixture_mode_ && !u.slot.imu.empty()) meta.extra["station"]["imu"] = u.slot.imu;
      u.writer = std::make_unique<RecordingWriter>(u.rec_dir, meta, ImuForm::rates, true, true);
    }
    runner_->start_readers();

    runner_->run_plan();
    table_->stop_all();
    table_done = true;
    runner_->stop_readers();
    // Fit (the spine's bench fit) and store, unit by unit.
    live_->publish(units_, runner_->live_step(), true);
    std::size_t done = 0;
    for (auto& up : units_) {
      Unit& u = *up;
      if (u.failed) continue;
      try {
        finish_unit(u);
        ++done;
      } catch (const std::exception& e) {
        if (!fixture_mode_) throw;
        runner_->fail_unit(u, std::string("fit or store: ") + e.what());
      }
    }
    for (auto& up : units_)
      if (up->failed) {
        runner_->keep_partial(*up);
        record_aborted(*up, "fail", up->why, res);
      }
    complete_run(res, facts(), done);
    LiveStep end = runner_->live_step();
    end.name = "fitted and stored";
    end.kind = "done";
    end.fraction = 1;
    live_->finish(units_, end, "");
  } catch (const std::exception& e) {
    // Safety first: stop and disable the table (best effort, bounded time), keep the partial recordings.
    bool stopped = table_done;
    if (table_ && !table_done) {
      table_->stop_heartbeat();
      stopped = table_->stop_all();
    }
    if (runner_) {
      runner_->stop_readers();
      for (auto& u : units_) runner_->keep_partial(*u);
    }
    res.exit_code = (dynamic_cast<const std::invalid_argument*>(&e) || dynamic_cast<const InputError*>(&e)) ? 2 : 1;
    // Before the table or the IMU was touched (a plan error, a bad URI) nothing ran: say so.
    bool ran = table_ != nullptr;
    for (const auto& u : units_) ran = ran || u->imu || u->writer;
    res.message = std::string(ran ? "station aborted: " : "station not started (nothing ran): ") + e.what() +
                  (table_ ? (stopped ? "; table stopped and disabled" : "; table stop attempted (no answer)") : "");
    res.summary["aborted"] = true;
    res.summary["table_stopped"] = stopped;
    for (auto& u : units_) {
      if (u->failed) record_aborted(*u, "fail", u->why, res);
      else record_aborted(*u, "aborted", e.what(), res);
    }
    if (!fixture_mode_ && !units_.empty() && units_.front()->summary.contains("db"))
      res.summary["db"] = units_.front()->summary["db"];
    if (live_ && runner_) live_->finish(units_, runner_->live_step(), res.message);
  }
  if (table_emu_) table_emu_->stop();
  summarise_run(res, facts());
  return res;
}

}  // namespace

Result run(const Options& opt, std::ostream& log, const std::atomic<bool>& stop) {
  Station s(opt, log, stop);
  return s.run();
}

}  // namespace calbench::station
