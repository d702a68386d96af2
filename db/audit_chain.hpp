// Tamper evidence of the SQLite store's audit log (issue 54 item 4): a hash chain over its rows.
// Each row's `chain` is SHA-256 over the previous row's chain and every field of the row (id, time,
// user, station, db_role, entity, entity id, device, action, detail), written by calbench in the
// transaction that writes the row. A row inserted, edited or deleted outside calbench (sqlite3 on
// the file) breaks the chain at that row: `calbench db verify`, the device report and provisioning
// check it. What this cannot do: stop a person who writes the file and recomputes the chain after
// a forged row (the algorithm is public and there is no secret on a one-file store): the chain's
// head, printed by `db verify`, recorded elsewhere, shows that too. PostgreSQL needs no chain: its
// audit rows are written only by the server's functions (docs/database.md "Threat model").
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "db/store.hpp"

namespace calbench::db {

struct AuditRowFields {
  std::int64_t id = 0;
  std::string at, user, station, db_role, entity;
  std::int64_t entity_id = 0;
  std::optional<std::int64_t> device_id;
  std::string action, detail;
};
// The chain value of `row` after `prev` ("" before the first row), 64 hex digits.
std::string audit_chain_link(const std::string& prev, const AuditRowFields& row);

struct ChainBreak {
  std::int64_t id = 0;  // the audit row whose link does not hold
  std::string why;      // e.g. "no chain value (inserted outside calbench)"
};
struct ChainCheck {
  bool applies = true;   // false on PostgreSQL (no chain there)
  std::int64_t rows = 0;  // rows checked
  std::string head;       // the last row's chain value (the whole log only)
  std::vector<ChainBreak> breaks;
  bool ok() const { return breaks.empty(); }
};
// The whole log, or (device given) the rows of that device and the row before each: enough to
// show a row of the device forged, edited, or a row before it removed.
ChainCheck check_audit_chain(Store& store, std::optional<std::int64_t> device = std::nullopt);
// One row against the row before it (a signed approval's, say).
ChainCheck check_audit_row(Store& store, std::int64_t id);
// Writes the chain of every row that has none, in id order (schema 9's migration of an older store;
// those rows are vouched for as they were at the migration). Inside the caller's transaction.
void seal_audit_chain_locked(Connection& c);

}  // namespace calbench::db
