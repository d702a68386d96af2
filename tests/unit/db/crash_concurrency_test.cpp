// Acceptance: a writer killed with SIGKILL in the middle of storing a set leaves an intact database
// with the set either complete or absent; two processes storing 200 sets each at the same time
// lose none and never surface "database is locked".
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <thread>

#include "db_test_util.hpp"

namespace calbench::db {
namespace {

// Every set complete: 24 indexed values, its bench run and QC rows, its create audit entry.
void expect_consistent(Store& s) {
  auto ic = s.connection().prepare("PRAGMA integrity_check");
  ASSERT_TRUE(ic.step());
  EXPECT_EQ(ic.text(0), "ok");
  auto fk = s.connection().prepare("PRAGMA foreign_key_check");
  EXPECT_FALSE(fk.step()) << "foreign key violation";
  auto partial = s.connection().prepare(
      "SELECT s.id FROM coefficient_sets s WHERE (SELECT COUNT(*) FROM coefficient_values v WHERE v.set_id = s.id) <> 24 "
      "OR s.bench_run_id IS NULL OR (SELECT COUNT(*) FROM qc_results q WHERE q.bench_run_id = s.bench_run_id) <> 1 "
      "OR (SELECT COUNT(*) FROM audit_log a WHERE a.entity = 'coefficient_set' AND a.entity_id = s.id) <> 1");
  EXPECT_FALSE(partial.step()) << "partial set " << partial.int64(0);
  auto orphans = s.connection().prepare(
      "SELECT COUNT(*) FROM bench_runs r WHERE NOT EXISTS (SELECT 1 FROM coefficient_sets s WHERE s.bench_run_id = r.id)");
  orphans.step();
  EXPECT_EQ(orphans.int64(0), 0) << "bench run without its set";
}

TEST(DbCrash, SigkillInTheMiddleOfStoringASetLeavesItAbsent) {
  test::TempDir t;
  { Store s(t.db(), test::create_opts(), test::test_actor()); s.store_bench({"ADIS16488A", "K0", ""}, test::bench_run(), test::payload("K0", test::random_errors(1))); }
  for (const char* point : {"set-row", "set-values"}) {
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      try {
        Store s(t.db(), {}, test::test_actor());
        s.set_test_hook([point](const char* p) {
          if (std::strcmp(p, point) == 0) ::kill(::getpid(), SIGKILL);
        });
        s.store_bench({"ADIS16488A", "K1", ""}, test::bench_run(), test::payload("K1", test::random_errors(2)));
      } catch (...) {
      }
      ::_exit(3);  // not reached when the hook fires
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "writer was not killed at " << point;
    Store s(t.db(), {}, test::test_actor());
    expect_consistent(s);
    EXPECT_EQ(s.count("coefficient_sets"), 1) << point;
    EXPECT_FALSE(s.find_device("K1")) << "device of the killed transaction survived";
  }
}

TEST(DbCrash, SigkillAtRandomTimesNeverLeavesAPartialSet) {
  test::TempDir t;
  { Store s(t.db(), test::create_opts(), test::test_actor()); }
  std::int64_t last = 0;
  for (int k = 0; k < 6; ++k) {
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      try {
        Store s(t.db(), {}, test::test_actor());
        for (unsigned i = 0;; ++i)
        {
          const std::string serial = std::string("R").append(std::to_string(i % 7));
          s.store_bench({"ADIS16488A", serial, ""}, test::bench_run(), test::payload(serial, test::random_errors(i)));
        }
      } catch (...) {
      }
      ::_exit(3);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(40 + 23 * k));
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status)) << "writer ended by itself";
    Store s(t.db(), {}, test::test_actor());
    expect_consistent(s);
    const auto n = s.count("coefficient_sets");
    EXPECT_GE(n, last);  // committed sets stay
    last = n;
  }
  EXPECT_GT(last, 0) << "the writers never committed anything";
}

TEST(DbConcurrency, TwoProcessesStore200SetsEachWithoutLossOrLockErrors) {
  test::TempDir t;
  { Store s(t.db(), test::create_opts(), test::test_actor()); }
  constexpr int kSets = 200;
  int pipes[2][2];
  pid_t pids[2];
  for (int w = 0; w < 2; ++w) {
    ASSERT_EQ(::pipe(pipes[w]), 0);
    pids[w] = ::fork();
    ASSERT_GE(pids[w], 0);
    if (pids[w] == 0) {
      ::close(pipes[w][0]);
      std::string err;
      try {
        Store s(t.db(), {}, test::test_actor());
        for (int i = 0; i < kSets; ++i) {
          // Both writers add versions to the same device (contended) and to their own.
          const std::string serial = i % 2 ? std::string("SHARED") : std::string("W").append(std::to_string(w));
          s.store_bench({"ADIS16488A", serial, ""}, test::bench_run(),
                        test::payload(serial, test::random_errors(static_cast<unsigned>(w * 1000 + i))));
        }
      } catch (const std::exception& e) {
        err = e.what();
      }
      if (!err.empty()) (void)!::write(pipes[w][1], err.data(), err.size());
      ::_exit(err.empty() ? 0 : 1);
    }
    ::close(pipes[w][1]);
  }
  for (int w = 0; w < 2; ++w) {
    std::string msg;
    char buf[512];
    for (ssize_t n; (n = ::read(pipes[w][0], buf, sizeof buf)) > 0;) msg.append(buf, static_cast<std::size_t>(n));
    ::close(pipes[w][0]);
    int status = 0;
    ::waitpid(pids[w], &status, 0);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "writer " << w << ": " << msg;
    EXPECT_EQ(msg.find("locked"), std::string::npos) << msg;
  }
  Store s(t.db(), {}, test::test_actor());
  expect_consistent(s);
  EXPECT_EQ(s.count("coefficient_sets"), 2 * kSets);
  // Versions of the shared device are 1..200 without gaps or duplicates.
  auto v = s.connection().prepare(
      "SELECT COUNT(*), MIN(version), MAX(version), COUNT(DISTINCT version) FROM coefficient_sets s "
      "JOIN devices d ON d.id = s.device_id WHERE d.serial = 'SHARED'");
  ASSERT_TRUE(v.step());
  EXPECT_EQ(v.int64(0), kSets);
  EXPECT_EQ(v.int64(1), 1);
  EXPECT_EQ(v.int64(2), kSets);
  EXPECT_EQ(v.int64(3), kSets);
}

}  // namespace
}  // namespace calbench::db
