// calbench db user add|list: who a PostgreSQL login is (db/users.hpp, issue 35).
#include <termios.h>
#include <unistd.h>

#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>

#include "bench/cli/db_args.hpp"
#include "bench/cli/operator_option.hpp"
#include "bench/cli/registry.hpp"
#include "bench/io/json_util.hpp"
#include "db/console_accounts.hpp"
#include "db/users.hpp"

namespace calbench::cli::dbcmd {
namespace {
using nlohmann::json;

// The password of a console account: $CALBENCH_PASSWORD, else the first line of stdin (echo off on
// a terminal). Never an argument (argv is visible to every user of the machine).
std::string read_password(const char* var = "CALBENCH_PASSWORD", const std::string& prompt = "password for the console account") {
  if (const char* p = std::getenv(var); p && *p) return p;
  const bool tty = ::isatty(STDIN_FILENO);
  termios old{};
  if (tty) {
    std::cerr << prompt << ": " << std::flush;
    ::tcgetattr(STDIN_FILENO, &old);
    termios quiet = old;
    quiet.c_lflag &= ~static_cast<tcflag_t>(ECHO);
    ::tcsetattr(STDIN_FILENO, TCSANOW, &quiet);
  }
  std::string pw;
  std::getline(std::cin, pw);
  if (tty) {
    ::tcsetattr(STDIN_FILENO, TCSANOW, &old);
    std::cerr << "\n";
  }
  if (!pw.empty() && pw.back() == '\r') pw.pop_back();
  return pw;
}

void cmd_user_add(const DbArgs& a) {
  const bool sqlite = !db::is_postgres_uri(db_path(a));
  if (!(sqlite && a.role == "admin")) db::group_of_role(a.role);  // bad input before the server is asked
  if (sqlite) {  // SQLite: a console account with a password
    auto s = open_store(a);
    db::AccountAuthority by;
    if (!a.admin.empty()) {
      by.admin_login = a.admin;
      by.admin_password = read_password("CALBENCH_ADMIN_PASSWORD", "password of admin account " + a.admin);
    } else if (const char* cur = std::getenv("CALBENCH_CURRENT_PASSWORD"); cur && *cur) {
      by.current_password = cur;
    }
    const std::string said = db::add_console_account(*s, a.login, a.name, a.role, read_password(), by);
    std::cout << "console account " << a.login << " = " << a.name << " (" << a.role << "): " << said << "\n";
    return;
  }
  auto s = open_store(a);
  const std::string said = db::add_user(*s, a.login, a.name, a.role);
  std::cout << "login " << a.login << " = " << a.name << " (" << a.role << ", member of " << db::group_of_role(a.role)
            << "): " << said << "\n";
}

void cmd_user_list(const DbArgs& a) {
  auto s = open_store(a);
  if (!db::is_postgres_uri(db_path(a))) {
    const auto list = db::console_accounts(*s);
    if (a.json) {
      json arr = json::array();
      for (const auto& u : list)
        arr.push_back({{"login", u.login}, {"name", u.name}, {"role", u.role}, {"added_at", u.added_at}, {"added_by", u.added_by}});
      print_json(json{{"accounts", arr}}.dump(2));
      return;
    }
    for (const auto& u : list)
      std::cout << std::left << std::setw(16) << u.login << std::setw(14) << u.role << u.name << "  (by " << u.added_by
                << " at " << u.added_at << ")\n";
    std::cout << list.size() << " console account(s)\n";
    return;
  }
  const auto list = db::users(*s);
  if (a.json) {
    json arr = json::array();
    for (const auto& u : list)
      arr.push_back({{"login", u.login}, {"name", u.name}, {"role", u.role}, {"added_at", u.added_at}, {"added_by", u.added_by}});
    print_json(json{{"users", arr}}.dump(2));
    return;
  }
  for (const auto& u : list)
    std::cout << std::left << std::setw(16) << u.login << std::setw(14) << u.role << u.name << "  (by " << u.added_by
              << " at " << u.added_at << ")\n";
  std::cout << list.size() << " login(s) mapped to a person\n";
}
}  // namespace

void add_user_commands(CLI::App* db, const std::shared_ptr<DbArgs>& a) {
  auto* user = db->add_subcommand("user", "PostgreSQL: who each login is (the person who signs with it); SQLite: the web "
                                          "console's accounts");
  user->require_subcommand(1);
  const auto db_opt = [&](CLI::App* sub) {
    sub->add_option("--db", a->db, "a SQLite store FILE (console accounts) or the central store postgresql://USER@HOST[:PORT]/DB (default: $CALBENCH_DB)");
  };
  auto* add = user->add_subcommand("add", "SQLite: add or change a console account (password from $CALBENCH_PASSWORD or standard input, kept as an argon2id hash); PostgreSQL: map a login to a person and a role (grants the role's group if needed); audited");
  db_opt(add);
  add->add_option("LOGIN", a->login, "SQLite: the console account's login; PostgreSQL: an existing login role (CREATE ROLE LOGIN LOGIN PASSWORD '...')")->required();
  add->add_option("--name", a->name, "the person's full name, as it will appear beside each signature")->required();
  add->add_option("--role", a->role, "qc | station | provisioning (member of calbench_qc, calbench_station, calbench_provisioning); "
                                     "SQLite also admin (manages the console accounts, signs nothing)")
      ->required()
      ->check(CLI::IsMember({"qc", "station", "provisioning", "admin"}));
  add->add_option("--admin", a->admin, "SQLite: the admin account that authorizes this change (its password from "
                                       "$CALBENCH_ADMIN_PASSWORD, else stdin); without it an existing account changes "
                                       "only its own password, given in $CALBENCH_CURRENT_PASSWORD");
  add_operator_option(add, a->op, "who you are, recorded in the audit log (default: $CALBENCH_OPERATOR, else the OS user)");
  add->footer("SQLite store: adds (or changes) a console account for `calbench serve`; the password is read from\n"
              "$CALBENCH_PASSWORD, else from the first line of stdin (prompted, echo off, on a terminal), never from\n"
              "the command line; 8 to 1024 characters; kept only as an argon2id hash. Changing an existing account\n"
              "needs its current password ($CALBENCH_CURRENT_PASSWORD; the password only) or an admin account\n"
              "(--admin LOGIN); once the store has an admin, adding an account needs one too (docs/database.md\n"
              "\"Threat model\").\n"
              "PostgreSQL: run as an administrator (the database owner, or a role that may grant the groups). Once mapped, the login's\n"
              "person signs: --operator may only name that person or the login, and four-eyes compares persons (two logins\n"
              "of one person are one person). A new role takes the login out of its other calbench groups.");
  add->callback([a] { cmd_user_add(*a); });
  auto* list = user->add_subcommand("list", "the logins mapped to people");
  db_opt(list);
  list->add_flag("--json", a->json, "machine-readable output");
  list->callback([a] { cmd_user_list(*a); });
}

}  // namespace calbench::cli::dbcmd
