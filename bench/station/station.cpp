#include "bench/station/station.hpp"
#include "common/noise_spec.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <deque>
#include <limits>
#include <mutex>
#include <thread>
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
#include "calibration/bench_fit.hpp"
#include "calibration/bench_kinematics.hpp"
#include "calibration/earth.hpp"
#include "common/imu_error_sim.hpp"
#include "common/json_fields.hpp"
#include "common/units.hpp"
#include "db/journal.hpp"
#include "db/store.hpp"
#include "devices/adis16488a.hpp"
#include "devices/adis16488a_emulator.hpp"
#include "devices/ft232h.hpp"
#include "devices/imu_uri.hpp"
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
  // KIND[:SERIAL][#csN], or provision's form KIND://[SERIAL].
  const ImuUri u = parse_imu_uri(uri);  // checked when the fixture was read
  if (u.kind == "ft232h") {
    if (u.cs != 0)  // the bus drives ADBUS3 only (devices/ft232h.hpp)
      throw std::invalid_argument("'" + uri + "': the FT232H bus drives chip select cs0 (ADBUS3) only");
    auto bus = std::make_unique<Ft232hBus>(open_libftdi(mpsse::kVid, mpsse::kPid, u.serial));
    bus->configure();
    return bus;
  }
  Mcp2210Config mc;
  mc.cs_pin = u.cs;
  auto bus = std::make_unique<Mcp2210Bus>(open_hidapi(mcp2210::kVid, mcp2210::kPid, u.serial), mc);
  bus->configure();
  return bus;
}

std::string iso_utc(std::chrono::system_clock::time_point tp) {
  const std::time_t t = std::chrono::system_clock::to_time_t(tp);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char b[32];
  std::strftime(b, sizeof b, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return b;
}


// One unit of the fixture: its devices, the step being recorded, its output and its fate.
struct Unit {
  FixtureSlot slot;
  bool at_centre = true;           // identity pose at the centre: the centre's kinematics as they are
  fs::path out, rec_dir;
  std::uint64_t seed = 1;
  ImuInjections inj;
  bool flags_applied = false;
  std::shared_ptr<VirtualClock> clock;  // its own bus time (emulated, several units: one bridge each)
  std::unique_ptr<SpiBus> bus;
  Adis16488aEmulator* emu = nullptr;
  std::unique_ptr<Adis16488a> imu;
  SensorErrors truth;
  std::unique_ptr<RecordingWriter> writer;
  // The step being recorded (rows are written once the step passes its data check).
  bool recording = false;
  double t0 = -1;
  std::vector<ImuRecord> imu_rows;
  std::vector<BenchRefRow> ref_rows;
  std::uint64_t step_lost = 0, step_errors = 0, step_saturated = 0;
  std::string err_text;
  int misses = 0;                  // data-ready timeouts in a row
  // Totals and fate.
  std::uint64_t samples = 0, lost = 0, error_samples = 0, repeats = 0;
  bool identified = false, failed = false;
  std::string why;                 // failed: the reason
  nlohmann::json steps = nlohmann::json::array(), summary = nlohmann::json::object();
  // Reader thread (real time): samples wait here for the station's thread.
  std::thread reader;
  std::mutex mu;
  std::deque<ImuSample> queue;
  std::string reader_error;
  std::atomic<bool> reading{false};

  bool live() const { return !failed; }
  std::string label() const { return "slot " + slot.name; }
};

class Station {
 public:
  Station(const Options& o, std::ostream& log, const std::atomic<bool>& stop) : o_(o), log_(log), stop_(stop) {}
  ~Station() { stop_readers(); }
  Result run();

 private:
  void setup();
  void make_units();
  void connect_unit(Unit& u);
  void poll(bool force = false);          // heartbeat + status at the heartbeat period
  void pump();                            // take the next sample(s) of the units, keep polling
  void take(Unit& u, const ImuSample& x); // one sample of a unit: recorded when its step records
  void fail_unit(Unit& u, const std::string& why);
  void start_readers();
  void stop_readers();
  void wait_settled(const PlanStep& s, double timeout_s);
  void wait_for(double seconds);          // keep streaming (and polling) for this long
  void record_step(int k, const PlanStep& s, const std::vector<Unit*>& units);
  std::string step_check(const Unit& u) const;  // empty: the step's data passed
  void command_step(const PlanStep& s);
  void progress(const std::string& what, bool line = false);
  void finish_unit(Unit& u);
  void keep_partial(Unit& u);
  void record_aborted(Unit& u, const std::string& outcome, const std::string& why, Result& res);
  double now() const { return clock_ ? clock_->now() : units_.front()->bus->now(); }
  std::size_t live_units() const {
    std::size_t n = 0;
    for (const auto& u : units_) n += u->live();
    return n;
  }
  std::uint64_t total(std::uint64_t Unit::*f) const {
    std::uint64_t n = 0;
    for (const auto& u : units_) n += (*u).*f;
    return n;
  }
  // The store and the bench-run record of this run (the done and the aborted run share them).
  std::unique_ptr<db::Store> open_store() const;
  std::string store_path() const;  // the SQLite file written: --db, or the journal of a central --db
  void forward(db::Store& journal, nlohmann::json& summary, const std::string& uid);
  db::BenchRunInput bench_run_record(const Unit& u, const db::Store& store, const std::string& outcome,
                                     const std::string& recording) const;
  void check_stop() {
    if (stop_) throw Aborted("interrupted (Ctrl-C)");
    if (o_.inject.table_kill_at_s >= 0 && table_emu_ && table_emu_->port() && (clock_ || wall_clock_) &&
        now() >= o_.inject.table_kill_at_s && !killed_) {
      killed_ = true;
      table_emu_->stop();  // the table controller dies
    }
  }

  const Options& o_;
  std::ostream& log_;
  const std::atomic<bool>& stop_;
  BenchPlan plan_;
  Fixture fixture_;
  bool fixture_mode_ = false;             // a fixture (file or --units): one folder per slot
  bool threaded_ = false;                 // real time: a reader thread per unit
  std::string run_id_ = db::new_uid();    // ties the units of one table cycle
  std::unique_ptr<SiteEarth> earth_;
  std::shared_ptr<VirtualClock> clock_;   // emulated time (the table's; several units: the slowest unit's)
  std::shared_ptr<WallClock> wall_clock_;
  std::unique_ptr<TableEmulator> table_emu_;
  std::unique_ptr<TableClient> table_;
  std::vector<std::unique_ptr<Unit>> units_;
  int mount_ = 2;                         // the fixture's current mount
  double last_poll_ = -1e9;
  AxisStatus st_[2];
  bool killed_ = false;
  // The step being recorded: the reference the samples get.
  double rec_outer_ = 0, rec_inner0_ = 0, rec_rate_ = 0, rec_t_poll_ = 0, rec_dwell_ = 0;
  int rec_step_ = -1, rec_mount_ = 2;
  std::size_t step_index_ = 0;
  double plan_s_ = 0, done_s_ = 0;
  std::uint64_t pumps_ = 0;
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
  // Bus arbitration: one bridge per unit (each reads its data-ready stream at the full output rate).
  // Units on one bridge's chip selects would share its time: not built; refused before anything moves.
  if (!o_.emulated) {
    std::map<std::string, std::string> bridges;
    for (const auto& s : fixture_.slots)
      if (const auto [it, fresh] = bridges.emplace(s.uri.bridge(), s.name); !fresh)
        throw InputError(fixture_.file, s.line, "imu",
                         "slots '" + it->second + "' and '" + s.name + "' share the bridge " + s.uri.kind +
                             (s.uri.serial.empty() ? "" : ":" + s.uri.serial) +
                             ": time-slicing one bridge between units is not supported; give each unit its own bridge");
  }
  for (const auto& [name, _] : o_.inject.slot) {
    bool found = false;
    for (const auto& s : fixture_.slots) found = found || s.name == name;
    if (!found) {
      std::string names;
      for (const auto& s : fixture_.slots) names += (names.empty() ? "" : ", ") + s.name;
      throw InputError("--inject", 0, name, "no slot '" + name + "' in the fixture (slots: " + names + ")");
    }
  }
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
  // In real time the bus is read by a thread of its own: a Modbus round trip to the table (a few ms)
  // must not hold up a data-ready stream whose samples come every 0.41 ms.
  threaded_ = !clock_;
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
                  plan_.steps.size(), plan_s_ / 60.0, bytes / 1e6, o_.out_dir.string().c_str());
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
  mount_ = plan_.steps.front().mount;
  if (o_.emulated && clock_) {
    TableEmulatorConfig tc;
    tc.watchdog_s = 0.5;
    tc.max_rate = std::max(tc.max_rate, plan_.table.max_rate * 1.2);
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
              for (int a = 0; a < 2; ++a) s[a] = AxisState{st_[a].position + st_[a].rate * (t - last_poll_), st_[a].rate, 0};
            }
            BenchKinematics k = bench_kinematics(*earth_, s[0], s[1], mount_);
            if (!up->at_centre) k = slot_kinematics(k, up->slot.pose);
            return EmuTruth{k.w_ib_b, k.f_b};
          },
          u->truth, adis16488a_noise(), ic);
      if (u->inj.prod_id) emu->faults().prod_id = *u->inj.prod_id;
      emu->faults().self_test_diag = u->inj.self_test_diag;
      u->emu = emu.get();
      u->bus = std::move(emu);
    } else {
      u->bus = open_imu(u->slot.imu);
    }
  }
  table_ = std::make_unique<TableClient>(table_at);
  table_->connect();
  log_ << "table: " << table_uri << "\n";
  for (auto& u : units_) connect_unit(*u);
  if (live_units() == 0) throw Aborted("no unit passed identification and self-test");
  for (int a = 0; a < 2; ++a) {
    table_->set_limits(a, plan_.table.max_accel, a == kInner ? std::max(plan_.table.max_rate, plan_.table.slew_rate)
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
    fail_unit(u, e.what());
  }
}

void Station::fail_unit(Unit& u, const std::string& why) {
  if (u.failed) return;
  u.failed = true;
  u.why = why;
  u.recording = false;
  u.reading = false;
  log_ << (o_.progress_tty ? "\n" : "") << u.label() << " failed: " << why
       << (live_units() ? " (the other units go on)" : "") << "\n";
}

void Station::poll(bool force) {
  check_stop();
  const double t = now();
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

void Station::start_readers() {
  if (!threaded_) return;
  for (auto& up : units_) {
    Unit& u = *up;
    if (u.failed) continue;
    u.reading = true;
    u.reader = std::thread([&u] {
      int misses = 0;
      while (u.reading) {
        try {
          const auto s = u.imu->read_sample();
          std::lock_guard lk(u.mu);
          if (s) {
            u.queue.push_back(*s);
            misses = 0;
          } else if (++misses >= 3) {
            u.reader_error = "IMU: no data-ready for 3 × 0.1 s";
            break;
          }
        } catch (const std::exception& e) {
          std::lock_guard lk(u.mu);
          u.reader_error = e.what();
          break;
        }
      }
    });
  }
}

void Station::stop_readers() {
  for (auto& u : units_) {
    u->reading = false;
    if (u->reader.joinable()) u->reader.join();
  }
}

// The next samples. Emulated time: the unit whose bus is furthest behind reads next (each unit has its
// own bridge, so their reads overlap in time); the table's clock is the slowest unit's. In real time:
// each unit's reader thread has queued its samples; they are taken here, on this thread.
void Station::pump() {
  poll();
  if (++pumps_ % 256 == 0) progress(rec_step_ >= 0 ? "recording" : "moving");
  if (threaded_) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    for (auto& up : units_) {
      Unit& u = *up;
      if (u.failed) continue;
      std::deque<ImuSample> q;
      std::string err;
      {
        std::lock_guard lk(u.mu);
        q.swap(u.queue);
        err = u.reader_error;
      }
      for (const auto& x : q) take(u, x);
      if (!err.empty()) {
        if (!fixture_mode_) throw DeviceError(err);
        fail_unit(u, err);
      }
    }
    if (live_units() == 0) throw Aborted("every unit failed");
    return;
  }
  Unit* next = nullptr;
  for (auto& u : units_)
    if (!u->failed && (!next || u->bus->now() < next->bus->now())) next = u.get();
  if (!next) throw Aborted("every unit failed");
  Unit& u = *next;
  try {
    if (const auto x = u.imu->read_sample()) {
      u.misses = 0;
      take(u, *x);
    } else if (++u.misses >= 3) {
      throw DeviceError("IMU: no data-ready for 3 × 0.1 s");
    }
  } catch (const std::exception& e) {
    if (!fixture_mode_) throw;
    fail_unit(u, e.what());
  }
  if (units_.size() > 1 && clock_) {
    double slowest = std::numeric_limits<double>::infinity();
    for (const auto& o : units_)
      if (!o->failed) slowest = std::min(slowest, o->bus->now());
    if (std::isfinite(slowest)) clock_->wait_until(slowest);
  }
  // Error flags from an emulated time on (a unit failing mid-run).
  for (auto& o : units_)
    if (o->emu && o->inj.flags_from_s >= 0 && !o->flags_applied && now() >= o->inj.flags_from_s) {
      o->emu->faults().sys_e_flag = o->inj.sys_e_flag;
      o->flags_applied = true;
    }
  if (live_units() == 0) throw Aborted("every unit failed");
}

void Station::take(Unit& u, const ImuSample& x) {
  if (!u.recording) return;  // moving, settling, re-mounting: not recorded
  if (u.t0 < 0) u.t0 = x.t;
  if (x.t - u.t0 >= rec_dwell_) {
    u.recording = false;
    return;
  }
  if (!u.imu_rows.empty()) u.step_lost += x.lost_before;
  if (x.error()) {
    ++u.step_errors;
    u.err_text = x.error_text();
  }
  if (x.saturated) ++u.step_saturated;
  ImuRecord r;
  r.t = x.t;
  r.dt = 1.0 / u.imu->identity().output_rate_hz;
  r.gyro = x.gyro;
  r.accel = x.accel;
  r.temp_c = x.temp_c;
  r.seq = x.seq_cnt;
  u.imu_rows.push_back(r);
  // Inner angle at this sample: from the encoder reading and the commanded rate.
  const double th = rec_inner0_ + rec_rate_ * (x.host_time - rec_t_poll_);
  BenchKinematics kin = bench_kinematics(*earth_, AxisState{rec_outer_, 0, 0}, AxisState{th, rec_rate_, 0}, rec_mount_);
  if (!u.at_centre) kin = slot_kinematics(kin, u.slot.pose);
  double a = std::fmod(units::deg(th), 360.0);
  u.ref_rows.push_back({x.t, kin.w_ib_b, kin.f_b, rec_step_, a < 0 ? a + 360.0 : a});
}

void Station::wait_for(double seconds) {
  const double end = now() + seconds;
  while (now() < end) pump();
}

void Station::command_step(const PlanStep& s) {
  // Outer axis: position. Inner: position for static steps; for rate steps stop at the start angle,
  // then rate mode. Positions go the short way round from the current (unwrapped) angle.
  poll(true);
  auto target = [&](int a, double ang) { return st_[a].position + std::remainder(ang - st_[a].position, 2 * M_PI); };
  if (st_[kInner].mode == table::Mode::rate) {
    table_->command_rate(kInner, 0.0);
    while (std::abs(st_[kInner].rate) > 1e-6) pump(), poll();
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
  const double end = now() + timeout_s;
  poll(true);
  auto near = [](double a, double b) { return std::abs(std::remainder(a - b, 2 * M_PI)) < 0.01 * units::kDeg; };
  auto done = [&] {
    if (!(st_[0].settled() && st_[1].settled())) return false;
    if (!near(st_[kOuter].position, s.outer)) return false;
    if (st_[kInner].mode == table::Mode::rate) return std::abs(st_[kInner].rate - s.rate) < 0.01 * units::kDeg;
    return near(st_[kInner].position, s.inner);
  };
  while (!done()) {
    if (now() > end)
      throw Aborted("table did not settle for step '" + s.label + "' within " + std::to_string(int(timeout_s)) + " s");
    pump();
  }
}

void Station::progress(const std::string& what, bool line) {
  const std::size_t n = plan_.steps.size();
  const double frac = std::min(1.0, done_s_ / std::max(plan_s_, 1e-9));
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  const double eta = frac > 0.01 ? wall * (1 - frac) / frac : 0;
  std::uint64_t samples = total(&Unit::samples);
  for (const auto& u : units_) samples += u->imu_rows.size();
  char buf[240];
  std::snprintf(buf, sizeof buf, "[step %zu/%zu] %-22.22s %-8s outer %7.2f° inner %8.2f°/s  samples %llu  ETA %.0f s",
                step_index_ + 1, n, plan_.steps[std::min(step_index_, n - 1)].label.c_str(), what.c_str(),
                units::deg(st_[0].position), units::deg(st_[1].rate), static_cast<unsigned long long>(samples), eta);
  std::string text = buf;
  if (units_.size() > 1) text += "  units " + std::to_string(live_units()) + "/" + std::to_string(units_.size());
  if (o_.progress_tty && !line) {
    static double last = -1;
    if (wall - last > 0.1) {
      log_ << "\r" << text << std::flush;
      last = wall;
    }
  } else if (line) {
    log_ << (o_.progress_tty ? "\r" : "") << text << "\n";
  }
}

// Records one step on the given units at once: each takes the step's dwell from its own first sample.
void Station::record_step(int k, const PlanStep& s, const std::vector<Unit*>& units) {
  poll(true);
  // Reference: the plan's angles for static steps (the table's position accuracy is in the plan), the
  // commanded rate and the encoder's inner angle at the start for rate steps.
  rec_outer_ = s.outer;
  rec_inner0_ = s.kind == StepKind::rate ? st_[kInner].position : s.inner;
  rec_rate_ = s.kind == StepKind::rate ? s.rate : 0.0;
  rec_t_poll_ = now();
  rec_dwell_ = s.dwell_s;
  rec_step_ = k;
  rec_mount_ = s.mount;
  for (Unit* u : units) {
    u->imu_rows.clear();
    u->ref_rows.clear();
    u->step_lost = u->step_errors = u->step_saturated = 0;
    u->err_text.clear();
    u->t0 = -1;
    u->recording = !u->failed;
  }
  auto busy = [&] {
    for (const Unit* u : units)
      if (u->recording) return true;
    return false;
  };
  while (busy()) pump();
  rec_step_ = -1;
  for (Unit* u : units) {
    u->samples += u->imu_rows.size();
    u->lost += u->step_lost;
    u->error_samples += u->step_errors;
  }
}

std::string Station::step_check(const Unit& u) const {
  if (u.step_lost) return std::to_string(u.step_lost) + " samples lost";
  if (u.step_errors) return std::to_string(u.step_errors) + " samples with error flags (" + u.err_text + ")";
  if (u.step_saturated) return std::to_string(u.step_saturated) + " saturated samples";
  return "";
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

db::BenchRunInput Station::bench_run_record(const Unit& u, const db::Store& store, const std::string& outcome,
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
  BenchFitOptions fo;
  fo.table = plan_.table;
  const BenchRecordingData data = load_bench_blocks(u.rec_dir, 1.0);
  const BenchFitResult fr = fit_bench(data.blocks, fo);
  const CoefficientSet cs = bench_result_to_coefficients(fr, fo, data.meta, u.rec_dir.string());
  write_coefficients(u.out / "COEFFS.json", cs);
  if (!o_.db.empty()) {  // the coefficient store: bench run + draft set, one transaction
    const std::unique_ptr<db::Store> store = open_store();
    db::BenchRunInput run = bench_run_record(u, *store, "pass", u.rec_dir.string());
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
  js["fit"] = bench_result_json(fr, cs);
}

// Nothing captured is lost: the step in progress did not pass its check (or was cut short), so its
// samples are kept with step −1 (outside any plan step: a fit will not use them); meta.json stays
// "incomplete".
void Station::keep_partial(Unit& u) {
  if (!u.writer) return;
  try {
    for (std::size_t i = 0; i < u.imu_rows.size() && i < u.ref_rows.size(); ++i) {
      u.writer->imu(u.imu_rows[i]);
      BenchRefRow r = u.ref_rows[i];
      r.step = -1;
      u.writer->bench_ref(r);
    }
    u.imu_rows.clear();
    u.ref_rows.clear();
    u.writer->flush();
  } catch (const std::exception& w) {
    log_ << "could not keep the partial step" << (fixture_mode_ ? " of " + u.label() : "") << ": " << w.what() << "\n";
  }
}

// A run that did not give the unit coefficients is part of its history: recorded (with why) once the
// unit is known, so `db history SERIAL` shows it. Best effort: the outcome itself is what counts.
void Station::record_aborted(Unit& u, const std::string& outcome, const std::string& why, Result& res) {
  if (o_.db.empty() || !u.imu || u.imu->identity().prod_id == 0) return;
  try {
    const std::unique_ptr<db::Store> store = open_store();
    const db::BenchRunInput run = bench_run_record(u, *store, outcome, fs::exists(u.rec_dir) ? u.rec_dir.string() : "");
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
      meta.kind = RecordingKind::bench;
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
      if (u.emu && u.inj.skip_every) u.emu->faults().skip_every = u.inj.skip_every;
      if (u.emu && u.inj.flags_from_s < 0) u.emu->faults().sys_e_flag = u.inj.sys_e_flag;
    }
    start_readers();

    for (step_index_ = 0; step_index_ < plan_.steps.size(); ++step_index_) {
      const PlanStep& s = plan_.steps[step_index_];
      if (s.mount != mount_) {
        // Stop, and have the cube (the fixture) re-mounted with axis `mount` on the inner axis.
        if (st_[kInner].mode == table::Mode::rate) table_->command_rate(kInner, 0.0);
        log_ << (o_.progress_tty ? "\n" : "")
             << (s.mount >= 3      ? "re-mount on the 45° wedge: IMU "
                 : fixture_mode_ ? "re-mount the fixture: fixture "
                                 : "re-mount the cube: IMU ")
             << mount_name(s.mount) << (s.mount < 3 ? " axis" : " diagonal") << " on the inner axis ("
             << plan_.table.remount_s << " s)\n";
        wait_for(plan_.table.remount_s);
        mount_ = s.mount;  // emulated: the operator did it; real: the operator had remount_s
      }
      std::vector<Unit*> pending;
      for (auto& u : units_)
        if (u->live()) pending.push_back(u.get());
      int attempt = 0;
      for (;; ++attempt) {
        command_step(s);
        wait_settled(s, 600);
        wait_for(plan_.table.settle_s);
        record_step(static_cast<int>(step_index_), s, pending);
        std::vector<Unit*> again;
        for (Unit* u : pending) {
          if (u->failed) continue;
          const std::string why = step_check(*u);
          if (why.empty()) {
            for (std::size_t i = 0; i < u->imu_rows.size(); ++i) {
              u->writer->imu(u->imu_rows[i]);
              u->writer->bench_ref(u->ref_rows[i]);
            }
            u->writer->flush();
            u->steps.push_back({{"step", step_index_}, {"label", s.label}, {"samples", u->imu_rows.size()}, {"repeats", attempt}});
            u->imu_rows.clear();
            u->ref_rows.clear();
            continue;
          }
          log_ << (o_.progress_tty ? "\n" : "") << "step " << step_index_ + 1 << " '" << s.label << "' failed its check"
               << (fixture_mode_ ? " on " + u->label() : "") << ": " << why;
          if (attempt >= o_.max_repeats) {
            log_ << "\n";
            const std::string msg = "step '" + s.label + "' failed " + std::to_string(attempt + 1) + " times: " + why;
            if (!fixture_mode_) throw Aborted(msg);
            keep_partial(*u);
            fail_unit(*u, msg);
            continue;
          }
          log_ << "; repeating\n";
          ++u->repeats;
          again.push_back(u);
        }
        if (again.empty()) break;
        pending = again;
      }
      done_s_ += s.dwell_s + plan_.table.settle_s;
      progress("done", true);
    }
    table_->stop_all();
    table_done = true;
    stop_readers();
    // Fit (the spine's bench fit) and store, unit by unit.
    std::size_t done = 0;
    for (auto& up : units_) {
      Unit& u = *up;
      if (u.failed) continue;
      try {
        finish_unit(u);
        ++done;
      } catch (const std::exception& e) {
        if (!fixture_mode_) throw;
        fail_unit(u, std::string("fit or store: ") + e.what());
      }
    }
    for (auto& up : units_)
      if (up->failed) {
        keep_partial(*up);
        record_aborted(*up, "fail", up->why, res);
      }
    if (!fixture_mode_) {
      const Unit& u = *units_.front();
      res.message = "station run complete: " + std::to_string(plan_.steps.size()) + " steps, coefficients in " +
                    (u.out / "COEFFS.json").string();
      res.summary["coefficients"] = u.summary["coefficients"];
      res.summary["fit"] = u.summary["fit"];
      if (u.summary.contains("db")) res.summary["db"] = u.summary["db"];
    } else {
      res.message = "station run complete: " + std::to_string(plan_.steps.size()) + " steps, " + std::to_string(done) +
                    " of " + std::to_string(units_.size()) + " units calibrated (coefficients in " +
                    (o_.out_dir / "SLOT" / "COEFFS.json").string() + ")";
      for (const auto& u : units_)
        if (u->failed) res.message += "; " + u->label() + " failed: " + u->why;
      if (done < units_.size()) res.exit_code = 1;
    }
  } catch (const std::exception& e) {
    // Safety first: stop and disable the table (best effort, bounded time), keep the partial recordings.
    bool stopped = table_done;
    if (table_ && !table_done) {
      table_->stop_heartbeat();
      stopped = table_->stop_all();
    }
    stop_readers();
    for (auto& u : units_) keep_partial(*u);
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
  }
  if (table_emu_) table_emu_->stop();
  res.summary["ok"] = res.exit_code == 0;
  res.summary["message"] = res.message;
  res.summary["run_id"] = run_id_;
  if (!fixture_mode_) {
    const fs::path rec = units_.empty() ? o_.out_dir / "recording" : units_.front()->rec_dir;
    res.summary["recording"] = rec.string();
    res.summary["steps"] = units_.empty() ? nlohmann::json::array() : units_.front()->steps;
  } else {
    res.summary["fixture"] = {{"name", fixture_.name}, {"file", fixture_.file}, {"units", units_.size()},
                              {"arbitration", "one bridge per unit"}};
    nlohmann::json us = nlohmann::json::array();
    for (const auto& u : units_) {
      nlohmann::json j = u->summary;
      j["slot"] = u->slot.name;
      j["ok"] = !u->failed && j.contains("coefficients");
      if (u->failed) j["failed"] = u->why;
      if (u->identified) j["serial"] = u->imu->identity().serial_string();
      j["recording"] = u->rec_dir.string();
      j["samples"] = u->samples;
      j["samples_lost"] = u->lost;
      j["error_samples"] = u->error_samples;
      j["repeats"] = u->repeats;
      j["steps"] = u->steps.size();
      j["rate_hz"] = u->identified ? u->imu->identity().output_rate_hz : 0.0;
      us.push_back(j);
    }
    res.summary["units"] = us;
  }
  res.summary["samples"] = total(&Unit::samples);
  res.summary["samples_lost"] = total(&Unit::lost);
  res.summary["error_samples"] = total(&Unit::error_samples);
  res.summary["repeats"] = total(&Unit::repeats);
  res.summary["emulated_s"] = clock_ ? clock_->now() : (wall_clock_ ? wall_clock_->now() : 0.0);
  res.summary["wall_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  return res;
}

}  // namespace

Result run(const Options& opt, std::ostream& log, const std::atomic<bool>& stop) {
  Station s(opt, log, stop);
  return s.run();
}

}  // namespace calbench::station
