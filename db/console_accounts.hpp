// The web console's local accounts on a SQLite store (issue 38; table console_accounts, schema 7):
// `calbench db user add LOGIN --name … --role qc|station|provisioning` on a SQLite file. A password
// is kept only as an argon2id hash (libsodium crypto_pwhash_str, memory-hard: 64 MiB and 2 passes,
// libsodium's "interactive" limits). PostgreSQL needs none: there the console logs in with the
// database's own logins (db/users.hpp maps them to people).
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "db/store.hpp"

namespace calbench::db {

struct ConsoleAccount {
  std::string login, name, role, added_at, added_by;
  // The account's stored password hash (never shown): a session remembers the one it logged in
  // with, and ends when it changed (a new password) — see find_console_account.
  std::string credential;
};

// What is wrong with a password (8 to 1024 bytes, no control characters), or "".
std::string console_password_problem(const std::string& password);
// Adds the account, or changes the name, role and password of an existing one (audited as entity
// "account", never with the password or its hash). Returns "added" or "changed: …". Bad login,
// name, role or password: InputError naming it. A PostgreSQL store is refused (it has logins).
std::string add_console_account(Store& store, const std::string& login, const std::string& name,
                                const std::string& role, const std::string& password);
std::vector<ConsoleAccount> console_accounts(Store& store);
// The account if `password` is its password, else nothing. An unknown login costs the same hash
// check as a known one (no timing difference tells which logins exist).
std::optional<ConsoleAccount> check_console_password(Store& store, const std::string& login, const std::string& password);

// The account as it is now (name, role, credential), or nothing when it is gone: the console checks
// every request against it, so a role or password change takes effect at once.
std::optional<ConsoleAccount> find_console_account(Store& store, const std::string& login);

}  // namespace calbench::db
