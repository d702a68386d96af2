// Who signs (issue 35): an approval, a revocation, a setting change or a provisioning is signed by a
// person. On PostgreSQL the person is the authenticated login's (table calbench_users, filled by
// `calbench db user add`): --operator may only name that person (or the login itself) and four-eyes
// compares logins. On SQLite (one station, no authentication) the typed name signs, the OS user is
// recorded beside it, and names are compared ignoring case and runs of whitespace.
#pragma once
#include <string>

#include "db/store.hpp"

namespace calbench::db {

// `name` lower-cased (ASCII), trimmed, with every run of whitespace, Unicode spaces (U+00A0 ...)
// included, made one space. Invisible characters and mixed-script words are refused before
// (operator_name_problem, db/store.cpp), so look-alike names compare equal or are refused.
std::string normalized_name(const std::string& name);
bool same_person(const std::string& a, const std::string& b);

// Whether `set` was stored by the person who signs on `store` now (four-eyes is between persons,
// not logins): the set's creator (its own field) is the signer's person, or (PostgreSQL) the same
// login stored it, or the login that stored it is mapped to the signer's person; on SQLite a
// console account's login counts as its person's name. PostgreSQL checks the same again in
// calbench_approve. The check that the signer is the login's person is Store::check_signer.
bool stored_by_signer(Store& store, const CoefficientSetRecord& set);
// The person who stored a set: its creator field (schema 9), else (older rows) the name before
// the first '@' of created_by "NAME@STATION".
std::string creator_name(const CoefficientSetRecord& set);
// PostgreSQL: the person a login is mapped to (calbench_users), "" when none; "" on SQLite.
std::string person_of_login(Store& store, const std::string& login);

// How a signature was made, for history and reports: "login anna" (PostgreSQL) or
// "OS user tess, not authenticated (SQLite)"; "" when the login was not recorded (before schema 6).
// A login "console:anna" is the web console's local account anna on a SQLite store.
inline constexpr const char* kConsoleLoginPrefix = "console:";
std::string signature_note(const std::string& login, bool authenticated);

}  // namespace calbench::db
