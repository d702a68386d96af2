// The station's live state and operator prompts in the store (issue 38 item 3, schema 8).
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cmath>

#include "common/input_error.hpp"
#include "db/schema.hpp"
#include "db/station_live.hpp"
#include "db_test_util.hpp"

namespace calbench::db {
namespace {
using test::TempDir;

SlotProgress slot(const std::string& run, const std::string& name) {
  SlotProgress p;
  p.run_id = run;
  p.slot = name;
  p.station = "station-T";
  p.serial = "S" + name;
  p.step_count = 3;
  p.step_name = "z down";
  p.step_kind = "static";
  p.check_name = "bad samples";
  p.check_value = 0;
  p.check_limit = 0;
  p.check_unit = "samples";
  return p;
}

TEST(DbStationLive, ProgressRowsAreReplacedPerSlotAndCarryTheirHeartbeat) {
  TempDir t;
  Store s(t.db(), test::create_opts(), test::test_actor());
  SlotProgress a = slot("run1", "1"), b = slot("run1", "2");
  put_progress(s, a);
  put_progress(s, b);
  a.step_index = 2;
  a.step_fraction = 0.5;
  put_progress(s, a);
  b.state = "failed";
  b.reason = "step 'z down' failed 3 times: 12 samples lost";
  b.check_value = 12;
  put_progress(s, b);
  const auto rows = progress_rows(s, "run1");
  ASSERT_EQ(rows.size(), 2u);
  for (const auto& r : rows) {
    EXPECT_EQ(r.login, "tester");
    const double age = age_s(r.heartbeat_at, epoch_now_s());
    EXPECT_TRUE(age >= -1 && age < 60) << r.heartbeat_at;
    if (r.slot == "1") {
      EXPECT_EQ(r.step_index, 2);
      EXPECT_DOUBLE_EQ(r.step_fraction, 0.5);
      EXPECT_EQ(r.state, "running");
    } else {
      EXPECT_EQ(r.state, "failed");
      EXPECT_NE(r.reason.find("samples lost"), std::string::npos);
      EXPECT_DOUBLE_EQ(*r.check_value, 12);
    }
  }
  EXPECT_TRUE(progress_rows(s, "other").empty());
  EXPECT_EQ(progress_rows(s).size(), 2u);
  // A failed slot must say why; states and fractions are checked.
  SlotProgress bad = slot("run1", "3");
  bad.state = "failed";
  EXPECT_THROW(put_progress(s, bad), InputError);
  bad.state = "exploded";
  bad.reason = "x";
  EXPECT_THROW(put_progress(s, bad), InputError);
  bad.state = "running";
  bad.step_fraction = 1.5;
  EXPECT_THROW(put_progress(s, bad), InputError);
  // The database itself refuses a failed row without a reason (a writer that bypasses put_progress).
  EXPECT_THROW(s.connection().exec("UPDATE station_progress SET state = 'failed', reason = '' WHERE slot = '1'"), DbError);
}

TEST(DbStationLive, AgeOfIsoTimestamps) {
  EXPECT_NEAR(age_s("1970-01-01T00:01:00.500Z", 100.0), 39.5, 1e-9);
  EXPECT_NEAR(age_s("1970-01-01T00:01:00Z", 100.0), 40.0, 1e-9);
  EXPECT_TRUE(std::isnan(age_s("yesterday", 100.0)));
}

TEST(DbStationLive, PromptIsAnsweredOnceByAPersonAndAudited) {
  TempDir t;
  Store station(t.db(), test::create_opts(), test::test_actor());
  const auto id = create_prompt(station, "run1", "station-T", "3", "mount the unit in slot 3, then confirm", 30);
  ASSERT_EQ(waiting_prompts(station).size(), 1u);
  EXPECT_EQ(waiting_prompts(station, "run1").front().text, "mount the unit in slot 3, then confirm");
  Store op(t.db(), {}, Actor{"Nora", "line-2", "--operator", "noraos"});
  EXPECT_THROW(answer_prompt(op, id, false, ""), InputError);  // a rejection says why
  const Prompt p = answer_prompt(op, id, true, "");
  EXPECT_EQ(p.state, "confirmed");
  EXPECT_EQ(p.answered_by, "Nora");
  EXPECT_EQ(p.answered_login, "noraos");
  EXPECT_FALSE(p.answered_at.empty());
  EXPECT_TRUE(waiting_prompts(station).empty());
  // Once only: a second answer names the first; a timeout leaves the answer as it was.
  try {
    answer_prompt(op, id, false, "too late");
    FAIL() << "second answer accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("confirmed by Nora"), std::string::npos) << e.what();
  }
  EXPECT_EQ(expire_prompt(station, id).state, "confirmed");
  EXPECT_THROW(answer_prompt(op, 999, true, ""), InputError);
  // The database refuses a change of an answered prompt, and its deletion.
  EXPECT_THROW(station.connection().exec("UPDATE station_prompts SET state = 'rejected'"), DbError);
  EXPECT_THROW(station.connection().exec("DELETE FROM station_prompts"), DbError);
  // Asked and answered are in the audit log.
  auto st = station.connection().prepare("SELECT count(*) FROM audit_log WHERE entity = 'station_prompt'");
  ASSERT_TRUE(st.step());
  EXPECT_EQ(st.int64(0), 2);
}

TEST(DbStationLive, UnansweredPromptTimesOutAndARejectionSaysWhy) {
  TempDir t;
  Store s(t.db(), test::create_opts(), test::test_actor());
  const auto a = create_prompt(s, "run2", "station-T", "", "close the chamber door", 2.5);
  const Prompt e = expire_prompt(s, a);
  EXPECT_EQ(e.state, "timed out");
  EXPECT_NE(e.reason.find("2.5 s"), std::string::npos) << e.reason;
  EXPECT_EQ(e.answered_by, "station");
  const auto b = create_prompt(s, "run2", "station-T", "1", "mount slot 1", 10);
  const Prompt r = answer_prompt(s, b, false, "slot 1 connector broken");
  EXPECT_EQ(r.state, "rejected");
  EXPECT_EQ(r.reason, "slot 1 connector broken");
  EXPECT_THROW(create_prompt(s, "run2", "station-T", "", "", 10), InputError);
  EXPECT_THROW(create_prompt(s, "run2", "station-T", "", "x", 0), InputError);
}

// Schema 8 from 6 and from 1: the station tables appear, old rows stay.
TEST(DbStationLive, MigratesFromSchema6AndFromSchema1) {
  for (const int from : {6, 1}) {
    TempDir t;
    {
      sqlite3* raw = nullptr;
      ASSERT_EQ(sqlite3_open(t.db().c_str(), &raw), SQLITE_OK);
      for (int i = 0; i < from; ++i) ASSERT_EQ(sqlite3_exec(raw, migrations()[i], nullptr, nullptr, nullptr), SQLITE_OK);
      const std::string rows = "INSERT INTO devices VALUES (1, 'ADIS16488A', 'OLD1', '', '2026-01-01T00:00:00.000Z');"
                               "PRAGMA user_version = " + std::to_string(from) + ";";
      ASSERT_EQ(sqlite3_exec(raw, rows.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
      sqlite3_close(raw);
    }
    Store s(t.db(), {}, test::test_actor());
    EXPECT_EQ(s.schema_version(), kSchemaVersion) << "from " << from;
    EXPECT_TRUE(s.find_device("OLD1").has_value());
    put_progress(s, slot("r", "1"));
    EXPECT_EQ(progress_rows(s).size(), 1u);
    EXPECT_GT(create_prompt(s, "r", "station-T", "", "confirm", 5), 0);
  }
}

}  // namespace
}  // namespace calbench::db
