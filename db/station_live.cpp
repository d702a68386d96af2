// The station's live state and operator prompts (db/station_live.hpp).
#include "db/station_live.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>

#include "common/input_error.hpp"

namespace calbench::db {
namespace {

const char* kProgressColumns =
    "run_id, slot, station, login, serial, step_index, step_count, step_name, step_kind, step_fraction, check_name, "
    "check_value, check_limit, check_unit, state, reason, started_at, heartbeat_at";

SlotProgress read_progress(Statement& st) {
  SlotProgress p;
  p.run_id = st.text(0), p.slot = st.text(1), p.station = st.text(2), p.login = st.text(3), p.serial = st.text(4);
  p.step_index = static_cast<int>(st.int64(5)), p.step_count = static_cast<int>(st.int64(6));
  p.step_name = st.text(7), p.step_kind = st.text(8), p.step_fraction = st.real(9), p.check_name = st.text(10);
  p.check_value = st.opt_real(11), p.check_limit = st.opt_real(12), p.check_unit = st.text(13);
  p.state = st.text(14), p.reason = st.text(15), p.started_at = st.text(16), p.heartbeat_at = st.text(17);
  return p;
}

const char* kPromptColumns =
    "id, run_id, station, slot, text, timeout_s, created_at, created_login, state, reason, answered_by, "
    "answered_login, answered_at";

Prompt read_prompt(Statement& st) {
  Prompt p;
  p.id = st.int64(0), p.run_id = st.text(1), p.station = st.text(2), p.slot = st.text(3), p.text = st.text(4);
  p.timeout_s = st.real(5), p.created_at = st.text(6), p.created_login = st.text(7), p.state = st.text(8);
  p.reason = st.text(9), p.answered_by = st.text(10), p.answered_login = st.text(11), p.answered_at = st.text(12);
  return p;
}

bool one_of(const std::string& s, std::initializer_list<const char*> set) {
  for (const char* x : set)
    if (s == x) return true;
  return false;
}

}  // namespace

void put_progress(Store& store, const SlotProgress& p) {
  if (p.run_id.empty() || p.slot.empty()) throw InputError("station_progress", 0, "run_id/slot", "empty");
  if (!one_of(p.state, {"running", "waiting", "passed", "failed", "aborted"}))
    throw InputError("station_progress", 0, "state", "'" + p.state + "' is not running, waiting, passed, failed or aborted");
  if ((p.state == "failed" || p.state == "aborted") && p.reason.empty())
    throw InputError("station_progress", 0, "reason", "a " + p.state + " slot says why");
  if (!(p.step_fraction >= 0 && p.step_fraction <= 1))
    throw InputError("station_progress", 0, "step_fraction", "must be within 0..1");
  Connection& c = store.connection();
  const std::string now = c.now_sql();
  c.write_transaction([&] {
  auto st = c.prepare(
      "INSERT INTO station_progress(run_id, slot, station, login, serial, step_index, step_count, step_name, step_kind, "
      "step_fraction, check_name, check_value, check_limit, check_unit, state, reason, started_at, heartbeat_at) "
      "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, " + now + ", " + now + ") "
      "ON CONFLICT (run_id, slot) DO UPDATE SET station = excluded.station, login = excluded.login, "
      "serial = excluded.serial, step_index = excluded.step_index, step_count = excluded.step_count, "
      "step_name = excluded.step_name, step_kind = excluded.step_kind, step_fraction = excluded.step_fraction, "
      "check_name = excluded.check_name, check_value = excluded.check_value, check_limit = excluded.check_limit, "
      "check_unit = excluded.check_unit, state = excluded.state, reason = excluded.reason, "
      "heartbeat_at = excluded.heartbeat_at");
  st.bind(1, p.run_id).bind(2, p.slot).bind(3, p.station).bind(4, store.login()).bind(5, p.serial);
  st.bind(6, p.step_index).bind(7, p.step_count).bind(8, p.step_name).bind(9, p.step_kind).bind(10, p.step_fraction);
  st.bind(11, p.check_name).bind(12, p.check_value).bind(13, p.check_limit).bind(14, p.check_unit);
  st.bind(15, p.state).bind(16, p.reason);
  st.run();
  });
}

std::vector<SlotProgress> progress_rows(Store& store, const std::string& run_id, const std::string& since) {
  std::vector<SlotProgress> out;
  auto st = store.connection().prepare(std::string("SELECT ") + kProgressColumns +
                                       " FROM station_progress WHERE (? = '' OR run_id = ?) " +
                                       (since.empty() ? "" : "AND heartbeat_at >= ? ") +
                                       "ORDER BY heartbeat_at DESC, run_id, slot");
  st.bind(1, run_id).bind(2, run_id);
  if (!since.empty()) st.bind(3, since);
  while (st.step()) out.push_back(read_progress(st));
  return out;
}

std::int64_t create_prompt(Store& store, const std::string& run_id, const std::string& station, const std::string& slot,
                           const std::string& text, double timeout_s) {
  if (text.empty()) throw InputError("station_prompts", 0, "text", "a prompt says what to do");
  if (!(timeout_s > 0 && std::isfinite(timeout_s))) throw InputError("station_prompts", 0, "timeout_s", "must be > 0");
  Connection& c = store.connection();
  std::int64_t id = 0;
  c.write_transaction([&] {
    auto st = c.prepare(std::string("INSERT INTO station_prompts(run_id, station, slot, text, timeout_s, created_at, "
                                    "created_login) VALUES (?, ?, ?, ?, ?, ") + c.now_sql() + ", ?) RETURNING id");
    st.bind(1, run_id).bind(2, station).bind(3, slot).bind(4, text).bind(5, timeout_s).bind(6, store.login());
    st.step();
    id = st.int64(0);
    store.audit_locked("station_prompt", id, "ask", "run " + run_id + (slot.empty() ? "" : ", slot " + slot) + ": " + text);
  });
  return id;
}

std::optional<Prompt> find_prompt(Store& store, std::int64_t id) {
  auto st = store.connection().prepare(std::string("SELECT ") + kPromptColumns + " FROM station_prompts WHERE id = ?");
  st.bind(1, id);
  if (!st.step()) return std::nullopt;
  return read_prompt(st);
}

std::vector<Prompt> waiting_prompts(Store& store, const std::string& run_id) {
  std::vector<Prompt> out;
  auto st = store.connection().prepare(std::string("SELECT ") + kPromptColumns +
                                       " FROM station_prompts WHERE state = 'waiting' AND (? = '' OR run_id = ?) "
                                       "ORDER BY id");
  st.bind(1, run_id).bind(2, run_id);
  while (st.step()) out.push_back(read_prompt(st));
  return out;
}

namespace {
// Ends a waiting prompt (answered, or timed out), audited, in one transaction. A prompt no longer
// waiting is an InputError saying how it ended (answer) or is returned as it is (timeout).
Prompt end_prompt(Store& store, std::int64_t id, const std::string& state, const std::string& reason, bool must_wait) {
  Connection& c = store.connection();
  Prompt out;
  c.write_transaction([&] {
    const auto p = find_prompt(store, id);
    if (!p) throw InputError("prompt", 0, "", "no operator prompt " + std::to_string(id) + " in " + c.path());
    if (p->state != "waiting") {
      if (!must_wait) {
        out = *p;
        return;
      }
      throw InputError("prompt", 0, "",
                       "prompt " + std::to_string(id) + " is no longer waiting: " + p->state +
                           (p->answered_by.empty() ? "" : " by " + p->answered_by) +
                           (p->answered_at.empty() ? "" : " at " + p->answered_at) +
                           (p->reason.empty() ? "" : " (" + p->reason + ")"));
    }
    // PostgreSQL stamps answered_login itself (trigger calbench_prompt_answer; the column is not
    // granted to anyone); SQLite records the store's login.
    const bool pg = store.authenticated();
    auto st = c.prepare(std::string("UPDATE station_prompts SET state = ?, reason = ?, answered_by = ?, ") +
                        (pg ? "" : "answered_login = ?, ") + "answered_at = " + c.now_sql() +
                        " WHERE id = ? AND state = 'waiting'");
    const bool person = state != "timed out";
    st.bind(1, state).bind(2, reason).bind(3, person ? store.actor().user : std::string("station"));
    if (pg) st.bind(4, id);
    else st.bind(4, store.login()).bind(5, id);
    st.run();
    store.audit_locked("station_prompt", id, state == "timed out" ? "timeout" : "answer",
                       state + (reason.empty() ? "" : ": " + reason));
    out = *find_prompt(store, id);
  });
  return out;
}
}  // namespace

Prompt answer_prompt(Store& store, std::int64_t id, bool confirm, const std::string& reason) {
  if (!confirm && reason.find_first_not_of(" \t\r\n") == std::string::npos)
    throw InputError("reason", 0, "", "a rejection says why (the reason is empty)");
  // SQLite with a console account: the twin of PostgreSQL's grant (UPDATE on station_prompts to
  // calbench_station and calbench_qc only).
  const std::string& role = store.console_role();
  if (!role.empty() && role != "station" && role != "qc")
    throw PermissionError(0, store.connection().path() + ": refused to a " + role +
                                 " account: only a station or QC account answers an operator prompt (as only a login "
                                 "in calbench_station or calbench_qc may on PostgreSQL)",
                          "42501");
  return end_prompt(store, id, confirm ? "confirmed" : "rejected", reason, true);
}

Prompt expire_prompt(Store& store, std::int64_t id) {
  const auto p = find_prompt(store, id);
  if (!p) throw InputError("PROMPT_ID", 0, "", "no operator prompt " + std::to_string(id));
  char why[64];
  std::snprintf(why, sizeof why, "not answered within %g s", p->timeout_s);
  return end_prompt(store, id, "timed out", why, false);
}

double age_s(const std::string& iso, double now_epoch_s) {
  std::tm tm{};
  int ms = 0;
  char frac[8] = "";
  // 2026-11-27T01:02:03.456Z (SQLite, PostgreSQL as the store reads it) or without milliseconds.
  if (std::sscanf(iso.c_str(), "%4d-%2d-%2d%*1[T ]%2d:%2d:%2d", &tm.tm_year, &tm.tm_mon, &tm.tm_mday, &tm.tm_hour, &tm.tm_min,
                  &tm.tm_sec) != 6)
    return NAN;
  if (iso.size() > 20 && iso[19] == '.' && std::sscanf(iso.c_str() + 20, "%3[0-9]", frac) == 1) {
    ms = std::atoi(frac);
    for (std::size_t k = std::strlen(frac); k < 3; ++k) ms *= 10;
  }
  tm.tm_year -= 1900;
  tm.tm_mon -= 1;
  const double t = static_cast<double>(timegm(&tm)) + ms / 1000.0;
  return now_epoch_s - t;
}

std::string iso_utc_at(double epoch_s) {
  const std::time_t t = static_cast<std::time_t>(std::floor(epoch_s));
  std::tm tm{};
  gmtime_r(&t, &tm);
  char b[32];
  std::strftime(b, sizeof b, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return b;
}

double epoch_now_s() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace calbench::db
