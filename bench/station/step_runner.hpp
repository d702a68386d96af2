// The station's step runner (bench/station/station.hpp): runs a plan's steps on the table and the
// fixture's units — command, settle, record, check, repeat a failed step — streaming the units'
// samples and polling the table (heartbeat, status, faults) all the while. A unit that fails is
// marked failed and the others go on (with one unit: Aborted). It never stops the table itself: the
// station does, on every path out of a run (bench/station/station.cpp).
#pragma once
#include <atomic>
#include <chrono>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "bench/io/plan_toml.hpp"
#include "bench/station/live.hpp"
#include "bench/station/station.hpp"
#include "bench/station/unit.hpp"
#include "calibration/bench_plan.hpp"
#include "calibration/earth.hpp"
#include "devices/emu_clock.hpp"
#include "devices/table_client.hpp"

namespace calbench::station {

class StepRunner {
 public:
  // `clock`: emulated time (the table's; several units: the slowest unit's), else null (real time:
  // a reader thread per unit). Every reference must outlive the runner.
  StepRunner(const Options& o, std::ostream& log, const std::atomic<bool>& stop, const StationPlan& plan,
             const SiteEarth& earth, Units& units, bool fixture_mode, std::shared_ptr<devices::VirtualClock> clock,
             std::chrono::steady_clock::time_point wall0);

  void attach_table(devices::TableClient& table) { table_ = &table; }
  void attach_live(LiveView& live) { live_ = &live; }
  // Where the run is, for the live view.
  LiveStep live_step() const;
  // Every step of the plan, in order, on the live units (start_readers() first).
  void run_plan();

  void poll(bool force = false);           // heartbeat + status at the heartbeat period
  void fail_unit(Unit& u, const std::string& why);
  void start_readers();
  void stop_readers();
  void keep_partial(Unit& u);              // the step in progress, kept as step −1

  // The fixture's current mount, and what the table last reported for axis a, extrapolated to time t
  // (the emulated IMUs' physics when the table is an external one).
  int mount() const { return mount_; }
  AxisState reported(int a, double t) const {
    return AxisState{st_[a].position + st_[a].rate * (t - last_poll_), st_[a].rate, 0};
  }

 private:
  void run_step(const PlanStep& s);       // command, settle, record, check; repeat failed units
  void pump();                            // take the next sample(s) of the units, keep polling
  void take(Unit& u, const devices::ImuSample& x);  // one sample of a unit: recorded when its step records
  void wait_settled(const PlanStep& s, double timeout_s);
  void wait_for(double seconds);          // keep streaming (and polling) for this long
  void record_step(int k, const PlanStep& s, const std::vector<Unit*>& units);  // begin, dwell, end
  void begin_record(int k, const PlanStep& s, const std::vector<Unit*>& units, double dwell_s);
  void end_record(const std::vector<Unit*>& units);
  void write_rows(Unit& u, bool partial);  // the step's rows into the unit's recording
  std::string step_check(const Unit& u) const;  // empty: the step's data passed
  void command_step(const PlanStep& s);
  void progress(const std::string& what, bool line = false);
  void ask_prompts(std::size_t before_step);  // the plan's operator prompts before this table step
  void inner_to_rest();
  double now() const { return clock_ ? clock_->now() : units_.front()->bus->now(); }
  void check_stop() {
    if (stop_) throw Aborted("interrupted (Ctrl-C)");
  }

  const Options& o_;
  std::ostream& log_;
  const std::atomic<bool>& stop_;
  const StationPlan& plan_;
  const SiteEarth& earth_;
  Units& units_;
  const bool fixture_mode_;               // a fixture (file or --units): units named by slot
  std::shared_ptr<devices::VirtualClock> clock_;
  const bool threaded_;                   // real time: a reader thread per unit
  devices::TableClient* table_ = nullptr;
  LiveView* live_ = nullptr;
  int mount_ = 2;                         // the fixture's current mount
  double last_poll_ = -1e9;
  devices::AxisStatus st_[2];
  // The step being recorded: the reference the samples get.
  double rec_outer_ = 0, rec_inner0_ = 0, rec_rate_ = 0, rec_t_poll_ = 0, rec_dwell_ = 0;
  int rec_step_ = -1, rec_mount_ = 2;
  std::size_t step_index_ = 0;
  double plan_s_ = 0, done_s_ = 0;
  std::uint64_t pumps_ = 0;
  std::chrono::steady_clock::time_point wall0_;
  // --pace: emulated time since pace_emu0_ at most pace x the wall time since pace_wall0_ (re-anchored
  // after an operator prompt, during which emulated time stands still).
  double pace_emu0_ = 0;
  std::chrono::steady_clock::time_point pace_wall0_ = std::chrono::steady_clock::now();
  void keep_pace();
};

}  // namespace calbench::station
