#include "bench/station/step_runner.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <ostream>
#include <thread>

#include "calibration/bench_kinematics.hpp"
#include "common/units.hpp"

namespace calbench::station {
namespace {
using namespace devices;
constexpr int kOuter = 0, kInner = 1;
}  // namespace

StepRunner::StepRunner(const Options& o, std::ostream& log, const std::atomic<bool>& stop, const StationPlan& plan,
                       const SiteEarth& earth, Units& units, bool fixture_mode, std::shared_ptr<VirtualClock> clock,
                       std::chrono::steady_clock::time_point wall0)
    : o_(o), log_(log), stop_(stop), plan_(plan), earth_(earth), units_(units), fixture_mode_(fixture_mode),
      clock_(std::move(clock)),
      // In real time the bus is read by a thread of its own: a Modbus round trip to the table (a few ms)
      // must not hold up a data-ready stream whose samples come every 0.41 ms.
      threaded_(!clock_),
      mount_(plan.steps.front().mount),
      plan_s_(plan_duration_s(plan)),
      wall0_(wall0) {}

void StepRunner::run_plan() {
  for (step_index_ = 0; step_index_ < plan_.steps.size(); ++step_index_) {
    ask_prompts(step_index_);
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
    run_step(s);
    done_s_ += s.dwell_s + plan_.table.settle_s;
    progress("done", true);
  }
  ask_prompts(plan_.steps.size());
}

// The plan's operator prompts before table step `before` (after the last: steps.size()). The table
// is brought to rest first (a person is about to touch the fixture), and is kept under heartbeat while
// the station waits; the IMUs keep streaming (nothing is recorded).
void StepRunner::ask_prompts(std::size_t before) {
  for (const PlanPrompt& p : plan_.prompts) {
    if (p.before_step != before) continue;
    poll(true);
    inner_to_rest();
    LiveStep at = live_step();
    at.name = "prompt: " + p.text;
    at.kind = "prompt";
    at.fraction = 0;
    const auto keep_alive = [this] {
      if (threaded_) pump();  // drains the readers' queues (nothing is recorded between steps)
      poll(true);
    };
    if (live_) {
      live_->ask(p, units_, at, keep_alive, stop_);
    } else {
      LiveView terminal("", "", "", log_);
      terminal.ask(p, units_, at, keep_alive, stop_);
    }
    log_ << "prompt answered: " << p.text << "\n";
    if (clock_) pace_emu0_ = clock_->now(), pace_wall0_ = std::chrono::steady_clock::now();
  }
}

// A rotating inner axis: rate 0, wait until it stands, then position mode at where it stopped.
void StepRunner::inner_to_rest() {
  if (st_[kInner].mode != table::Mode::rate) return;
  table_->command_rate(kInner, 0.0);
  while (std::abs(st_[kInner].rate) > 1e-6) pump(), poll();
  table_->set_mode(kInner, table::Mode::position);
  poll(true);
}

void StepRunner::keep_pace() {
  if (!(o_.pace > 0) || !clock_) return;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - pace_wall0_).count();
  const double ahead = (clock_->now() - pace_emu0_) / o_.pace - wall;
  if (ahead > 0.005) std::this_thread::sleep_for(std::chrono::duration<double>(ahead));
}

LiveStep StepRunner::live_step() const {
  LiveStep l;
  const std::size_t n = plan_.steps.size();
  l.index = static_cast<int>(std::min(step_index_, n));
  l.count = static_cast<int>(n);
  if (step_index_ < n) {
    const PlanStep& s = plan_.steps[step_index_];
    l.name = s.label;
    l.kind = s.kind == StepKind::rate ? "rate" : "static";
    // Within the step: the share of its dwell recorded so far (0 while the table moves and settles).
    if (rec_step_ >= 0 && rec_dwell_ > 0 && std::isfinite(rec_dwell_)) l.fraction = std::clamp((now() - rec_t_poll_) / rec_dwell_, 0.0, 1.0);
  } else {
    l.name = "plan done";
    l.kind = "fit";
  }
  return l;
}

// One step on the live units: command, settle, record, check; the units whose data failed the check
// repeat it (up to --max-repeats), the others keep their rows.
void StepRunner::run_step(const PlanStep& s) {
  std::vector<Unit*> pending;
  for (auto& u : units_)
    if (u->live()) pending.push_back(u.get());
  int attempt = 0;
  for (;; ++attempt) {
    const int k = static_cast<int>(step_index_);
    if (plan_.position_only) {
      // A positions plan: the move to the pose, its settling and the dwell in one piece (the multipos
      // fit integrates the gyros across each rotation between two poses).
      begin_record(k, s, pending, std::numeric_limits<double>::infinity());
      command_step(s);
      wait_settled(s, 600);
      wait_for(plan_.table.settle_s + s.dwell_s);
      end_record(pending);
    } else {
      command_step(s);
      wait_settled(s, 600);
      wait_for(plan_.table.settle_s);
      record_step(k, s, pending);
    }
    std::vector<Unit*> again;
    for (Unit* u : pending) {
      if (u->failed) continue;
      const std::string why = step_check(*u);
      if (why.empty()) {
        write_rows(*u, false);
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
}

void StepRunner::fail_unit(Unit& u, const std::string& why) {
  if (u.failed) return;
  u.failed = true;
  u.why = why;
  u.recording = false;
  u.reading = false;
  log_ << (o_.progress_tty ? "\n" : "") << u.label() << " failed: " << why
       << (live_units(units_) ? " (the other units go on)" : "") << "\n";
  if (live_) live_->publish(units_, live_step(), true);
}

void StepRunner::poll(bool force) {
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

void StepRunner::start_readers() {
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

void StepRunner::stop_readers() {
  for (auto& u : units_) {
    u->reading = false;
    if (u->reader.joinable()) u->reader.join();
  }
}

// The next samples. Emulated time: the unit whose bus is furthest behind reads next (each unit has its
// own bridge, so their reads overlap in time); the table's clock is the slowest unit's. In real time:
// each unit's reader thread has queued its samples; they are taken here, on this thread.
void StepRunner::pump() {
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
    if (live_units(units_) == 0) throw Aborted("every unit failed");
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
  keep_pace();
  if (units_.size() > 1 && clock_) {
    double slowest = std::numeric_limits<double>::infinity();
    for (const auto& o : units_)
      if (!o->failed) slowest = std::min(slowest, o->bus->now());
    if (std::isfinite(slowest)) clock_->wait_until(slowest);
  }
  if (live_units(units_) == 0) throw Aborted("every unit failed");
}

void StepRunner::take(Unit& u, const ImuSample& x) {
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
  BenchKinematics kin = bench_kinematics(earth_, AxisState{rec_outer_, 0, 0}, AxisState{th, rec_rate_, 0}, rec_mount_);
  if (!u.at_centre) kin = slot_kinematics(kin, u.slot.pose);
  double a = std::fmod(units::deg(th), 360.0);
  u.ref_rows.push_back({x.t, kin.w_ib_b, kin.f_b, rec_step_, a < 0 ? a + 360.0 : a});
}

void StepRunner::wait_for(double seconds) {
  const double end = now() + seconds;
  while (now() < end) pump();
}

void StepRunner::command_step(const PlanStep& s) {
  // Outer axis: position. Inner: position for static steps; for rate steps stop at the start angle,
  // then rate mode. Positions go the short way round from the current (unwrapped) angle.
  poll(true);
  auto target = [&](int a, double ang) { return st_[a].position + std::remainder(ang - st_[a].position, 2 * M_PI); };
  inner_to_rest();
  table_->command_position(kOuter, target(kOuter, s.outer));
  table_->command_position(kInner, target(kInner, s.inner));
  if (s.kind == StepKind::rate) {
    wait_settled(s, 600);
    table_->command_rate(kInner, s.rate);
    table_->set_mode(kInner, table::Mode::rate);
  }
}

void StepRunner::wait_settled(const PlanStep& s, double timeout_s) {
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

void StepRunner::progress(const std::string& what, bool line) {
  const std::size_t n = plan_.steps.size();
  const double frac = std::min(1.0, done_s_ / std::max(plan_s_, 1e-9));
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  const double eta = frac > 0.01 ? wall * (1 - frac) / frac : 0;
  std::uint64_t samples = total(units_, &Unit::samples);
  for (const auto& u : units_) samples += u->imu_rows.size();
  char buf[240];
  std::snprintf(buf, sizeof buf, "[step %zu/%zu] %-22.22s %-8s outer %7.2f° inner %8.2f°/s  samples %llu  ETA %.0f s",
                step_index_ + 1, n, plan_.steps[std::min(step_index_, n - 1)].label.c_str(), what.c_str(),
                units::deg(st_[0].position), units::deg(st_[1].rate), static_cast<unsigned long long>(samples), eta);
  std::string text = buf;
  if (live_) live_->publish(units_, live_step(), line);
  if (units_.size() > 1) text += "  units " + std::to_string(live_units(units_)) + "/" + std::to_string(units_.size());
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
void StepRunner::record_step(int k, const PlanStep& s, const std::vector<Unit*>& units) {
  begin_record(k, s, units, s.dwell_s);
  auto busy = [&] {
    for (const Unit* u : units)
      if (u->recording) return true;
    return false;
  };
  while (busy()) pump();
  end_record(units);
}

void StepRunner::begin_record(int k, const PlanStep& s, const std::vector<Unit*>& units, double dwell_s) {
  poll(true);
  // Reference: the plan's angles for static steps (the table's position accuracy is in the plan), the
  // commanded rate and the encoder's inner angle at the start for rate steps.
  rec_outer_ = s.outer;
  rec_inner0_ = s.kind == StepKind::rate ? st_[kInner].position : s.inner;
  rec_rate_ = s.kind == StepKind::rate ? s.rate : 0.0;
  rec_t_poll_ = now();
  rec_dwell_ = dwell_s;
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
}

void StepRunner::end_record(const std::vector<Unit*>& units) {
  rec_step_ = -1;
  for (Unit* u : units) {
    u->recording = false;
    u->samples += u->imu_rows.size();
    u->lost += u->step_lost;
    u->error_samples += u->step_errors;
  }
}

std::string StepRunner::step_check(const Unit& u) const {
  if (u.step_lost) return std::to_string(u.step_lost) + " samples lost";
  if (u.step_errors) return std::to_string(u.step_errors) + " samples with error flags (" + u.err_text + ")";
  if (u.step_saturated) return std::to_string(u.step_saturated) + " saturated samples";
  return "";
}

// Nothing captured is lost: the step in progress did not pass its check (or was cut short), so its
// samples are kept with step −1 (outside any plan step: a fit will not use them); meta.json stays
// "incomplete".
// The unit's rows of a step into its recording (a positions plan's multipos recording has no reference
// table); `partial`: as step −1.
void StepRunner::write_rows(Unit& u, bool partial) {
  for (std::size_t i = 0; i < u.imu_rows.size() && i < u.ref_rows.size(); ++i) {
    u.writer->imu(u.imu_rows[i]);
    if (plan_.position_only) continue;
    BenchRefRow r = u.ref_rows[i];
    if (partial) r.step = -1;
    u.writer->bench_ref(r);
  }
  u.imu_rows.clear();
  u.ref_rows.clear();
  u.writer->flush();
}

void StepRunner::keep_partial(Unit& u) {
  if (!u.writer) return;
  try {
    write_rows(u, true);
  } catch (const std::exception& w) {
    log_ << "could not keep the partial step" << (fixture_mode_ ? " of " + u.label() : "") << ": " << w.what() << "\n";
  }
}

}  // namespace calbench::station
