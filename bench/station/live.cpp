#include "bench/station/live.hpp"

#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ostream>
#include <thread>

#include "db/station_live.hpp"
#include "db/store.hpp"

namespace calbench::station {
namespace {
double wall_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
std::string slot_name(const Unit& u) { return u.slot.name.empty() ? "1" : u.slot.name; }
}  // namespace

LiveView::LiveView(const std::string& db, std::string run_id, std::string station, std::ostream& log)
    : run_id_(std::move(run_id)), station_(std::move(station)), log_(log) {
  if (db.empty()) return;
  try {
    db::OpenOptions o;
    o.create = !db::is_postgres_uri(db);  // the station's own SQLite file; a central store exists already
    store_ = std::make_unique<db::Store>(db, o, db::Actor::from_environment());
    log_ << "live view: run " << run_id_ << " in " << db::redact_uri(db) << " (calbench serve, page /live)\n";
  } catch (const std::exception& e) {
    log_ << "live view off: " << e.what() << " (the run goes on; its prompts are asked on the terminal)\n";
  }
}

LiveView::~LiveView() = default;

void LiveView::write(const Units& units, const LiveStep& step, const std::string& waiting, const std::string& aborted) {
  if (!store_) return;
  try {
    for (const auto& up : units) {
      const Unit& u = *up;
      db::SlotProgress p;
      p.run_id = run_id_;
      p.slot = slot_name(u);
      if (u.failed) failed_at_.emplace(p.slot, step);
      const LiveStep& at = u.failed ? failed_at_.at(p.slot) : step;
      p.station = station_;
      if (u.imu && u.identified) p.serial = u.imu->identity().serial_string();
      p.step_index = at.index;
      p.step_count = at.count;
      p.step_name = at.name;
      p.step_kind = at.kind;
      p.step_fraction = std::isfinite(at.fraction) ? std::clamp(at.fraction, 0.0, 1.0) : 0.0;
      p.check_name = kStepCheckName;
      p.check_value = static_cast<double>(u.step_lost + u.step_errors + u.step_saturated);
      p.check_limit = 0;
      p.check_unit = "samples";
      if (u.failed) {
        p.state = "failed";
        p.reason = u.why.empty() ? "failed" : u.why;
      } else if (!aborted.empty()) {
        p.state = "aborted";
        p.reason = aborted;
      } else if (step.kind == "done") {
        p.state = "passed";
      } else if (!waiting.empty()) {
        p.state = "waiting";
        p.reason = waiting;
      } else {
        p.state = "running";
      }
      db::put_progress(*store_, p);
    }
    failures_ = 0;
  } catch (const std::exception& e) {
    if (++failures_ == 1) log_ << "\nlive view: could not write the progress rows: " << e.what() << " (the run goes on)\n";
    if (failures_ >= 3) {
      log_ << "\nlive view off for this run after 3 failed writes in a row\n";
      store_.reset();
    }
  }
}

void LiveView::publish(const Units& units, const LiveStep& step, bool force) {
  const double now = wall_s();
  if (!force && now - last_write_ < 0.5) return;
  last_write_ = now;
  write(units, step, "", "");
}

void LiveView::finish(const Units& units, const LiveStep& step, const std::string& aborted) {
  write(units, step, "", aborted);
}

void LiveView::ask(const PlanPrompt& p, const Units& units, const LiveStep& step, const std::function<void()>& keep_alive,
                   const std::atomic<bool>& stop) {
  const std::string what = "operator prompt" + std::string(p.slot.empty() ? "" : " (slot " + p.slot + ")") + ": " + p.text;
  std::string why;
  bool confirmed = false;
  if (!store_) {
    confirmed = ask_terminal(p, keep_alive, stop, why);
  } else {
    std::int64_t id = 0;
    try {
      id = db::create_prompt(*store_, run_id_, station_, p.slot, p.text, p.timeout_s);
    } catch (const std::exception& e) {
      log_ << "\nlive view: could not ask in the store (" << e.what() << "): asking on the terminal\n";
    }
    if (id == 0) {
      confirmed = ask_terminal(p, keep_alive, stop, why);
    } else {
      write(units, step, p.text, "");
      log_ << "\n" << what << "\n  waiting for an answer in the console (page /live, prompt " << id << "), at most "
           << p.timeout_s << " s\n";
      const double end = wall_s() + p.timeout_s;
      double next_check = 0, next_beat = wall_s() + 5;
      for (;;) {
        if (stop) {
          try {
            db::expire_prompt(*store_, id);
          } catch (const std::exception&) {
          }
          throw Aborted("interrupted (Ctrl-C) while waiting for an operator's answer to: " + p.text);
        }
        keep_alive();
        const double now = wall_s();
        if (now >= next_beat) {  // the rows' heartbeat: the station is alive while it waits
          next_beat = now + 5;
          write(units, step, p.text, "");
        }
        if (now >= next_check) {
          next_check = now + 0.25;
          std::optional<db::Prompt> a;
          try {
            a = db::find_prompt(*store_, id);
          } catch (const std::exception& e) {
            log_ << "\nlive view: could not read prompt " << id << ": " << e.what() << "\n";
          }
          if (a && a->state == "confirmed") {
            log_ << "confirmed by " << a->answered_by << "\n";
            confirmed = true;
            break;
          }
          if (a && a->state == "rejected") {
            why = "rejected by " + a->answered_by + ": " + a->reason;
            break;
          }
          if (now >= end) {
            const db::Prompt e = db::expire_prompt(*store_, id);
            if (e.state == "confirmed") {  // answered in the last instant
              confirmed = true;
              break;
            }
            why = e.state == "rejected" ? "rejected by " + e.answered_by + ": " + e.reason : e.reason;
            break;
          }
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    }
  }
  if (!confirmed) throw Aborted("operator prompt '" + p.text + "' " + why);
  last_write_ = -1e9;
}

// No store to answer in: the terminal. "y", "Y" or "yes" confirms; an empty line asks again; any
// other line rejects (the line is the reason); a closed standard input rejects.
bool LiveView::ask_terminal(const PlanPrompt& p, const std::function<void()>& keep_alive, const std::atomic<bool>& stop,
                            std::string& why) {
  log_ << "\noperator prompt" << (p.slot.empty() ? "" : " (slot " + p.slot + ")") << ": " << p.text
       << "\n  type y and Enter to confirm, or a reason to reject (at most " << p.timeout_s << " s): " << std::flush;
  const double end = wall_s() + p.timeout_s;
  std::string line;
  while (wall_s() < end) {
    if (stop) throw Aborted("interrupted (Ctrl-C) while waiting for an operator's answer to: " + p.text);
    keep_alive();
    pollfd fd{STDIN_FILENO, POLLIN, 0};
    if (::poll(&fd, 1, 100) <= 0) continue;
    char c = 0;
    const ssize_t n = ::read(STDIN_FILENO, &c, 1);
    if (n <= 0) {
      why = "not answered: standard input closed (no operator at the terminal, and no --db store to answer from)";
      return false;
    }
    if (c == '\r') continue;  // a CR LF line end
    if (c != '\n') {
      if (line.size() < 500) line += c;
      continue;
    }
    if (line.find_first_not_of(" \t") == std::string::npos) {  // Enter alone: ask again, never abort a run
      log_ << "  type y and Enter to confirm, or a reason to reject: " << std::flush;
      line.clear();
      continue;
    }
    if (line == "y" || line == "yes" || line == "Y") return true;
    why = "rejected at the terminal: " + (line.empty() ? std::string("(no reason given)") : line);
    return false;
  }
  why = "not answered within " + std::to_string(static_cast<long long>(p.timeout_s)) + " s";
  return false;
}

}  // namespace calbench::station
