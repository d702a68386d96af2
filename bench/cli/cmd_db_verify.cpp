// calbench db verify: is the store's record the one calbench wrote? (issue 54 item 4)
// SQLite: the audit log's hash chain, the console accounts against their audit rows, and every
// approved or provisioned set against its signed approval. PostgreSQL: the signed approvals (its
// audit rows are written only by the server's functions; it has no chain).
#include <iostream>
#include <nlohmann/json.hpp>

#include "bench/cli/db_args.hpp"
#include "bench/cli/registry.hpp"
#include "bench/io/json_util.hpp"
#include "db/audit_chain.hpp"
#include "db/console_accounts.hpp"
#include "db/signed_approval.hpp"

namespace calbench::cli::dbcmd {
namespace {
using nlohmann::json;

void cmd_verify(const DbArgs& a) {
  auto s = open_store(a);
  json problems = json::array();
  const db::ChainCheck chain = db::check_audit_chain(*s);
  for (const auto& b : chain.breaks) problems.push_back({{"audit_row", b.id}, {"problem", b.why}});
  const auto accounts = db::check_console_accounts(*s);
  for (const auto& x : accounts) problems.push_back({{"console_account", x.login}, {"problem", x.why}});
  std::int64_t sets = 0;
  for (const auto& d : s->devices())
    for (const auto& set : s->sets_of(d.id)) {
      if (set.status != db::SetStatus::approved && set.status != db::SetStatus::provisioned) continue;
      ++sets;
      if (const db::SignedApproval sa = db::signed_approval(*s, set); !sa.ok)
        problems.push_back({{"set", set.id}, {"serial", set.serial}, {"problem", sa.why}});
    }
  const bool admin = s->authenticated() || db::has_admin_account(*s);
  if (a.json) {
    print_json(json{{"ok", problems.empty()}, {"audit_rows", chain.rows}, {"chain", chain.applies},
                    {"chain_head", chain.head}, {"approved_sets_checked", sets}, {"admin_account", admin},
                    {"problems", problems}}
                   .dump(2));
  } else {
    if (chain.applies)
      std::cout << "audit log: " << chain.rows << " row(s), hash chain " << (chain.ok() ? "intact" : "BROKEN")
                << (chain.head.empty() ? "" : ", head " + chain.head) << "\n";
    else
      std::cout << "audit log: written only by the server's functions (PostgreSQL; no hash chain)\n";
    std::cout << "approved or provisioned sets: " << sets << " checked against their signed approval\n";
    if (!admin)
      std::cout << "note: no admin console account: anyone who can write this file may add console accounts "
                   "(calbench db user add LOGIN --role admin)\n";
    for (const auto& p : problems) std::cout << "PROBLEM: " << p.dump() << "\n";
    std::cout << (problems.empty() ? "verified: the record is the one calbench wrote\n"
                                   : std::to_string(problems.size()) + " problem(s): the record was changed outside calbench\n");
  }
  if (!problems.empty()) throw Exit{1};
}
}  // namespace

void add_verify_command(CLI::App* db, const std::shared_ptr<DbArgs>& a) {
  auto* v = db->add_subcommand("verify", "check that the store's record is the one calbench wrote (audit hash chain, "
                                         "console accounts, signed approvals); exit 1 on any problem");
  v->add_option("--db", a->db, "a SQLite store FILE or the central store postgresql://USER@HOST[:PORT]/DB (default: $CALBENCH_DB)");
  v->add_flag("--json", a->json, "machine-readable output");
  v->footer("SQLite: every audit row's hash-chain link (a row inserted, edited or removed with sqlite3 breaks it), each\n"
            "console account against its last audit row, and each approved or provisioned set against a valid signed\n"
            "approval. The chain head printed here, kept elsewhere, also shows a log rewritten and re-chained.\n"
            "PostgreSQL: the signed approvals (audit rows there are written only by the server's functions).");
  v->callback([a] { cmd_verify(*a); });
}

}  // namespace calbench::cli::dbcmd
