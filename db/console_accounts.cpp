#include "db/console_accounts.hpp"

#include <sodium.h>

#include <stdexcept>

#include "db/input_errors.hpp"
#include "db/signer.hpp"
#include "db/users.hpp"

namespace calbench::db {
namespace {

void need_sodium() {
  static const bool ok = sodium_init() >= 0;
  if (!ok) throw std::runtime_error("libsodium could not be initialised");
}

std::string hash_password(const std::string& password) {
  need_sodium();
  char out[crypto_pwhash_STRBYTES];
  if (crypto_pwhash_str_alg(out, password.data(), password.size(), crypto_pwhash_OPSLIMIT_INTERACTIVE,
                            crypto_pwhash_MEMLIMIT_INTERACTIVE, crypto_pwhash_ALG_ARGON2ID13) != 0)
    throw std::runtime_error("out of memory hashing a password (argon2id needs 64 MiB)");
  return out;
}

bool verify_password(const std::string& hash, const std::string& password) {
  need_sodium();
  return crypto_pwhash_str_verify(hash.c_str(), password.data(), password.size()) == 0;
}

void check_login(const std::string& login) {
  if (login.empty() || login.size() > 64) throw arg_error("LOGIN", "must be 1 to 64 characters");
  for (char c : login)
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-'))
      throw arg_error("LOGIN", "'" + login + "' may hold only letters, digits, '.', '_' and '-'");
}

}  // namespace

std::string console_password_problem(const std::string& password) {
  if (password.size() < 8) return "shorter than 8 characters";
  if (password.size() > 1024) return "longer than 1024 characters";
  for (unsigned char c : password)
    if (c < 0x20 || c == 0x7f) return "contains control characters";
  return {};
}

std::string account_fingerprint(const std::string& name, const std::string& role, const std::string& hash) {
  need_sodium();
  const std::string m = "calbench-account-v1\x1f" + name + "\x1f" + role + "\x1f" + hash;
  unsigned char h[crypto_hash_sha256_BYTES];
  crypto_hash_sha256(h, reinterpret_cast<const unsigned char*>(m.data()), m.size());
  char hex[2 * crypto_hash_sha256_BYTES + 1];
  sodium_bin2hex(hex, sizeof hex, h, sizeof h);
  return std::string(hex).substr(0, 32);
}

bool has_admin_account(Store& store) {
  auto st = store.connection().prepare("SELECT 1 FROM console_accounts WHERE role = 'admin' LIMIT 1");
  return st.step();
}

namespace {
PermissionError refused(Store& store, const std::string& why) {
  return PermissionError(0, store.connection().path() + ": refused: " + why + "; nothing was changed", "42501");
}

// Who authorizes this change, for the audit row; PermissionError when nobody does.
std::string authorize(Store& store, const std::optional<ConsoleAccount>& before, const std::string& name,
                      const std::string& role, const AccountAuthority& by) {
  if (!by.admin_login.empty()) {
    const auto a = check_console_password(store, by.admin_login, by.admin_password);
    const bool bootstrap_admin = !before && role == "admin" && !has_admin_account(store);
    if (!a || !(a->role == "admin" || (bootstrap_admin && a->role == "qc")))
      throw refused(store, "--admin " + by.admin_login + ": wrong password, or not an admin account" +
                               std::string(bootstrap_admin ? " (or, before the first admin, a qc account)" : ""));
    return "authorized by " + std::string(a->role == "admin" ? "admin " : "qc account ") + a->login;
  }
  if (before) {
    if (by.current_password.empty() || !check_console_password(store, before->login, by.current_password))
      throw refused(store, "account '" + before->login + "' exists: changing it needs its current password "
                           "($CALBENCH_CURRENT_PASSWORD) or an admin account (--admin LOGIN, $CALBENCH_ADMIN_PASSWORD)");
    if (!same_person(before->name, name) || before->role != role)
      throw refused(store, "with its own password an account changes its password only; a new name or role needs an "
                           "admin account (--admin LOGIN)");
    return "authorized by its own password";
  }
  if (has_admin_account(store))
    throw refused(store, "this store has an admin account: adding '" + name +
                         "' needs one (--admin LOGIN, password in $CALBENCH_ADMIN_PASSWORD)");
  if (role == "admin" && !console_accounts(store).empty())
    throw refused(store, "the first admin of a store that has accounts is appointed with a qc account's password "
                         "(--admin QC_LOGIN, $CALBENCH_ADMIN_PASSWORD)");
  return "no admin account on this store: anyone who can write the file may add accounts until one is appointed";
}
}  // namespace

std::string add_console_account(Store& store, const std::string& login, const std::string& name,
                                const std::string& role, const std::string& password, const AccountAuthority& by) {
  if (role != "admin") group_of_role(role);  // qc | station | provisioning | admin, else bad input naming --role
  check_login(login);
  check_operator_name(name, "--name");  // the name signs as an operator name does
  if (const std::string p = console_password_problem(password); !p.empty()) throw arg_error("password", p);
  Connection& c = store.connection();
  if (c.dialect() == Dialect::postgres)
    throw arg_error("--db", "console accounts are for a SQLite store; on PostgreSQL the console logs in with the "
                            "database's logins (db user add maps them to people)");
  const std::string who = authorize(store, find_console_account(store, login), name, role, by);
  const std::string hash = hash_password(password);  // outside the transaction: it takes a while
  std::string said;
  c.write_transaction([&] {
    const auto before = find_console_account(store, login);
    if (before) {
      said = "changed: " + before->name + " (" + before->role + ") -> " + name + " (" + role + "), password set";
      auto up = c.prepare(std::string("UPDATE console_accounts SET name = ?, role = ?, password_hash = ?, added_at = ") +
                          c.now_sql() + ", added_by = ? WHERE login = ?");
      up.bind(1, name).bind(2, role).bind(3, hash).bind(4, store.actor().user).bind(5, login).run();
    } else {
      said = "added";
      auto ins = c.prepare(std::string("INSERT INTO console_accounts(login, name, role, password_hash, added_at, added_by) "
                                       "VALUES (?, ?, ?, ?, ") + c.now_sql() + ", ?)");
      ins.bind(1, login).bind(2, name).bind(3, role).bind(4, hash).bind(5, store.actor().user).run();
    }
    store.audit_locked("account", 0, "map", login + " = " + name + " (" + role + ", console account): " + said + "; " +
                                                who + "; fingerprint " + account_fingerprint(name, role, hash));
  });
  return said + " (" + who + ")";
}

std::vector<AccountCheck> check_console_accounts(Store& store) {
  std::vector<AccountCheck> out;
  if (store.connection().dialect() == Dialect::postgres) return out;
  auto last = store.connection().prepare("SELECT detail FROM audit_log WHERE entity = 'account' AND action = 'map' AND "
                                         "detail LIKE ? ESCAPE '\\' ORDER BY id DESC LIMIT 1");
  for (const auto& a : console_accounts(store)) {
    const auto full = find_console_account(store, a.login);
    std::string pattern;
    for (char ch : a.login + " = ") {
      if (ch == '%' || ch == '_' || ch == '\\') pattern += '\\';
      pattern += ch;
    }
    last.reset();
    last.bind(1, pattern + "%");
    const std::string fp = account_fingerprint(full->name, full->role, full->credential);
    if (!last.step()) out.push_back({a.login, "no audit row added it (written outside calbench)"});
    else if (last.text(0).find("fingerprint ") == std::string::npos)
      continue;  // added before schema 9: nothing to compare
    else if (last.text(0).find("fingerprint " + fp) == std::string::npos)
      out.push_back({a.login, "its name, role or password hash is not the one its last audit row records (changed "
                              "outside calbench)"});
  }
  return out;
}

std::vector<ConsoleAccount> console_accounts(Store& store) {
  std::vector<ConsoleAccount> out;
  auto st = store.connection().prepare("SELECT login, name, role, added_at, added_by FROM console_accounts ORDER BY login");
  while (st.step()) out.push_back(ConsoleAccount{st.text(0), st.text(1), st.text(2), st.text(3), st.text(4), {}});
  return out;
}

std::optional<ConsoleAccount> check_console_password(Store& store, const std::string& login, const std::string& password) {
  // A hash of a random password, checked when the login is unknown: the same work either way.
  static const std::string decoy = [] {
    need_sodium();
    unsigned char r[16];
    randombytes_buf(r, sizeof r);
    return hash_password(std::string(reinterpret_cast<const char*>(r), sizeof r));
  }();
  auto st = store.connection().prepare(
      "SELECT login, name, role, added_at, added_by, password_hash FROM console_accounts WHERE login = ?");
  st.bind(1, login);
  if (!st.step()) {
    verify_password(decoy, password);
    return std::nullopt;
  }
  ConsoleAccount a{st.text(0), st.text(1), st.text(2), st.text(3), st.text(4), st.text(5)};
  if (!verify_password(a.credential, password)) return std::nullopt;
  return a;
}

std::optional<ConsoleAccount> find_console_account(Store& store, const std::string& login) {
  auto st = store.connection().prepare(
      "SELECT login, name, role, added_at, added_by, password_hash FROM console_accounts WHERE login = ?");
  st.bind(1, login);
  if (!st.step()) return std::nullopt;
  return ConsoleAccount{st.text(0), st.text(1), st.text(2), st.text(3), st.text(4), st.text(5)};
}

}  // namespace calbench::db
