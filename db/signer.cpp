#include "db/signer.hpp"

#include <cctype>

#include "common/utf8.hpp"
#include "db/input_errors.hpp"

namespace calbench::db {

std::string normalized_name(const std::string& name) {
  std::string out;
  bool space = false;
  for (std::size_t i = 0; i < name.size();) {
    unsigned cp = 0;
    std::size_t len = utf8::decode(name, i, cp);
    if (len == 0) len = 1, cp = static_cast<unsigned char>(name[i]);  // kept as it is (refused as a name anyway)
    if ((cp < 0x80 && std::isspace(static_cast<int>(cp))) || utf8::space_like(cp)) {  // NBSP and the like are spaces
      space = !out.empty();
    } else {
      if (space) out += ' ';
      space = false;
      if (cp < 0x80) out += static_cast<char>(std::tolower(static_cast<int>(cp)));
      else out.append(name, i, len);
    }
    i += len;
  }
  return out;
}

bool same_person(const std::string& a, const std::string& b) { return normalized_name(a) == normalized_name(b); }

std::string creator_name(const CoefficientSetRecord& set) {
  if (!set.creator.empty()) return set.creator;
  // A set read from a store before schema 9 (or a journal row): the name before the FIRST '@' —
  // an operator name never holds one, a station name may.
  return set.created_by.substr(0, set.created_by.find('@'));
}

std::string person_of_login(Store& store, const std::string& login) {
  if (!store.authenticated() || login.empty()) return {};
  auto st = store.connection().prepare("SELECT name FROM calbench_users WHERE login = ?");
  st.bind(1, login);
  return st.step() ? st.text(0) : std::string();
}

bool stored_by_signer(Store& store, const CoefficientSetRecord& set) {
  const std::string signer = store.actor().user;
  if (same_person(creator_name(set), signer)) return true;  // the typed (or signed-in) person
  if (store.authenticated()) {
    // PostgreSQL: the same login, or two logins of one person (anna_st stores, anna approves).
    if (set.created_by_login == store.login()) return true;
    const std::string maker = person_of_login(store, set.created_by_login);
    return !maker.empty() && same_person(maker, signer);
  }
  // SQLite: a console account is its person under two names, the account's login and the person's
  // name: a set stored as either was stored by the one signing now (typed or signed in).
  const std::string login = store.login();
  if (login.rfind(kConsoleLoginPrefix, 0) == 0 &&
      same_person(creator_name(set), login.substr(std::string(kConsoleLoginPrefix).size())))
    return true;
  auto acct = store.connection().prepare("SELECT name FROM console_accounts WHERE login = ? OR login = ?");
  acct.bind(1, creator_name(set)).bind(2, signer);
  while (acct.step())
    if (same_person(acct.text(0), signer) || same_person(acct.text(0), creator_name(set))) return true;
  return false;
}

std::string signature_note(const std::string& login, bool authenticated) {
  if (login.empty()) return {};
  if (login.rfind(kConsoleLoginPrefix, 0) == 0)
    return "console account " + login.substr(std::string(kConsoleLoginPrefix).size()) +
           ", password checked by calbench serve (SQLite)";
  return authenticated ? "login " + login : "OS user " + login + ", not authenticated (SQLite)";
}

void Store::check_signer(const char* role) {
  if (conn_->dialect() != Dialect::postgres) {  // SQLite: the typed name, the OS user beside it
    if (!console_login_.empty() && console_role_ != role)  // a console account signs only as its role
      throw PermissionError(0, conn_->path() + ": refused to console account '" + console_login_ + "' (role " +
                                   console_role_ + "): only a " + role + " account may sign this (as only a login in calbench_" +
                                   role + " may on PostgreSQL)",
                            "42501");
    return;
  }
  const std::string who = login();
  auto st = conn_->prepare("SELECT name FROM calbench_users WHERE login = ?");
  st.bind(1, who);
  if (!st.step()) {
    // A login that may not sign at all (a station's) is told so by the database's rules first.
    // (Schema 9: nobody updates a status directly; the group that signs is what the server checks.)
    auto pr = conn_->prepare("SELECT CASE WHEN EXISTS (SELECT 1 FROM pg_roles WHERE rolname = ?) "
                             "THEN pg_has_role(session_user, ?::name, 'MEMBER') ELSE false END");
    pr.bind(1, std::string("calbench_") + role).bind(2, std::string("calbench_") + role);
    pr.step();
    if (pr.int64(0) == 0)
      throw PermissionError(0, conn_->path() + ": the database refused this to role '" + who +
                                   "': permission denied for table coefficient_sets (this login may not sign: a "
                                   "login in calbench_qc approves, revokes and changes settings, one in "
                                   "calbench_provisioning provisions)",
                            "42501");
    throw arg_error("login", "login '" + who + "' (" + conn_->path() +
                                 ") is not mapped to a person, and a signature names one: an administrator runs "
                                 "`calbench db user add " + who +
                                 " --name \"FULL NAME\" --role qc|station|provisioning --db postgresql://ADMIN@HOST/DB`");
  }
  const std::string name = st.text(0);
  if (actor_.named() && !same_person(actor_.user, name) && !same_person(actor_.user, who))
    throw arg_error(actor_.source, "'" + actor_.user + "' is not who is logged in: login '" + who + "' is " + name +
                                       "; type --operator \"" + name + "\" (or leave --operator out), or connect as "
                                       "your own login");
  actor_.user = name;
  actor_.source = "login " + who;
}

}  // namespace calbench::db
