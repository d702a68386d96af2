#include "db/journal.hpp"

#include <cstdlib>

namespace calbench::db {

std::string journal_path(const std::string& option) {
  if (!option.empty()) return option;
  const char* e = std::getenv("CALBENCH_JOURNAL");
  return e && *e ? e : "calbench-journal.db";
}

std::vector<PendingItem> pending(Store& journal) {
  std::vector<PendingItem> out;
  auto st = journal.connection().prepare(
      "SELECT r.id, r.uid, d.serial, r.outcome, r.created_at, "
      "EXISTS (SELECT 1 FROM coefficient_sets s WHERE s.bench_run_id = r.id) FROM bench_runs r "
      "JOIN devices d ON d.id = r.device_id WHERE r.uid IS NOT NULL AND r.uid NOT IN (SELECT uid FROM forwarded) "
      "ORDER BY r.id");
  while (st.step()) out.push_back(PendingItem{st.int64(0), st.text(1), st.text(2), st.text(3), st.text(4), st.int64(5) != 0});
  return out;
}

namespace {

// Who stored the run in the journal (its audit entry), to be recorded as its author at the centre.
Actor run_author(Store& journal, std::int64_t run_id, std::string* detail) {
  auto st = journal.connection().prepare(
      "SELECT \"user\", station, detail FROM audit_log WHERE entity = 'bench_run' AND entity_id = ? AND action = 'create' "
      "ORDER BY id LIMIT 1");
  st.bind(1, run_id);
  Actor a{"unknown", "unknown", "journal"};
  if (st.step()) {
    a.user = st.text(0);
    a.station = st.text(1);
    if (detail) *detail = st.text(2);
  }
  return a;
}

}  // namespace

SyncOutcome sync_journal(Store& journal, const std::string& central, const OpenOptions& central_opt) {
  SyncOutcome out;
  const std::vector<PendingItem> items = pending(journal);
  out.pending_after = static_cast<int>(items.size());
  if (items.empty()) return out;
  std::unique_ptr<Store> c;
  try {
    c = std::make_unique<Store>(central, central_opt, journal.actor());
  } catch (const ConnectionLost& e) {
    out.reached = false;
    out.error = e.what();
    return out;
  }
  for (const PendingItem& it : items) {
    const auto run = journal.bench_run(it.local_run_id);
    if (!run) continue;
    const auto dev = [&] {
      auto st = journal.connection().prepare("SELECT model, serial, firmware FROM devices WHERE id = ?");
      st.bind(1, run->device_id);
      st.step();
      return DeviceInfo{st.text(0), st.text(1), st.text(2)};
    }();
    BenchRunInput in;
    in.station = run->station;
    in.plan = run->plan;
    in.recording_path = run->recording_path;
    in.recording_sha256 = run->recording_sha256;
    in.recording_uri = run->recording_uri;
    in.recording_digest = run->recording_digest;
    in.started_at = run->started_at;
    in.ended_at = run->ended_at;
    in.outcome = run->outcome;
    in.slot = run->slot;
    in.table_run = run->table_run;
    in.qc = journal.qc_of_bench_run(run->id);
    in.uid = it.uid;
    std::string detail;
    c->set_actor(run_author(journal, run->id, &detail));
    std::string line = it.serial + " run " + std::to_string(run->id) + " (" + run->outcome + ")";
    std::int64_t central_id = 0;
    bool existed = false;
    SyncOutcome::Item item{it.uid};
    try {
      if (it.has_set) {
        auto st = journal.connection().prepare(
            "SELECT payload_json FROM coefficient_sets WHERE bench_run_id = ? ORDER BY id LIMIT 1");
        st.bind(1, run->id);
        st.step();
        const StoredSet s = c->store_bench(dev, in, st.text(0));
        central_id = s.run_id;
        existed = s.existed;
        item.central_set = s.set_id;
        item.version = s.version;
        line += " -> central run " + std::to_string(s.run_id) + ", set " + std::to_string(s.set_id) + " (v" +
                std::to_string(s.version) + ")";
      } else {
        // The reason recorded with the run: its audit text after "plan P, outcome O: ".
        const std::string head = "plan " + run->plan + ", outcome " + run->outcome;
        std::string why = detail.rfind(head, 0) == 0 ? detail.substr(head.size()) : detail;
        if (why.rfind(": ", 0) == 0) why = why.substr(2);
        if (const auto p = why.find("; partial recording "); p != std::string::npos) why = why.substr(0, p);
        central_id = c->store_bench_run(dev, in, why, &existed);
        line += " -> central run " + std::to_string(central_id);
      }
    } catch (const ConnectionLost& e) {
      out.reached = out.forwarded + out.already > 0;
      out.error = e.what();
      break;
    }
    // The centre has it (committed): record that here. A crash before this line forwards it again,
    // and the centre returns the same ids.
    journal.connection().write_transaction([&] {
      auto st = journal.connection().prepare(
          std::string("INSERT INTO forwarded(uid, entity, local_id, central_id, target, at) VALUES (?, 'bench_run', ?, ?, ?, ") +
          journal.connection().now_sql() + ") ON CONFLICT(uid) DO NOTHING");
      st.bind(1, it.uid).bind(2, run->id).bind(3, central_id).bind(4, c->connection().path()).run();
    });
    (existed ? out.already : out.forwarded) += 1;
    item.central_run = central_id;
    item.existed = existed;
    out.items.push_back(item);
    out.pending_after -= 1;
    out.lines.push_back(line + (existed ? " (already there)" : ""));
  }
  return out;
}

}  // namespace calbench::db
