// The people behind PostgreSQL logins (issue 35): `calbench db user add LOGIN --name … --role …`
// maps a login to the person who signs with it (db/signer.hpp) and makes the login a member of the
// matching group role (db/postgres/roles.sql). Run by an administrator (a role that may grant the
// groups, e.g. the database owner). SQLite has no logins: refused.
#pragma once
#include <string>
#include <vector>

#include "db/store.hpp"

namespace calbench::db {

struct User {
  std::string login, name, role, added_at, added_by;
};

// "qc" → "calbench_qc", "station" → "calbench_station", "provisioning" → "calbench_provisioning";
// anything else is bad input naming --role.
std::string group_of_role(const std::string& role);
// Maps `login` (an existing login role) to `name` as `role`, granting the group if the login is
// not a member yet; a second call for the same login changes the name or role (audited, before ->
// after). Returns what changed, for the user ("added", "changed: …", "unchanged").
std::string add_user(Store& store, const std::string& login, const std::string& name, const std::string& role);
std::vector<User> users(Store& store);

}  // namespace calbench::db
