#include "bench/station/station.hpp"
#include "common/noise_spec.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <ostream>
#include <vector>

#include "bench/bench_recording.hpp"
#include "bench/io/coefficients_json.hpp"
#include "common/input_error.hpp"
#include "bench/io/json_util.hpp"
#include "bench/io/plan_toml.hpp"
#include "bench/io/recording.hpp"
#include "calibration/bench_fit.hpp"
#include "calibration/bench_kinematics.hpp"
#include "calibration/earth.hpp"
#include "common/imu_error_sim.hpp"
#include "common/units.hpp"
#include "db/journal.hpp"
#include "db/store.hpp"
#include "devices/adis16488a.hpp"
#include "devices/adis16488a_emulator.hpp"
#include "devices/ft232h.hpp"
#include "devices/mcp2210.hpp"
#include "devices/table_client.hpp"
#include "devices/table_emulator.hpp"

namespace calbench::station {
namespace {
using namespace devices;
constexpr int kOuter = 0, kInner = 1;

struct Aborted : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::unique_ptr<SpiBus> open_imu(const std::string& uri) {
  // KIND[:SERIAL], or provision's form KIND://[SERIAL].
  const auto colon = uri.find(':');
  const std::string kind = uri.substr(0, colon);
  std::string serial = colon == std::string::npos ? "" : uri.substr(colon + 1);
  if (serial.rfind("//", 0) == 0) serial = serial.substr(2);
  if (kind == "ft232h") {
    auto bus = std::make_unique<Ft232hBus>(open_libftdi(mpsse::kVid, mpsse::kPid, serial));
    bus->configure();
    return bus;
  }
  if (kind == "mcp2210") {
    auto bus = std::make_unique<Mcp2210Bus>(open_hidapi(mcp2210::kVid, mcp2210::kPid, serial));
    bus->configure();
    return bus;
  }
  throw std::invalid_argument("--imu must be ft232h[:SERIAL] or mcp2210[:SERIAL], not '" + uri + "'");
}

std::string iso_utc(std::chrono::system_clock::time_point tp) {
  const std::time_t t = std::chrono::system_clock::to_time_t(tp);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char b[32];
  std::strftime(b, sizeof b, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return b;
}


class Station {
 public:
  Station(const Options& o, std::ostream& log, const std::atomic<bool>& stop) : o_(o), log_(log), stop_(stop) {}
  Result run();

 private:
  void setup();
  void poll(bool force = false);          // heartbeat + status at the heartbeat period
  ImuSample next_sample();
  void wait_settled(const PlanStep& s, double timeout_s);
  void wait_for(double seconds);          // keep streaming (and polling) for this long
  bool record_step(int k, const PlanStep& s, std::vector<ImuRecord>& imu, std::vector<BenchRefRow>& ref,
                   std::string& why);
  void command_step(const PlanStep& s);
  void progress(const std::string& what, bool line = false);
  // The store and the bench-run record of this run (the done and the aborted run share them).
  std::unique_ptr<db::Store> open_store() const;
  std::string store_path() const;  // the SQLite file written: --db, or the journal of a central --db
  void forward(db::Store& journal, nlohmann::json& summary, const std::string& uid);
  db::BenchRunInput bench_run_record(const db::Store& store, const std::string& outcome, const std::string& recording) const;
  void check_stop() {
    if (stop_) throw Aborted("interrupted (Ctrl-C)");
    if (o_.inject.table_kill_at_s >= 0 && table_emu_ && table_emu_->port() && clock_ &&
        clock_->now() >= o_.inject.table_kill_at_s && !killed_) {
      killed_ = true;
      table_emu_->stop();  // the table controller dies
    }
  }

  const Options& o_;
  std::ostream& log_;
  const std::atomic<bool>& stop_;
  BenchPlan plan_;
  std::unique_ptr<SiteEarth> earth_;
  std::shared_ptr<VirtualClock> clock_;
  std::shared_ptr<WallClock> wall_clock_;
  std::unique_ptr<TableEmulator> table_emu_;
  std::unique_ptr<TableClient> table_;
  std::unique_ptr<SpiBus> bus_;
  Adis16488aEmulator* imu_emu_ = nullptr;
  std::unique_ptr<Adis16488a> imu_;
  SensorErrors truth_;
  int mount_ = 2;                         // the cube's current mount
  double last_poll_ = -1e9;
  AxisStatus st_[2];
  bool killed_ = false;
  std::size_t step_index_ = 0;
  double plan_s_ = 0, done_s_ = 0;
  std::uint64_t samples_ = 0, lost_ = 0, error_samples_ = 0, repeats_ = 0;
  std::chrono::steady_clock::time_point wall0_ = std::chrono::steady_clock::now();
  std::string started_ = iso_utc(std::chrono::system_clock::now());
};

void Station::setup() {
  plan_ = load_plan(o_.plan_file);
  if (plan_.steps.empty()) throw std::runtime_error(o_.plan_file.string() + ": the plan has no steps");
  // Where the results go is checked before anything moves (a wrong --out or --db found after the
  // plan costs a table cycle); nothing is written yet: a missing database is created at the end.
  check_output_folder(o_.out_dir);
  if (!o_.db.empty()) {
    // A central store is not contacted here: the run never waits for the network (the journal
    // takes the run, and forwards it at the end when the server answers).
    db::check_target(o_.db);
    const std::string local = store_path();
    if (fs::exists(local)) db::Store check(local);  // a calbench database (named InputError otherwise)
    else check_output_path(local);
  }
  earth_ = std::make_unique<SiteEarth>(plan_.site);
  plan_s_ = plan_duration_s(plan_);
  // What the run will write, before anything moves: imu.csv and reference.csv at 17 significant
  // digits take about 337 bytes per sample together (measured on the factory plan: 413 MB for
  // 1,225,118 samples), at the ADIS16488A's 2460 Hz. Refused when the disk cannot hold it (with 20 %
  // to spare): a full disk in the middle of a plan costs a table cycle.
  {
    constexpr double kBytesPerSample = 337, kMargin = 1.2;
    double recorded_s = 0;  // the steps' data time (moves and re-mounts record nothing)
    for (const auto& st : plan_.steps) recorded_s += st.dwell_s;
    const double bytes = recorded_s * adis16488a_noise().output_rate_hz * kBytesPerSample;
    fs::path probe = o_.out_dir;
    while (!probe.empty() && !fs::exists(probe)) probe = probe.parent_path();
    if (probe.empty()) probe = ".";
    std::error_code ec;
    const fs::space_info sp = fs::space(probe, ec);
    char line[200];
    std::snprintf(line, sizeof line, "plan %s: %zu steps, about %.1f min, about %.0f MB to write into %s", plan_.name.c_str(),
                  plan_.steps.size(), plan_s_ / 60.0, bytes / 1e6, o_.out_dir.string().c_str());
    log_ << line;
    if (!ec) log_ << " (" << static_cast<long long>(static_cast<double>(sp.available) / 1e6) << " MB free)";
    log_ << "\n";
    if (!ec && static_cast<double>(sp.available) < kMargin * bytes)
      throw std::runtime_error("not enough free disk space for the recording: the plan writes about " +
                               std::to_string(std::llround(bytes / 1e6)) + " MB, " +
                               std::to_string(static_cast<long long>(static_cast<double>(sp.available) / 1e6)) + " MB are free at " +
                               probe.string());
  }
  mount_ = plan_.steps.front().mount;
  std::string table_uri = o_.table_uri;
  if (o_.emulated) {
    clock_ = std::make_shared<VirtualClock>();
    if (table_uri.empty()) {
      TableEmulatorConfig tc;
      tc.watchdog_s = 0.5;
      tc.max_rate = std::max(tc.max_rate, plan_.table.max_rate * 1.2);
      table_emu_ = std::make_unique<TableEmulator>(tc, clock_);
      table_emu_->start();
      table_uri = table_emu_->uri();
    } else {
      // External table (e.g. `calbench emulate table`): real time, and the emulated IMU's physics follow
      // the table's reported encoder states (last poll, extrapolated with the reported rate).
      wall_clock_ = std::make_shared<WallClock>(1.0);
    }
    truth_ = draw_random_unit(o_.seed);
    Adis16488aEmulatorConfig ic;
    ic.seed = o_.seed;
    ic.serial = static_cast<std::uint16_t>(1000 + o_.seed % 60000);
    std::shared_ptr<EmuClock> imu_clock = wall_clock_ ? std::shared_ptr<EmuClock>(wall_clock_) : clock_;
    auto emu = std::make_unique<Adis16488aEmulator>(
        imu_clock,
        [this](double t) {
          std::array<AxisState, 2> s;
          if (table_emu_) {
            s = table_emu_->axis_states(t);
          } else {
            for (int a = 0; a < 2; ++a) s[a] = AxisState{st_[a].position + st_[a].rate * (t - last_poll_), st_[a].rate, 0};
          }
          const auto k = bench_kinematics(*earth_, s[0], s[1], mount_);
          return EmuTruth{k.w_ib_b, k.f_b};
        },
        truth_, adis16488a_noise(), ic);
    if (o_.inject.imu_prod_id) emu->faults().prod_id = *o_.inject.imu_prod_id;
    emu->faults().self_test_diag = o_.inject.imu_self_test_diag;
    imu_emu_ = emu.get();
    bus_ = std::move(emu);
  } else {
    if (table_uri.empty()) throw std::invalid_argument("--table is required without --emulated");
    if (o_.imu_uri.empty()) throw std::invalid_argument("--imu is required without --emulated");
  }
  TableUri table_at;  // a malformed URI is bad input, found before any device is opened
  try {
    table_at = parse_table_uri(table_uri);
  } catch (const std::invalid_argument& e) {
    throw InputError("--table", 0, "", e.what());
  }
  if (!o_.emulated) bus_ = open_imu(o_.imu_uri);
  table_ = std::make_unique<TableClient>(table_at);
  table_->connect();
  log_ << "table: " << table_uri << "\n";
  imu_ = std::make_unique<Adis16488a>(*bus_);
  const auto id = imu_->connect();  // DeviceError on a wrong PROD_ID: nothing has moved yet
  log_ << "IMU: ADIS16488A serial " << id.serial_string() << ", firmware " << id.firmware() << ", "
       << id.output_rate_hz << " Hz (" << bus_->describe() << ")\n";
  const auto st = imu_->self_test();
  if (!st.passed) throw DeviceError("IMU self-test failed: " + st.message);
  log_ << "IMU self-test passed\n";
  for (int a = 0; a < 2; ++a) {
    table_->set_limits(a, plan_.table.max_accel, a == kInner ? std::max(plan_.table.max_rate, plan_.table.slew_rate)
                                                             : plan_.table.slew_rate);
    table_->set_mode(a, table::Mode::position);
    table_->command_position(a, table_->status(a).position);
    table_->enable(a);
  }
  table_->heartbeat();
}

void Station::poll(bool force) {
  check_stop();
  const double t = bus_->now();
  if (!force && t - last_poll_ < o_.heartbeat_s) return;
  last_poll_ = t;
  table_->heartbeat();
  for (int a = 0; a < 2; ++a) {
    st_[a] = table_->status(a);
    if (st_[a].faulted())
      throw Aborted("table axis " + std::to_string(a) + " fault: " + table::fault_text(st_[a].fault_code) + " (" +
                    table::status_text(st_[a].statusword) + ")");
  }
}

ImuSample Station::next_sample() {
  for (int tries = 0; tries < 3; ++tries) {
    poll();
    if (auto s = imu_->read_sample()) return *s;
  }
  throw DeviceError("IMU: no data-ready for 3 × 0.1 s");
}

void Station::wait_for(double seconds) {
  const double end = bus_->now() + seconds;
  while (bus_->now() < end) next_sample();
}

void Station::command_step(const PlanStep& s) {
  // Outer axis: position. Inner: position for static steps; for rate steps stop at the start angle,
  // then rate mode. Positions go the short way round from the current (unwrapped) angle.
  poll(true);
  auto target = [&](int a, double ang) { return st_[a].position + std::remainder(ang - st_[a].position, 2 * M_PI); };
  if (st_[kInner].mode == table::Mode::rate) {
    table_->command_rate(kInner, 0.0);
    while (std::abs(st_[kInner].rate) > 1e-6) next_sample(), poll();
    table_->set_mode(kInner, table::Mode::position);
    poll(true);
  }
  table_->command_position(kOuter, target(kOuter, s.outer));
  table_->command_position(kInner, target(kInner, s.inner));
  if (s.kind == StepKind::rate) {
    wait_settled(s, 600);
    table_->command_rate(kInner, s.rate);
    table_->set_mode(kInner, table::Mode::rate);
  }
}

void Station::wait_settled(const PlanStep& s, double timeout_s) {
  const double end = bus_->now() + timeout_s;
  poll(true);
  auto near = [](double a, double b) { return std::abs(std::remainder(a - b, 2 * M_PI)) < 0.01 * units::kDeg; };
  auto done = [&] {
    if (!(st_[0].settled() && st_[1].settled())) return false;
    if (!near(st_[kOuter].position, s.outer)) return false;
    if (st_[kInner].mode == table::Mode::rate) return std::abs(st_[kInner].rate - s.rate) < 0.01 * units::kDeg;
    return near(st_[kInner].position, s.inner);
  };
  while (!done()) {
    if (bus_->now() > end)
      throw Aborted("table did not settle for step '" + s.label + "' within " + std::to_string(int(timeout_s)) + " s");
    next_sample();
    progress("moving");
  }
}

void Station::progress(const std::string& what, bool line) {
  const std::size_t n = plan_.steps.size();
  const double frac = std::min(1.0, done_s_ / std::max(plan_s_, 1e-9));
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  const double eta = frac > 0.01 ? wall * (1 - frac) / frac : 0;
  char buf[200];
  std::snprintf(buf, sizeof buf, "[step %zu/%zu] %-22.22s %-8s outer %7.2f° inner %8.2f°/s  samples %llu  ETA %.0f s",
                step_index_ + 1, n, plan_.steps[std::min(step_index_, n - 1)].label.c_str(), what.c_str(),
                units::deg(st_[0].position), units::deg(st_[1].rate), static_cast<unsigned long long>(samples_), eta);
  if (o_.progress_tty && !line) {
    static double last = -1;
    if (wall - last > 0.1) {
      log_ << "\r" << buf << std::flush;
      last = wall;
    }
  } else if (line) {
    log_ << (o_.progress_tty ? "\r" : "") << buf << "\n";
  }
}

bool Station::record_step(int k, const PlanStep& s, std::vector<ImuRecord>& imu, std::vector<BenchRefRow>& ref,
                          std::string& why) {
  imu.clear();
  ref.clear();
  poll(true);
  // Reference: the plan's angles for static steps (the table's position accuracy is in the plan), the
  // commanded rate and the encoder's inner angle at the start for rate steps.
  const double outer = s.outer;
  const double inner0 = s.kind == StepKind::rate ? st_[kInner].position : s.inner;
  const double rate = s.kind == StepKind::rate ? s.rate : 0.0;
  const double t_poll = bus_->now();
  std::uint64_t lost = 0, errors = 0, saturated = 0;
  std::string err_text;
  double t0 = -1;
  while (true) {
    const ImuSample x = next_sample();
    if (t0 < 0) t0 = x.t;
    if (x.t - t0 >= s.dwell_s) break;
    if (imu.size() > 0) lost += x.lost_before;
    if (x.error()) {
      ++errors;
      err_text = x.error_text();
    }
    if (x.saturated) ++saturated;
    ImuRecord r;
    r.t = x.t;
    r.dt = 1.0 / imu_->identity().output_rate_hz;
    r.gyro = x.gyro;
    r.accel = x.accel;
    r.temp_c = x.temp_c;
    r.seq = x.seq_cnt;
    imu.push_back(r);
    // Inner angle at this sample: from the encoder reading and the commanded rate.
    const double th = inner0 + rate * (x.host_time - t_poll);
    const auto kin = bench_kinematics(*earth_, AxisState{outer, 0, 0}, AxisState{th, rate, 0}, s.mount);
    double a = std::fmod(units::deg(th), 360.0);
    ref.push_back({x.t, kin.w_ib_b, kin.f_b, k, a < 0 ? a + 360.0 : a});
    if (imu.size() % 256 == 0) progress("recording");
  }
  samples_ += imu.size();
  lost_ += lost;
  error_samples_ += errors;
  if (lost) why = std::to_string(lost) + " samples lost";
  else if (errors) why = std::to_string(errors) + " samples with error flags (" + err_text + ")";
  else if (saturated) why = std::to_string(saturated) + " saturated samples";
  return why.empty();
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

db::BenchRunInput Station::bench_run_record(const db::Store& store, const std::string& outcome,
                                            const std::string& recording) const {
  db::BenchRunInput run;
  // An emulated run is "calbench-emulated" unless the station is named ($CALBENCH_STATION).
  const char* named = std::getenv("CALBENCH_STATION");
  run.station = o_.emulated && !(named && *named) ? "calbench-emulated" : store.actor().station;
  run.plan = plan_.name;
  run.recording_path = recording;
  run.started_at = started_;
  run.ended_at = iso_utc(std::chrono::system_clock::now());
  run.outcome = outcome;
  run.uid = db::new_uid();  // stable across forwarding from the journal
  run.qc.push_back({"samples_lost", static_cast<double>(lost_), 0.0, lost_ == 0, "samples", db::kSampleNotApplicable,
                    "no IMU sample lost while recording: value ≤ 0"});
  return run;
}

Result Station::run() {
  Result res;
  std::unique_ptr<RecordingWriter> writer;
  const fs::path rec_dir = o_.out_dir / "recording";
  nlohmann::json steps = nlohmann::json::array();
  // Samples of the step being recorded; written once the step passes its data check.
  std::vector<ImuRecord> imu;
  std::vector<BenchRefRow> ref;
  try {
    setup();
    fs::create_directories(o_.out_dir);
    RecordingMeta meta;
    meta.kind = RecordingKind::bench;
    meta.device = DeviceId{"ADIS16488A", imu_->identity().serial_string()};
    meta.site = plan_.site;
    meta.imu_rate_hz = imu_->identity().output_rate_hz;
    meta.notes = "recorded by calbench station run" + std::string(o_.emulated ? " --emulated" : "");
    meta.extra["bench"] = {{"plan", plan_.name}, {"table", table_spec_json(plan_.table)}};
    meta.extra["station"] = {{"firmware", imu_->identity().firmware()}, {"emulated", o_.emulated}};
    writer = std::make_unique<RecordingWriter>(rec_dir, meta, ImuForm::rates, true, true);
    if (o_.emulated && o_.inject.imu_skip_every) imu_emu_->faults().skip_every = o_.inject.imu_skip_every;
    if (o_.emulated) imu_emu_->faults().sys_e_flag = o_.inject.imu_sys_e_flag;

    for (step_index_ = 0; step_index_ < plan_.steps.size(); ++step_index_) {
      const PlanStep& s = plan_.steps[step_index_];
      if (s.mount != mount_) {
        // Stop, and have the cube re-mounted with IMU axis `mount` on the inner axis.
        if (st_[kInner].mode == table::Mode::rate) table_->command_rate(kInner, 0.0);
        log_ << (o_.progress_tty ? "\n" : "") << (s.mount < 3 ? "re-mount the cube: IMU " : "re-mount on the 45° wedge: IMU ")
             << mount_name(s.mount) << (s.mount < 3 ? " axis" : " diagonal") << " on the inner axis ("
             << plan_.table.remount_s << " s)\n";
        wait_for(plan_.table.remount_s);
        mount_ = s.mount;  // emulated: the operator did it; real: the operator had remount_s
      }
      int attempt = 0;
      for (;; ++attempt) {
        command_step(s);
        wait_settled(s, 600);
        wait_for(plan_.table.settle_s);
        std::string why;
        if (record_step(static_cast<int>(step_index_), s, imu, ref, why)) break;
        log_ << (o_.progress_tty ? "\n" : "") << "step " << step_index_ + 1 << " '" << s.label << "' failed its check: " << why;
        if (attempt >= o_.max_repeats) {
          log_ << "\n";
          throw Aborted("step '" + s.label + "' failed " + std::to_string(attempt + 1) + " times: " + why);
        }
        log_ << "; repeating\n";
        ++repeats_;
      }
      for (std::size_t i = 0; i < imu.size(); ++i) {
        writer->imu(imu[i]);
        writer->bench_ref(ref[i]);
      }
      writer->flush();
      imu.clear();
      ref.clear();
      done_s_ += s.dwell_s + plan_.table.settle_s;
      steps.push_back({{"step", step_index_}, {"label", s.label}, {"samples", imu.size()}, {"repeats", attempt}});
      progress("done", true);
    }
    table_->stop_all();
    writer->finish();
    writer.reset();
    // Fit (the spine's bench fit) and store.
    BenchFitOptions fo;
    fo.table = plan_.table;
    const BenchRecordingData data = load_bench_blocks(rec_dir, 1.0);
    const BenchFitResult fr = fit_bench(data.blocks, fo);
    const CoefficientSet cs = bench_result_to_coefficients(fr, fo, data.meta, rec_dir.string());
    write_coefficients(o_.out_dir / "COEFFS.json", cs);
    if (!o_.db.empty()) {  // the coefficient store: bench run + draft set, one transaction
      const std::unique_ptr<db::Store> store = open_store();
      db::BenchRunInput run = bench_run_record(*store, "pass", rec_dir.string());
      run.recording_sha256 = sha256_file(rec_dir / "imu.csv");
      run.qc.push_back({"step_repeats", static_cast<double>(repeats_), std::nullopt, true, "", db::kSampleNotApplicable, ""});
      const auto& id = imu_->identity();
      const db::StoredSet st = store->store_bench({"ADIS16488A", id.serial_string(), id.firmware()}, run,
                                                 coefficients_to_json(cs).dump(2));
      res.summary["db"] = {{"path", store->connection().path()}, {"set", st.set_id}, {"version", st.version},
                           {"bench_run", st.run_id}};
      log_ << "stored in " << store->connection().path() << ": set " << st.set_id << " (v" << st.version << ", draft)\n";
      forward(*store, res.summary["db"], run.uid);
    }
    if (o_.emulated) {
      // In the spec's coefficients.json schema, so every tool (compare, simulate drive) reads it.
      CoefficientSet t;
      t.device = {"ADIS16488A", imu_->identity().serial_string()};
      t.errors = truth_;
      t.extra["note"] = "the emulated unit's true errors (for checking the station; never read by the fit)";
      write_coefficients(o_.out_dir / "EMULATED_TRUTH.json", t);
    }
    res.message = "station run complete: " + std::to_string(plan_.steps.size()) + " steps, coefficients in " +
                  (o_.out_dir / "COEFFS.json").string();
    res.summary["coefficients"] = (o_.out_dir / "COEFFS.json").string();
    res.summary["fit"] = bench_result_json(fr, cs);
  } catch (const std::exception& e) {
    // Safety first: stop and disable the table (best effort, bounded time), keep the partial recording.
    bool stopped = false;
    if (table_) {
      table_->stop_heartbeat();
      stopped = table_->stop_all();
    }
    if (writer) {
      // Nothing captured is lost: the step in progress did not pass its check, so its samples
      // are kept with step −1 (outside any plan step: a fit will not use them).
      try {
        for (std::size_t i = 0; i < imu.size() && i < ref.size(); ++i) {
          writer->imu(imu[i]);
          BenchRefRow r = ref[i];
          r.step = -1;
          writer->bench_ref(r);
        }
        writer->flush();  // not finished: meta.json stays "incomplete"
      } catch (const std::exception& w) {
        log_ << "could not keep the partial step: " << w.what() << "\n";
      }
    }
    res.exit_code = (dynamic_cast<const std::invalid_argument*>(&e) || dynamic_cast<const InputError*>(&e)) ? 2 : 1;
    // Before the table or the IMU was touched (a plan error, a bad URI) nothing ran: say so.
    const bool ran = table_ || imu_ || writer;
    res.message = std::string(ran ? "station aborted: " : "station not started (nothing ran): ") + e.what() +
                  (table_ ? (stopped ? "; table stopped and disabled" : "; table stop attempted (no answer)") : "");
    res.summary["aborted"] = true;
    res.summary["table_stopped"] = stopped;
    // An aborted run is part of the unit's history: recorded (outcome "aborted", with why) once the
    // unit is known, so `db history SERIAL` shows it. Best effort: the abort itself is what counts.
    if (!o_.db.empty() && imu_ && imu_->identity().prod_id != 0) {
      try {
        const std::unique_ptr<db::Store> store = open_store();
        const db::BenchRunInput run = bench_run_record(*store, "aborted", writer ? rec_dir.string() : "");
        const auto& id = imu_->identity();
        const std::int64_t run_id = store->store_bench_run({"ADIS16488A", id.serial_string(), id.firmware()}, run,
                                                          std::string(e.what()) + " (after " + std::to_string(samples_) +
                                                              " samples)");
        res.summary["db"] = {{"path", store->connection().path()}, {"bench_run", run_id}, {"outcome", "aborted"}};
        res.message += "; recorded as aborted bench run " + std::to_string(run_id) + " in " + store->connection().path();
        forward(*store, res.summary["db"], run.uid);
      } catch (const std::exception& w) {
        log_ << "could not record the aborted run in " << store_path() << ": " << w.what() << "\n";
      }
    }
  }
  if (table_emu_) table_emu_->stop();
  res.summary["ok"] = res.exit_code == 0;
  res.summary["message"] = res.message;
  res.summary["recording"] = rec_dir.string();
  res.summary["steps"] = steps;
  res.summary["samples"] = samples_;
  res.summary["samples_lost"] = lost_;
  res.summary["error_samples"] = error_samples_;
  res.summary["repeats"] = repeats_;
  res.summary["emulated_s"] = bus_ ? bus_->now() : 0.0;
  res.summary["wall_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  return res;
}

}  // namespace

Result run(const Options& opt, std::ostream& log, const std::atomic<bool>& stop) {
  Station s(opt, log, stop);
  return s.run();
}

}  // namespace calbench::station
