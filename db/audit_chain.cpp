#include "db/audit_chain.hpp"

#include <sodium.h>

#include <stdexcept>

namespace calbench::db {
namespace {

const char* kRowColumns =
    "SELECT id, at, \"user\", station, db_role, entity, entity_id, device_id, action, detail, chain FROM audit_log ";

AuditRowFields read_row(Statement& st) {
  AuditRowFields r;
  r.id = st.int64(0);
  r.at = st.text(1), r.user = st.text(2), r.station = st.text(3), r.db_role = st.text(4), r.entity = st.text(5);
  r.entity_id = st.int64(6);
  r.device_id = st.opt_int64(7);
  r.action = st.text(8), r.detail = st.text(9);
  return r;
}

}  // namespace

std::string audit_chain_link(const std::string& prev, const AuditRowFields& row) {
  static const bool ok = sodium_init() >= 0;
  if (!ok) throw std::runtime_error("libsodium could not be initialised");
  // Fields separated by the unit separator, which check_text refuses inside them.
  std::string m = "calbench-audit-v1\x1f" + prev;
  for (const std::string* f : {&row.at, &row.user, &row.station, &row.db_role, &row.entity, &row.action, &row.detail})
    m += "\x1f" + *f;
  m += "\x1f" + std::to_string(row.id) + "\x1f" + std::to_string(row.entity_id) + "\x1f" +
       (row.device_id ? std::to_string(*row.device_id) : std::string("-"));
  unsigned char h[crypto_hash_sha256_BYTES];
  crypto_hash_sha256(h, reinterpret_cast<const unsigned char*>(m.data()), m.size());
  char hex[2 * crypto_hash_sha256_BYTES + 1];
  sodium_bin2hex(hex, sizeof hex, h, sizeof h);
  return hex;
}

namespace {
// Checks the row `st` is on against `prev` (the chain value of the row before it); returns its own.
std::string check_link(const std::string& prev, Statement& st, ChainCheck& out) {
  ++out.rows;
  const AuditRowFields r = read_row(st);
  if (st.is_null(10)) out.breaks.push_back({r.id, "no chain value (written outside calbench)"});
  else if (st.text(10) != audit_chain_link(prev, r))
    out.breaks.push_back({r.id, "its chain value does not match its contents and the row before it (edited, "
                                "inserted or a row before it removed outside calbench)"});
  return st.is_null(10) ? std::string() : st.text(10);
}

// The rows `st` selects (in id order), each against the row just before it in the whole log.
void check_selected(Connection& c, Statement& st, ChainCheck& out) {
  auto before = c.prepare("SELECT chain FROM audit_log WHERE id < ? ORDER BY id DESC LIMIT 1");
  while (st.step()) {
    before.reset();
    before.bind(1, st.int64(0));
    check_link(before.step() && !before.is_null(0) ? before.text(0) : std::string(), st, out);
  }
}
}  // namespace

ChainCheck check_audit_chain(Store& store, std::optional<std::int64_t> device) {
  ChainCheck out;
  Connection& c = store.connection();
  if (c.dialect() == Dialect::postgres) {
    out.applies = false;
    return out;
  }
  if (!device) {
    auto st = c.prepare(std::string(kRowColumns) + "ORDER BY id");
    while (st.step()) out.head = check_link(out.head, st, out);
    return out;
  }
  auto st = c.prepare(std::string(kRowColumns) +
                      "WHERE device_id = ? OR (entity = 'coefficient_set' AND entity_id IN "
                      "(SELECT id FROM coefficient_sets WHERE device_id = ?)) ORDER BY id");
  st.bind(1, *device).bind(2, *device);
  check_selected(c, st, out);
  return out;
}

ChainCheck check_audit_row(Store& store, std::int64_t id) {
  ChainCheck out;
  Connection& c = store.connection();
  if (c.dialect() == Dialect::postgres) {
    out.applies = false;
    return out;
  }
  auto st = c.prepare(std::string(kRowColumns) + "WHERE id = ?");
  st.bind(1, id);
  check_selected(c, st, out);
  return out;
}

void seal_audit_chain_locked(Connection& c) {
  auto last = c.prepare("SELECT chain FROM audit_log WHERE chain IS NOT NULL ORDER BY id DESC LIMIT 1");
  std::string prev = last.step() ? last.text(0) : std::string();
  auto st = c.prepare(std::string(kRowColumns) + "WHERE chain IS NULL ORDER BY id");
  std::vector<std::pair<std::int64_t, std::string>> links;
  while (st.step()) {
    prev = audit_chain_link(prev, read_row(st));
    links.emplace_back(st.int64(0), prev);
  }
  auto up = c.prepare("UPDATE audit_log SET chain = ? WHERE id = ?");
  for (const auto& [id, link] : links) {
    up.reset();
    up.bind(1, link).bind(2, id).run();
  }
}

}  // namespace calbench::db
