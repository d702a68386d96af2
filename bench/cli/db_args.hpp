// What the `calbench db …` subcommands share (bench/cli/cmd_db.cpp registers them all): their
// arguments, the store they open, and the subcommands that bring runs and sets into the store
// (bench/cli/cmd_db_write.cpp).
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "db/store.hpp"

namespace calbench::cli::dbcmd {

struct DbArgs {
  std::string db;
  std::string op;  // --operator
  std::string serial;
  std::int64_t set = 0;
  std::string out, reason, thresholds, file;
  std::int64_t parent = 0;
  bool json = false;
  // store-bench
  std::string coeffs, recording, plan, station, started, ended, outcome = "pass", firmware, sha256;
  std::vector<std::string> qc;
  // settings
  std::string key, value;
  bool roles = false;  // db init --roles
  std::string journal;  // a station's journal (with a PostgreSQL --db)
  bool status = false;  // db sync --status
  std::string login, name, role;  // db user add
  std::string admin;               // db user add --admin LOGIN (SQLite console accounts)
};

inline std::string db_path(const DbArgs& a) { return a.db.empty() ? db::Store::default_path() : a.db; }

inline std::unique_ptr<db::Store> open_store(const DbArgs& a, bool create = false) {
  db::OpenOptions o;
  o.create = create;
  const db::Actor who = db::Actor::from_environment(a.op);  // a bad name is refused before the file is opened
  return std::make_unique<db::Store>(db_path(a), o, who);
}

// db import-inmotion: an in-motion fit result (RESULT.json) stored against its device.
void cmd_import_inmotion(const DbArgs& a);
// db store-bench: a bench run and its coefficient set (through the journal with a PostgreSQL --db).
void cmd_store_bench(const DbArgs& a);
// db sync: forward the journal's pending runs and sets to the central store (--db URI).
void cmd_sync(const DbArgs& a);
// db user add|list: the people behind PostgreSQL logins (bench/cli/cmd_db_user.cpp), under `db`.
void add_user_commands(CLI::App* db, const std::shared_ptr<DbArgs>& a);
// db verify: the record against the audit hash chain and the signed approvals (cmd_db_verify.cpp).
void add_verify_command(CLI::App* db, const std::shared_ptr<DbArgs>& a);

}  // namespace calbench::cli::dbcmd
