#include <gtest/gtest.h>
#include <sqlite3.h>

#include <nlohmann/json.hpp>

#include "common/input_error.hpp"
#include "db/approval.hpp"
#include "db/schema.hpp"
#include "db_test_util.hpp"

namespace calbench::db {
namespace {
using test::TempDir;

std::string pragma_text(Store& s, const char* sql) {
  auto st = s.connection().prepare(sql);
  EXPECT_TRUE(st.step());
  return st.text(0);
}

TEST(DbStore, CreatesSchemaWithWalForeignKeysAndVersion) {
  TempDir t;
  Store s(t.db(), test::create_opts(), test::test_actor());
  EXPECT_EQ(s.schema_version(), kSchemaVersion);
  EXPECT_EQ(pragma_text(s, "PRAGMA journal_mode"), "wal");
  EXPECT_EQ(pragma_text(s, "PRAGMA foreign_keys"), "1");
  // Reopening does not migrate again (one migrate entry in the audit log).
  { Store again(t.db(), {}, test::test_actor()); }
  EXPECT_EQ(s.count("audit_log"), 1);
}

// A database of schema 1 (before QC results recorded their sample and criterion) is migrated when
// opened read-write; its QC rows read back with both empty (not recorded). Read-only opens of it
// are refused with the advice to migrate.
TEST(DbStore, MigratesSchema1QcResults) {
  TempDir t;
  {
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(t.db().c_str(), &raw), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(raw, migrations()[0], nullptr, nullptr, nullptr), SQLITE_OK);
    const char* rows =
        "INSERT INTO devices VALUES (1, 'ADIS16488A', 'OLD1', '', '2026-01-01T00:00:00.000Z');"
        "INSERT INTO bench_runs(id, device_id, outcome, created_at) VALUES (1, 1, 'pass', '2026-01-01T00:00:00.000Z');"
        "INSERT INTO qc_results(bench_run_id, metric, value, threshold, pass, unit) VALUES (1, 'r', 1, 2, 1, 'm');"
        "PRAGMA user_version = 1;";
    ASSERT_EQ(sqlite3_exec(raw, rows, nullptr, nullptr, nullptr), SQLITE_OK);
    sqlite3_close(raw);
  }
  OpenOptions ro;
  ro.read_only = true;
  EXPECT_THROW(Store(t.db(), ro, test::test_actor()), DbError);
  Store s(t.db(), {}, test::test_actor());
  EXPECT_EQ(s.schema_version(), kSchemaVersion);
  const auto qc = s.qc_of_bench_run(1);
  ASSERT_EQ(qc.size(), 1u);
  EXPECT_EQ(qc[0].sample, "");
  EXPECT_EQ(qc[0].criterion, "");
  EXPECT_FALSE(qc[0].informative());  // it has a threshold
  EXPECT_THROW(s.connection().exec("UPDATE qc_results SET sample = 'half-sample'"), DbError);
}

// Issue 35: a store of schema 5 is migrated to 6 (the login beside each name; a recording's URI
// and digest). Old rows read with those empty; new ones carry them; the login of a set is immutable.
TEST(DbStore, MigratesSchema5ToLoginsAndRecordingLocations) {
  TempDir t;
  {
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(t.db().c_str(), &raw), SQLITE_OK);
    for (int i = 0; i < 5; ++i) ASSERT_EQ(sqlite3_exec(raw, migrations()[i], nullptr, nullptr, nullptr), SQLITE_OK);
    const char* rows =
        "INSERT INTO devices VALUES (1, 'ADIS16488A', 'OLD1', '', '2026-01-01T00:00:00.000Z');"
        "INSERT INTO bench_runs(id, device_id, outcome, created_at) VALUES (1, 1, 'pass', '2026-01-01T00:00:00.000Z');"
        "INSERT INTO coefficient_sets(id, device_id, version, source, bench_run_id, payload_json, created_at, created_by) "
        "VALUES (1, 1, 1, 'bench', 1, '{}', '2026-01-01T00:00:00.000Z', 'old@x');"
        "INSERT INTO audit_log(at, user, station, entity, entity_id, device_id, action) "
        "VALUES ('2026-01-01T00:00:00.000Z', 'old', 'x', 'coefficient_set', 1, 1, 'create');"
        "PRAGMA user_version = 5;";
    ASSERT_EQ(sqlite3_exec(raw, rows, nullptr, nullptr, nullptr), SQLITE_OK);
    sqlite3_close(raw);
  }
  Store s(t.db(), {}, Actor{"Nora", "line-2", "--operator", "noraos"});
  EXPECT_EQ(s.schema_version(), kSchemaVersion);
  EXPECT_EQ(s.get_set(1).created_by_login, "");
  EXPECT_EQ(s.bench_run(1)->recording_uri, "");
  const auto old = s.audit_of_device(1);
  ASSERT_FALSE(old.empty());
  EXPECT_EQ(old.front().login, "");
  BenchRunInput run = test::bench_run();
  run.recording_uri = "file://h/abs/rec";
  run.recording_digest = std::string(64, 'a');
  const auto st = s.store_bench({"ADIS16488A", "NEW1", ""}, run, test::payload("NEW1", test::random_errors(2)));
  EXPECT_EQ(s.get_set(st.set_id).created_by_login, "noraos");
  EXPECT_EQ(s.bench_run(st.run_id)->recording_uri, "file://h/abs/rec");
  EXPECT_EQ(s.bench_run(st.run_id)->recording_digest, std::string(64, 'a'));
  EXPECT_EQ(s.audit_of_device(st.device_id).back().login, "noraos");
  EXPECT_THROW(s.connection().exec("UPDATE coefficient_sets SET created_by_role = 'someone' WHERE id = 1"), DbError);
}

TEST(DbStore, RefusesMissingFileWithoutCreateAndNewerSchema) {
  TempDir t;
  EXPECT_THROW(Store(t.db(), {}, test::test_actor()), InputError);
  { Store s(t.db(), test::create_opts(), test::test_actor()); s.connection().exec("PRAGMA user_version = 99"); }
  try {
    Store s(t.db(), {}, test::test_actor());
    FAIL() << "newer schema accepted";
  } catch (const DbError& e) {
    EXPECT_NE(std::string(e.what()).find("newer"), std::string::npos) << e.what();
  }
}

TEST(DbStore, StoresBenchRunAndSetAtomicallyWithVersionsAndAudit) {
  TempDir t;
  Store s(t.db(), test::create_opts(), test::test_actor());
  const SensorErrors e = test::random_errors(7);
  const auto a = s.store_bench({"ADIS16488A", "A100", "1.10"}, test::bench_run(), test::payload("A100", e, R"({"temperature": {"k": [1, 2]}})"));
  const auto b = s.store_bench({"ADIS16488A", "A100", ""}, test::bench_run(), test::payload("A100", e));
  EXPECT_EQ(a.version, 1);
  EXPECT_EQ(b.version, 2);
  EXPECT_EQ(a.device_id, b.device_id);
  const auto set = s.get_set(a.set_id);
  EXPECT_EQ(set.status, SetStatus::draft);
  EXPECT_EQ(set.source, SetSource::bench);
  EXPECT_EQ(set.created_by, "tester@station-T");
  EXPECT_EQ(set.errors.gyro.bias, e.gyro.bias);
  EXPECT_EQ(set.errors.accel.M, e.accel.M);
  EXPECT_EQ(set.errors.gyro.sigma_M, e.gyro.sigma_M);
  // Extra model terms kept in the payload.
  const auto j = nlohmann::json::parse(set.payload_json);
  EXPECT_EQ(j["temperature"]["k"][1], 2);
  EXPECT_EQ(s.find_device("A100")->firmware, "1.10");
  EXPECT_EQ(s.qc_of_set(set).size(), 1u);
  EXPECT_EQ(s.bench_run(*set.bench_run_id)->station, "station-T");
  bool created = false;
  for (const auto& entry : s.audit_of_device(a.device_id)) {
    EXPECT_EQ(entry.user, "tester");
    EXPECT_EQ(entry.station, "station-T");
    created = created || (entry.entity == "coefficient_set" && entry.action == "create");
  }
  EXPECT_TRUE(created);
}

// A run that produced no set (aborted) is kept in the unit's history with why; no set is created.
TEST(DbStore, AbortedRunIsRecordedWithItsReasonAndNoSet) {
  TempDir t;
  Store s(t.db(), test::create_opts(), test::test_actor());
  BenchRunInput run = test::bench_run();
  run.outcome = "aborted";
  run.recording_path = "out/recording";
  EXPECT_THROW(s.store_bench_run({"ADIS16488A", "AB1", ""}, test::bench_run(), "x"), InputError);  // "pass" needs a set
  const auto id = s.store_bench_run({"ADIS16488A", "AB1", ""}, run, "table lost\nat step 3");
  EXPECT_EQ(s.bench_run(id)->outcome, "aborted");
  EXPECT_EQ(s.count("coefficient_sets"), 0);
  bool found = false;
  for (const auto& a : s.audit_of_device(s.find_device("AB1")->id))
    found = found || (a.entity == "bench_run" && a.entity_id == id &&
                      a.detail.find("outcome aborted: table lost at step 3; partial recording out/recording") !=
                          std::string::npos);
  EXPECT_TRUE(found);
}

TEST(DbStore, UnknownSigmaRoundTripsAsNull) {
  TempDir t;
  Store s(t.db(), test::create_opts(), test::test_actor());
  SensorErrors e = test::random_errors(8);
  e.accel.sigma_M(0, 1) = kUnknownSigma;
  const auto id = s.store_set({"ADIS16488A", "A1", ""}, SetSource::bench, test::payload("A1", e)).set_id;
  EXPECT_TRUE(std::isinf(s.get_set(id).errors.accel.sigma_M(0, 1)));
  EXPECT_TRUE(nlohmann::json::parse(s.get_set(id).payload_json)["accel"]["sigma_M"][0][1].is_null());
}

TEST(DbStore, SetsAreImmutableAndStatusesOnlyMoveForward) {
  TempDir t;
  Store s(t.db(), test::create_opts(), test::test_actor());
  const auto id = s.store_bench({"ADIS16488A", "A2", ""}, test::bench_run(), test::payload("A2", test::random_errors(1))).set_id;
  // Even raw SQL cannot change a payload or delete a set (triggers).
  auto up = s.connection().prepare("UPDATE coefficient_sets SET payload_json = '{}' WHERE id = ?");
  up.bind(1, id);
  EXPECT_THROW(up.run(), DbError);
  auto del = s.connection().prepare("DELETE FROM coefficient_values WHERE set_id = ?");
  del.bind(1, id);
  EXPECT_THROW(del.run(), DbError);
  EXPECT_THROW(s.record_provisioning(id, "export", "/tmp/x.json", true, "", ""), InputError);  // draft
  EXPECT_THROW(s.set_status(id, SetStatus::provisioned, ""), InputError);
  s.set_status(id, SetStatus::approved, "test");
  s.record_provisioning(id, "device", "emu://1", true, R"({"ok": true})", "");
  EXPECT_EQ(s.get_set(id).status, SetStatus::provisioned);
  s.set_status(id, SetStatus::revoked, "recall");
  EXPECT_THROW(s.set_status(id, SetStatus::approved, ""), InputError);
  EXPECT_EQ(s.provisioning_of(s.get_set(id).device_id).size(), 1u);
}

TEST(DbStore, MalformedPayloadsAreRefusedAndNothingIsWritten) {
  TempDir t;
  Store s(t.db(), test::create_opts(), test::test_actor());
  const std::string good = test::payload("A3", test::random_errors(2));
  const auto before = s.count("audit_log");
  const std::vector<std::pair<std::string, std::string>> bad = {
      {good.substr(0, good.size() / 2), "truncated"},
      {R"({"format": "calbench-coefficients/1", "device": {"model": "ADIS16488A", "serial": "A3"}, "gyro": {"bias": [1, "x", 3], "M": [[0,0,0],[0,0,0],[0,0,0]]}, "accel": {}})", "gyro.bias[1]"},
      {R"({"format": "calbench-coefficients/1", "device": {"model": "ADIS16488A", "serial": "A3"}, "gyro": {"bias": [1, NaN, 3]}})", "invalid JSON"},
      {R"({"format": "calbench-coefficients/1", "device": {"model": "ADIS16488A", "serial": "A3"}, "gyro": {"bias": [1, 1e999, 3]}})", "number out of range"},
      {R"({"format": "calbench-coefficients/1", "device": {"model": "ADIS16488A", "serial": "B9"}, "gyro": {}, "accel": {}})", "does not match"},
      {R"({"format": "other/2"})", "format"},
      {R"([1, 2, 3])", "object"},
  };
  for (const auto& [text, expect] : bad) {
    try {
      s.store_bench({"ADIS16488A", "A3", ""}, test::bench_run(), text);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
    }
  }
  SensorErrors neg = test::random_errors(3);
  neg.gyro.sigma_bias(0) = -1;
  EXPECT_THROW(s.store_bench({"ADIS16488A", "A3", ""}, test::bench_run(), test::payload("A3", neg)), InputError);
  BenchRunInput nan_qc = test::bench_run();
  nan_qc.qc[0].value = NAN;
  EXPECT_THROW(s.store_bench({"ADIS16488A", "A3", ""}, nan_qc, good), InputError);
  EXPECT_EQ(s.count("devices"), 0);
  EXPECT_EQ(s.count("bench_runs"), 0);
  EXPECT_EQ(s.count("coefficient_sets"), 0);
  EXPECT_EQ(s.count("qc_results"), 0);
  EXPECT_EQ(s.count("audit_log"), before);
}

TEST(DbStore, SqlMetacharactersInNamesAreStoredVerbatim) {
  TempDir t;
  Store s(t.db(), test::create_opts(), Actor{"o'brien\"; DROP TABLE devices; --", "st'1", "OS user", "o'os"});
  const std::string serial = "X'); DROP TABLE coefficient_sets; --";
  BenchRunInput run = test::bench_run();
  run.station = "bench \"7\"; DELETE FROM audit_log;";
  run.plan = "plan'; --";
  const auto st = s.store_bench({"ADIS16488A", serial, "1.0'"}, run, test::payload(serial, test::random_errors(4)));
  EXPECT_EQ(s.find_device(serial)->serial, serial);
  EXPECT_EQ(s.bench_run(st.run_id)->station, run.station);
  EXPECT_EQ(s.bench_run(st.run_id)->plan, run.plan);
  EXPECT_EQ(s.count("coefficient_sets"), 1);
  EXPECT_GE(s.count("audit_log"), 4);
  EXPECT_EQ(s.audit_of_device(st.device_id).front().user, "o'brien\"; DROP TABLE devices; --");
  // Control characters are refused.
  EXPECT_THROW(s.ensure_device({"ADIS16488A", std::string("A\nB"), ""}), InputError);
}

TEST(DbStore, ModelMismatchForAKnownSerialIsRefused) {
  TempDir t;
  Store s(t.db(), test::create_opts(), test::test_actor());
  s.ensure_device({"ADIS16488A", "A5", ""});
  EXPECT_THROW(s.ensure_device({"ADIS16495", "A5", ""}), InputError);
}

TEST(DbStore, FleetUsesNewestNonRevokedSet) {
  TempDir t;
  Store s(t.db(), test::create_opts(), test::test_actor());
  const auto v1 = s.store_set({"ADIS16488A", "F1", ""}, SetSource::bench, test::payload("F1", test::random_errors(1)));
  const auto v2 = s.store_set({"ADIS16488A", "F1", ""}, SetSource::bench, test::payload("F1", test::random_errors(2)));
  s.store_set({"ADIS16488A", "F2", ""}, SetSource::bench, test::payload("F2", test::random_errors(3)));
  s.set_status(v2.set_id, SetStatus::revoked, "bad");
  const auto f = s.fleet();
  EXPECT_EQ(f.size(), 48u);
  for (const auto& v : f)
    if (v.serial == "F1") {
      EXPECT_EQ(v.set_id, v1.set_id);
    }
}

}  // namespace
}  // namespace calbench::db
