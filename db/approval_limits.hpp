// The coefficient limits the central store itself holds every approval to (PostgreSQL, schema 9,
// table approval_limits, checked by calbench_db_verdict): per device class, |bias|, |scale| and
// |skew| of each triad, written by the database's owner at `calbench db init`. A QC login that
// calls calbench_approve in psql cannot approve a set beyond them, whatever thresholds file it
// claims. SQLite has no such table (the client's verdict is the only one there).
#pragma once
#include <string>

#include "db/approval.hpp"

namespace calbench::db {

// Writes (or replaces) the limits of `model` (its normalized name, or "*" for any model without
// its own row) from `t`'s coefficient limits. The owner only (the database refuses others).
void publish_approval_limits(Store& store, const std::string& model, const Thresholds& t, const std::string& source);

}  // namespace calbench::db
