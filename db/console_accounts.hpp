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
// Who authorizes a change of the accounts (issue 54 item 3): an admin account's login and
// password, or the changed account's own current password.
struct AccountAuthority {
  std::string admin_login, admin_password;  // --admin LOGIN, $CALBENCH_ADMIN_PASSWORD
  std::string current_password;             // $CALBENCH_CURRENT_PASSWORD: an account changing its own password
};
// Adds the account, or changes the name, role and password of an existing one (audited as entity
// "account" with a fingerprint of the stored row, never with the password or its hash). Returns
// "added" or "changed: …". Who may:
//  - an existing account changes with its own current password (the password only) or an admin's;
//  - a new account needs an admin's password once the store has an admin account ("admin" role:
//    manages accounts, signs nothing); before that anyone with the file may add one, except an
//    admin, which then needs a qc account's password (or the store has no account yet).
// Refusals are PermissionError; bad login, name, role or password: InputError naming it. A
// PostgreSQL store is refused (it has logins).
std::string add_console_account(Store& store, const std::string& login, const std::string& name,
                                const std::string& role, const std::string& password, const AccountAuthority& by = {});
// The fingerprint of an account row as stored (name, role, password hash), recorded in its audit
// row: `db verify` compares it with the row now, so an edit outside calbench shows.
std::string account_fingerprint(const std::string& name, const std::string& role, const std::string& hash);
struct AccountCheck {
  std::string login, why;  // why the row is not the one its last audit entry vouches for
};
std::vector<AccountCheck> check_console_accounts(Store& store);
bool has_admin_account(Store& store);
std::vector<ConsoleAccount> console_accounts(Store& store);
// The account if `password` is its password, else nothing. An unknown login costs the same hash
// check as a known one (no timing difference tells which logins exist).
std::optional<ConsoleAccount> check_console_password(Store& store, const std::string& login, const std::string& password);

// The account as it is now (name, role, credential), or nothing when it is gone: the console checks
// every request against it, so a role or password change takes effect at once.
std::optional<ConsoleAccount> find_console_account(Store& store, const std::string& login);

}  // namespace calbench::db
