// The station's live state and its operator prompts in the store (issue 38 item 3; schema 8,
// tables station_progress and station_prompts; docs/database.md "Station progress and operator
// prompts"). `station run --db` writes one progress row per slot of its run as it goes and raises a
// prompt for each prompt step of its plan; a person answers a prompt from the store (`station
// answer`, later the console) through answer_prompt(). Readers (the live view) take the rows with
// the age of their heartbeat: a run that died leaves rows whose heartbeat goes stale.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "db/store.hpp"

namespace calbench::db {

// One slot of one station run, as it is now.
struct SlotProgress {
  std::string run_id, slot, station;
  std::string login;      // read: who wrote it (PostgreSQL: stamped by the server)
  std::string serial;     // "" before the unit was identified
  int step_index = 0;     // 0-based; step_count when the plan is done
  int step_count = 0;
  std::string step_name;  // the plan step's label, or "identify", "fit", "prompt: …"
  std::string step_kind;  // "static", "rate", "prompt", "setup", "fit", "done"
  double step_fraction = 0;  // progress within the step, 0..1
  // The step's data check: its figure against its limit (value ≤ limit passes), in `check_unit`.
  std::string check_name;
  std::optional<double> check_value, check_limit;
  std::string check_unit;
  std::string state = "running";  // running | waiting (an operator prompt) | passed | failed | aborted
  std::string reason;             // failed, aborted: why (required); waiting: the prompt
  std::string started_at, heartbeat_at;  // read: ISO 8601 UTC
};

// Writes (replaces) the row of p.run_id/p.slot with the heartbeat now. InputError on a bad state or
// fraction; PermissionError when the database refuses it (PostgreSQL: another login's row).
void put_progress(Store& store, const SlotProgress& p);
// Rows of every run (run_id empty) or of one, newest heartbeat first, then by run and slot; with
// `since` (ISO 8601 UTC), only rows whose heartbeat is that recent (through the heartbeat index).
std::vector<SlotProgress> progress_rows(Store& store, const std::string& run_id = "", const std::string& since = "");

// A prompt's states: waiting, then once confirmed, rejected or timed out.
struct Prompt {
  std::int64_t id = 0;
  std::string run_id, station, slot, text;
  double timeout_s = 0;
  std::string created_at, created_login;
  std::string state = "waiting";
  std::string reason;                      // rejected: why; timed out: the timeout
  std::string answered_by, answered_login, answered_at;
};
// A new waiting prompt of a run (audited). Returns its id.
std::int64_t create_prompt(Store& store, const std::string& run_id, const std::string& station, const std::string& slot,
                           const std::string& text, double timeout_s);
std::optional<Prompt> find_prompt(Store& store, std::int64_t id);
// Waiting prompts (run_id empty: of every run), oldest first.
std::vector<Prompt> waiting_prompts(Store& store, const std::string& run_id = "");
// A person's answer, by the store's actor (name, and login: PostgreSQL's session_user), audited.
// confirm = false: rejected, `reason` required. InputError: no such prompt, or it is no longer
// waiting (say how it was answered, by whom and when).
Prompt answer_prompt(Store& store, std::int64_t id, bool confirm, const std::string& reason);
// The station gives up waiting: timed out (if still waiting; returns the prompt as it ends).
Prompt expire_prompt(Store& store, std::int64_t id);

// Seconds from an ISO 8601 UTC timestamp (as the store writes them, with or without milliseconds)
// to `now_epoch_s`; NaN when it does not parse.
double age_s(const std::string& iso_utc, double now_epoch_s);
double epoch_now_s();
// An epoch time as ISO 8601 UTC to the second ("2026-11-27T08:30:00Z"), as the store compares times.
std::string iso_utc_at(double epoch_s);

}  // namespace calbench::db
