// A station's journal (issue 18): with a central PostgreSQL store, every bench run and its set is
// written first to a local SQLite store of the same schema, the journal, and then forwarded to
// the centre — at the end of the run when the server answers, else by `calbench db sync`. The
// station never waits for the network.
//
// Exactly once: each run and set carries a stable uid (the journal's); the centre stores a uid
// once (Store::store_bench returns the earlier store on a repeat), and the journal records what
// reached the centre (table `forwarded`) only after the centre committed. A sync killed between
// the two commits forwards the item again at the next sync, and the centre keeps one copy.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "db/store.hpp"

namespace calbench::db {

// The journal's file: `option` if given, else $CALBENCH_JOURNAL, else ./calbench-journal.db.
std::string journal_path(const std::string& option);

struct PendingItem {
  std::int64_t local_run_id = 0;
  std::string uid, serial, outcome, created_at;
  bool has_set = false;
};
// Runs in the journal that have not reached the centre, oldest first.
std::vector<PendingItem> pending(Store& journal);

struct SyncOutcome {
  bool reached = true;         // false: the centre did not answer (nothing forwarded; `error` says why)
  std::string error;
  int forwarded = 0;           // stored at the centre by this sync
  int already = 0;             // found there already (an earlier sync was interrupted), now marked
  int pending_after = 0;       // still in the journal only
  std::vector<std::string> lines;  // one per item: "A100 run 3 -> central run 17, set 21 (v2)"
  struct Item {
    std::string uid;  // the run's
    std::int64_t central_run = 0, central_set = 0;  // central_set 0: a run without a set
    int version = 0;
    bool existed = false;
  };
  std::vector<Item> items;  // what reached the centre, in order
};
// Forward every pending item of `journal` to the store at `central` (a PostgreSQL URI). Items are
// forwarded one transaction each, in order; a lost connection stops the sync (reached = false when
// nothing could be forwarded). Errors other than an unreachable server propagate.
SyncOutcome sync_journal(Store& journal, const std::string& central, const OpenOptions& central_opt = {});

}  // namespace calbench::db
