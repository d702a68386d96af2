// The station's live state and its operator prompts (issue 38 item 3; docs/devices.md "Live view
// and operator prompts"). With --db, `station run` writes one progress row per slot into that store
// (db/station_live.hpp: station_progress) as it goes — its step, the progress within it and the
// step's data check against its limit, or why the slot failed — and asks each prompt step of its plan
// there (station_prompts), waiting for a person's answer from the console (`calbench serve`, page
// /live). Without --db a prompt is asked on the terminal.
// The live view never costs a run: a write that fails is logged once, the run goes on (after three
// failures in a row the live view is switched off for the run, said in the log). A prompt is part
// of the plan: unanswered within its timeout, or rejected, the run ends as aborted (table stopped).
#pragma once
#include <atomic>
#include <functional>
#include <iosfwd>
#include <map>
#include <memory>
#include <string>

#include "bench/station/unit.hpp"
#include "calibration/bench_plan.hpp"

namespace calbench::db {
class Store;
}

namespace calbench::station {

// Where the run is: the same for every slot.
struct LiveStep {
  int index = 0, count = 0;  // 0-based step; index == count: after the last
  std::string name, kind;    // kind: static, rate, prompt, fit, done
  double fraction = 0;       // within the step, 0..1
};

// The step check every slot's row shows (StepRunner::step_check): the step's defective samples —
// lost, with error flags, or saturated — against the limit 0.
inline constexpr const char* kStepCheckName = "defective samples (lost, error flags, saturated) in the step";

class LiveView {
 public:
  // db: the station's --db (a SQLite file, or a PostgreSQL URI: written directly, as the station's
  // login); empty: no live rows, prompts on the terminal.
  LiveView(const std::string& db, std::string run_id, std::string station, std::ostream& log);
  ~LiveView();
  bool on() const { return store_ != nullptr; }
  const std::string& run_id() const { return run_id_; }

  // Every slot's row. Writes at most every 0.5 s (wall) unless `force`.
  void publish(const Units& units, const LiveStep& step, bool force = false);
  // The end of the run: each slot passed, failed (its reason) or, when `aborted` is not empty, aborted.
  void finish(const Units& units, const LiveStep& step, const std::string& aborted);

  // Asks `p` and waits for the answer. `keep_alive` runs about every 0.1 s (heartbeat the table, drain
  // the IMUs). Returns when a person confirmed; throws Aborted when rejected, unanswered within the
  // prompt's timeout, or stopped (Ctrl-C).
  void ask(const PlanPrompt& p, const Units& units, const LiveStep& step, const std::function<void()>& keep_alive,
           const std::atomic<bool>& stop);

 private:
  void write(const Units& units, const LiveStep& step, const std::string& waiting, const std::string& aborted);
  bool ask_terminal(const PlanPrompt& p, const std::function<void()>& keep_alive, const std::atomic<bool>& stop,
                    std::string& why);

  std::unique_ptr<db::Store> store_;
  std::string run_id_, station_;
  std::ostream& log_;
  double last_write_ = -1e9;
  std::map<std::string, LiveStep> failed_at_;  // a failed slot's row stays at the step where it failed
  int failures_ = 0;
};

}  // namespace calbench::station
