// Issue 54 item 4: the SQLite audit log's hash chain (db/audit_chain.hpp). Every row calbench
// writes links to the one before; a row inserted, edited or removed outside calbench breaks the
// chain at that row, and only there; a store of schema 8 is chained when migrated.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include "db/audit_chain.hpp"
#include "db/schema.hpp"
#include "db_test_util.hpp"

namespace calbench::db {
namespace {
using test::TempDir;

void exec(const std::string& file, const char* sql) {
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(file.c_str(), &raw), SQLITE_OK);
  char* err = nullptr;
  const int rc = sqlite3_exec(raw, sql, nullptr, nullptr, &err);
  const std::string msg = err ? err : "";
  sqlite3_free(err);
  sqlite3_close(raw);
  ASSERT_EQ(rc, SQLITE_OK) << msg;
}

// A store with a few audited writes: a device and two sets.
void fill(Store& s) {
  const auto d = DeviceInfo{"ADIS16488A", "C1", ""};
  s.store_set(d, SetSource::bench, coefficients_json_text(d, test::random_errors(1)));
  s.store_set(d, SetSource::bench, coefficients_json_text(d, test::random_errors(2)));
}

TEST(AuditChain, EveryRowCalbenchWritesIsLinked) {
  TempDir t;
  Store s(t.db(), test::create_opts(), test::test_actor());
  fill(s);
  const ChainCheck c = check_audit_chain(s);
  EXPECT_TRUE(c.applies);
  EXPECT_EQ(c.rows, 4);  // the migration, the device, two sets
  EXPECT_TRUE(c.ok());
  EXPECT_EQ(c.head.size(), 64u);
  // The link is the function of its row and the one before: any field changes it.
  AuditRowFields r{1, "2026-01-01T00:00:00.000Z", "u", "st", "db", "coefficient_set", 1, 1, "status", "x"};
  const std::string a = audit_chain_link("", r);
  r.detail = "y";
  EXPECT_NE(audit_chain_link("", r), a);
  r.detail = "x";
  EXPECT_NE(audit_chain_link("00", r), a);
  r.device_id.reset();
  EXPECT_NE(audit_chain_link("", r), a);
}

TEST(AuditChain, AForgedEditedOrRemovedRowBreaksTheChainThere) {
  TempDir t;
  {
    Store s(t.db(), test::create_opts(), test::test_actor());
    fill(s);
  }
  // Inserted by hand (no chain value, then a made-up one); calbench's next row still links.
  exec(t.db(), "INSERT INTO audit_log(at, user, station, entity, entity_id, device_id, action, detail, db_role) "
               "VALUES ('t', 'Bob', 'x', 'coefficient_set', 1, 1, 'status', 'draft -> approved', 'bob')");
  exec(t.db(), "INSERT INTO audit_log(at, user, station, entity, entity_id, device_id, action, detail, db_role, chain) "
               "VALUES ('t', 'Bob', 'x', 'coefficient_set', 1, 1, 'status', 'draft -> approved', 'bob', 'ab')");
  Store s(t.db(), {}, test::test_actor());
  const auto d = DeviceInfo{"ADIS16488A", "C1", ""};
  s.store_set(d, SetSource::bench, coefficients_json_text(d, test::random_errors(3)));
  ChainCheck c = check_audit_chain(s);
  ASSERT_EQ(c.breaks.size(), 2u);
  const std::int64_t forged = c.breaks[0].id;
  EXPECT_NE(c.breaks[0].why.find("no chain value"), std::string::npos);
  EXPECT_EQ(c.breaks[1].id, forged + 1);
  // The device's own view finds the same rows.
  EXPECT_EQ(check_audit_chain(s, 1).breaks.size(), 2u);
  // An edit of a calbench row (the append-only trigger dropped first, as one who writes the file can).
  exec(t.db(), "DROP TRIGGER audit_log_no_update; UPDATE audit_log SET detail = 'edited' WHERE id = 2");
  c = check_audit_chain(s);
  ASSERT_EQ(c.breaks.size(), 3u);
  EXPECT_EQ(c.breaks[0].id, 2);
  // A removed row: the row after it no longer links.
  exec(t.db(), "DROP TRIGGER audit_log_no_delete; DELETE FROM audit_log WHERE id = 4");
  c = check_audit_chain(s);
  bool five = false;
  for (const auto& b : c.breaks) five = five || b.id == 5;
  EXPECT_TRUE(five);
}

TEST(AuditChain, AStoreOfSchema8IsChainedWhenMigrated) {
  TempDir t;
  {
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(t.db().c_str(), &raw), SQLITE_OK);
    for (int i = 0; i < 8; ++i) ASSERT_EQ(sqlite3_exec(raw, migrations()[i], nullptr, nullptr, nullptr), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(raw,
                           "INSERT INTO devices VALUES (1, 'ADIS16488A', 'OLD1', '', 'c');"
                           "INSERT INTO coefficient_sets(id, device_id, version, source, payload_json, created_at, created_by) "
                           "VALUES (1, 1, 1, 'bench', '{}', 'c', 'Old Name@line@3');"
                           "INSERT INTO audit_log(at, user, station, entity, entity_id, device_id, action) "
                           "VALUES ('c', 'old', 'x', 'coefficient_set', 1, 1, 'create');"
                           "PRAGMA user_version = 8;",
                           nullptr, nullptr, nullptr),
              SQLITE_OK);
    sqlite3_close(raw);
  }
  Store s(t.db(), {}, test::test_actor());
  EXPECT_EQ(s.schema_version(), kSchemaVersion);
  const ChainCheck c = check_audit_chain(s);
  EXPECT_TRUE(c.ok());
  EXPECT_EQ(c.rows, 2);  // the old row and the migration's
  // The creator of an older set: the name before the first '@' (never the station's part).
  EXPECT_EQ(s.get_set(1).creator, "Old Name");
  // The approval rule holds after the migration: no status change without its signed row.
  EXPECT_THROW(s.connection().exec("UPDATE coefficient_sets SET status = 'approved' WHERE id = 1"), DbError);
}

}  // namespace
}  // namespace calbench::db
