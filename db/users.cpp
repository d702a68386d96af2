#include "db/users.hpp"

#include "db/input_errors.hpp"

namespace calbench::db {

namespace {
void need_postgres(Store& store) {
  if (store.connection().dialect() != Dialect::postgres)
    throw arg_error("--db", "database users are PostgreSQL logins; a SQLite file has none (its signatures are typed "
                            "names, recorded with the OS user): give --db postgresql://ADMIN@HOST/DB");
}
}  // namespace

std::string group_of_role(const std::string& role) {
  if (role == "qc" || role == "station" || role == "provisioning") return "calbench_" + role;
  throw arg_error("--role", "'" + role + "' is not one of qc, station, provisioning");
}

std::string add_user(Store& store, const std::string& login, const std::string& name, const std::string& role) {
  const std::string group = group_of_role(role);
  check_operator_name(name, "--name");  // a person's name signs as an operator name does
  check_text(login, "LOGIN", true);
  need_postgres(store);
  Connection& c = store.connection();
  {
    auto st = c.prepare("SELECT rolcanlogin FROM pg_roles WHERE rolname = ?");
    st.bind(1, login);
    if (!st.step())
      throw arg_error("LOGIN", "no role '" + login + "' on " + c.path() + ": create the login first, e.g. CREATE ROLE " +
                                   login + " LOGIN PASSWORD '...' (docs/database.md), then run this again");
    if (st.int64(0) == 0)
      throw arg_error("LOGIN", "role '" + login + "' cannot log in (NOLOGIN): map a login role, not a group");
    auto g = c.prepare("SELECT 1 FROM pg_roles WHERE rolname = ?");
    g.bind(1, group);
    if (!g.step())
      throw arg_error("--role", "group role " + group + " does not exist on " + c.path() +
                                    ": the owner runs `calbench db init --roles --db URI` first");
  }
  std::string said;
  c.write_transaction([&] {
    auto member = c.prepare("SELECT pg_has_role(?::name, ?::name, 'MEMBER')");
    member.bind(1, login).bind(2, group);
    member.step();
    if (member.int64(0) == 0) {
      auto q = c.prepare("SELECT format('GRANT %I TO %I', ?::text, ?::text)");
      q.bind(1, group).bind(2, login);
      q.step();
      c.exec(q.text(0).c_str());
    }
    // A role change takes the old role's group away: the login's rights are the new role's, at once,
    // for its open sessions too (the server checks membership on every statement). Groups granted
    // by hand beside the mapping stay (a QC login that may also store, say).
    auto old_role = c.prepare("SELECT role FROM calbench_users WHERE login = ? AND role <> ?");
    old_role.bind(1, login).bind(2, role);
    if (old_role.step()) {
      auto q = c.prepare("SELECT format('REVOKE %I FROM %I', ?::text, ?::text)");
      q.bind(1, group_of_role(old_role.text(0))).bind(2, login);
      q.step();
      c.exec(q.text(0).c_str());
    }
    auto before = c.prepare("SELECT name, role FROM calbench_users WHERE login = ?");
    before.bind(1, login);
    if (before.step()) {
      const std::string was = before.text(0) + " (" + before.text(1) + ")";
      if (before.text(0) == name && before.text(1) == role) {
        said = "unchanged";
      } else {
        auto up = c.prepare("UPDATE calbench_users SET name = ?, role = ?, added_at = now(), added_by = session_user "
                            "WHERE login = ?");
        up.bind(1, name).bind(2, role).bind(3, login).run();
        said = "changed: " + was + " -> " + name + " (" + role + ")";
      }
    } else {
      auto ins = c.prepare("INSERT INTO calbench_users(login, name, role) VALUES (?, ?, ?)");
      ins.bind(1, login).bind(2, name).bind(3, role).run();
      said = "added";
    }
    if (said != "unchanged")
      store.audit_locked("user", 0, "map", login + " = " + name + " (" + role + ", member of " + group + "): " + said);
  });
  return said;
}

std::vector<User> users(Store& store) {
  need_postgres(store);
  std::vector<User> out;
  auto st = store.connection().prepare(
      "SELECT login, name, role, added_at, added_by FROM calbench_users ORDER BY login");
  while (st.step()) out.push_back(User{st.text(0), st.text(1), st.text(2), st.text(3), st.text(4)});
  return out;
}

}  // namespace calbench::db
