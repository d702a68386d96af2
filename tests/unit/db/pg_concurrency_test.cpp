// Issue 18 acceptance on a real PostgreSQL server (tests/support/pg_server.sh; skipped when
// PostgreSQL is not installed):
//  * 8 processes × 100 sets into one server at once, 20 serials shared among them: none lost,
//    versions unique and gapless (1..n) per serial, no writer sees an error;
//  * the whole server SIGKILLed in the middle of a burst of stores and started again: the writers'
//    retries complete, the indexes pass amcheck, every set is whole or absent, versions stay
//    gapless, and every intended store is there exactly once (uids make a retried commit whose
//    outcome was unknown idempotent).
// Writers are forked processes with a Store (and a connection) each.
#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <thread>

#include "db_test_util.hpp"
#include "tests/support/pg_server.hpp"

namespace calbench::db {
namespace {

using Clock = std::chrono::steady_clock;

// A writer's outcome, written by the child into a file and read by the parent.
struct WriterResult {
  int stored = 0;    // stores that returned (a set id)
  int existed = 0;   // of which: the uid was already stored (a retried commit that had landed)
  int attempts = 0;  // times the set row was inserted (> stored: transactions rolled back and re-run)
  std::string error;
};

WriterResult read_result(const std::string& file) {
  WriterResult r;
  std::ifstream in(file);
  if (!(in >> r.stored >> r.existed >> r.attempts)) r.error = "no result file " + file + " (writer died?)";
  std::string rest;
  std::getline(in, rest);
  std::getline(in, rest);
  if (!rest.empty()) r.error = rest;
  return r;
}

// Waits for the writers and checks each one stored its `sets` without an error; returns their sum.
WriterResult join_writers(const std::vector<pid_t>& pids, const std::string& dir, int sets) {
  WriterResult sum;
  for (std::size_t w = 0; w < pids.size(); ++w) {
    int status = 0;
    ::waitpid(pids[w], &status, 0);
    const auto r = read_result(dir + "/writer-" + std::to_string(w) + ".txt");
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "writer " << w << ": " << r.error;
    EXPECT_EQ(r.error, "") << "writer " << w;
    EXPECT_EQ(r.stored, sets) << "writer " << w;
    sum.stored += r.stored;
    sum.existed += r.existed;
    sum.attempts += r.attempts;
  }
  return sum;
}

// Forks `n` writers. Each waits on `go` (a pipe the parent closes to start them all at once), runs
// `body(w, result)` and writes its result to dir/writer-w.txt; an exception is its error.
std::vector<pid_t> fork_writers(int n, const std::string& dir, int go_read, int go_write,
                                const std::function<void(int, WriterResult&)>& body) {
  std::vector<pid_t> pids;
  for (int w = 0; w < n; ++w) {
    const pid_t pid = ::fork();
    if (pid < 0) throw std::runtime_error("fork");
    if (pid == 0) {
      ::close(go_write);
      char c;
      while (::read(go_read, &c, 1) > 0) {
      }
      WriterResult r;
      try {
        body(w, r);
      } catch (const std::exception& e) {
        r.error = e.what();
      } catch (...) {
        r.error = "unknown exception";
      }
      std::ofstream out(dir + "/writer-" + std::to_string(w) + ".txt");
      for (char& ch : r.error)
        if (ch == '\n') ch = ' ';
      out << r.stored << ' ' << r.existed << ' ' << r.attempts << '\n' << r.error << '\n';
      out.close();
      ::_exit(r.error.empty() ? 0 : 1);
    }
    pids.push_back(pid);
  }
  return pids;
}

std::int64_t scalar(Connection& c, const char* sql) {
  auto st = c.prepare(sql);
  if (!st.step()) throw std::runtime_error(std::string("no row: ") + sql);
  return st.int64(0);
}

// Per serial (with a prefix): versions 1..n, unique, no gaps. Returns the total number of sets.
std::int64_t expect_gapless_versions(Connection& c, const std::string& prefix, int serials) {
  auto st = c.prepare(
      "SELECT d.serial, COUNT(*), MIN(s.version), MAX(s.version), COUNT(DISTINCT s.version) FROM coefficient_sets s "
      "JOIN devices d ON d.id = s.device_id WHERE d.serial LIKE ? GROUP BY d.serial ORDER BY d.serial");
  st.bind(1, prefix + "%");
  std::int64_t total = 0;
  int seen = 0;
  while (st.step()) {
    ++seen;
    const auto n = st.int64(1);
    total += n;
    EXPECT_EQ(st.int64(2), 1) << st.text(0);
    EXPECT_EQ(st.int64(3), n) << st.text(0) << ": versions have a gap";
    EXPECT_EQ(st.int64(4), n) << st.text(0) << ": duplicate versions";
  }
  EXPECT_EQ(seen, serials);
  return total;
}

// Every set whole: 24 indexed values and one create audit entry; with `bench`: its bench run with
// one QC row, and no bench run without its set.
void expect_sets_whole(Connection& c, bool bench) {
  auto partial = c.prepare(
      "SELECT s.id, (SELECT COUNT(*) FROM coefficient_values v WHERE v.set_id = s.id), "
      "(SELECT COUNT(*) FROM audit_log a WHERE a.entity = 'coefficient_set' AND a.entity_id = s.id) "
      "FROM coefficient_sets s WHERE (SELECT COUNT(*) FROM coefficient_values v WHERE v.set_id = s.id) <> 24 "
      "OR (SELECT COUNT(*) FROM audit_log a WHERE a.entity = 'coefficient_set' AND a.entity_id = s.id) <> 1");
  if (partial.step())
    ADD_FAILURE() << "set " << partial.int64(0) << " is not whole: " << partial.int64(1) << " values, "
                  << partial.int64(2) << " audit entries";
  if (!bench) return;
  EXPECT_EQ(scalar(c, "SELECT COUNT(*) FROM coefficient_sets s WHERE s.bench_run_id IS NULL OR "
                      "(SELECT COUNT(*) FROM qc_results q WHERE q.bench_run_id = s.bench_run_id) <> 1"),
            0)
      << "set without its bench run or QC row";
  EXPECT_EQ(scalar(c, "SELECT COUNT(*) FROM bench_runs r WHERE NOT EXISTS "
                      "(SELECT 1 FROM coefficient_sets s WHERE s.bench_run_id = r.id)"),
            0)
      << "bench run without its set";
}

struct PgFixture : ::testing::Test {
  test::TempDir tmp;
  std::unique_ptr<test::PgServer> pg;
  void SetUp() override {
    pg = std::make_unique<test::PgServer>((tmp.path / "pg").string());
    if (!pg->available()) GTEST_SKIP() << pg->why();
    pg->create_database();
    Store s(pg->uri(), {}, test::test_actor());  // schema applied by the owner before the writers start
    ASSERT_EQ(s.schema_version(), kSchemaVersion);
  }
  void TearDown() override { pg.reset(); }
  // Rolled-back transactions of this database so far (each retry of a write rolls one back).
  std::int64_t xact_rollback() {
    auto c = open_connection(pg->uri(), {});
    return scalar(*c, "SELECT xact_rollback FROM pg_stat_database WHERE datname = current_database()");
  }
};

TEST_F(PgFixture, EightProcessesStore100SetsEachOn20SharedSerials) {
  constexpr int kWriters = 8, kSets = 100, kSerials = 20;
  const std::int64_t rb0 = xact_rollback();
  int go[2];
  ASSERT_EQ(::pipe(go), 0);
  const std::string dir = tmp.path.string(), uri = pg->uri();
  auto pids = fork_writers(kWriters, dir, go[0], go[1], [&](int w, WriterResult& r) {
    OpenOptions o;
    o.retry_budget = std::chrono::seconds(120);
    Store s(uri, o, test::test_actor());
    s.set_test_hook([&r](const char* p) {
      if (std::string(p) == "set-row") ++r.attempts;
    });
    for (int i = 0; i < kSets; ++i) {
      // Each writer walks all 20 serials from its own start: every serial gets 40 sets from 8 writers.
      const std::string serial = std::string("C").append(std::to_string(100 + (i + 3 * w) % kSerials));
      const auto st = s.store_set({"ADIS16488A", serial, ""}, SetSource::bench,
                                  test::payload(serial, test::random_errors(static_cast<unsigned>(w * 1000 + i))),
                                  std::nullopt, "conc-" + std::to_string(w) + "-" + std::to_string(i));
      if (st.set_id <= 0 || st.version < 1) throw std::runtime_error("bad StoredSet");
      ++r.stored;
      r.existed += st.existed;
    }
  });
  ::close(go[0]);
  const auto t0 = Clock::now();
  ::close(go[1]);  // start
  const WriterResult all = join_writers(pids, dir, kSets);
  EXPECT_EQ(all.existed, 0) << "a new uid was reported as already stored";
  const int attempts = all.attempts;
  const double secs = std::chrono::duration<double>(Clock::now() - t0).count();
  Store s(pg->uri(), {}, test::test_actor());
  auto& c = s.connection();
  EXPECT_EQ(s.count("coefficient_sets"), kWriters * kSets);
  EXPECT_EQ(s.count("devices"), kSerials);
  EXPECT_EQ(scalar(c, "SELECT COUNT(DISTINCT uid) FROM coefficient_sets WHERE uid LIKE 'conc-%'"), kWriters * kSets);
  EXPECT_EQ(expect_gapless_versions(c, "C", kSerials), kWriters * kSets);
  for (int k = 0; k < kSerials; ++k) {
    const auto d = s.find_device("C" + std::to_string(100 + k));
    ASSERT_TRUE(d);
    EXPECT_EQ(s.sets_of(d->id).size(), static_cast<std::size_t>(kWriters * kSets / kSerials));
  }
  expect_sets_whole(c, false);
  const std::int64_t rb = xact_rollback() - rb0;
  std::printf("[ figures  ] %d writers x %d sets in %.1f s: %.0f sets/s; %lld transactions rolled back and re-run "
              "(%d set rows inserted for %d sets)\n",
              kWriters, kSets, secs, kWriters * kSets / secs, static_cast<long long>(rb), attempts, kWriters * kSets);
  RecordProperty("sets_per_s", static_cast<int>(kWriters * kSets / secs));
  RecordProperty("rollbacks", static_cast<int>(rb));
}

TEST_F(PgFixture, ServerSigkilledDuringABurstLosesAndDuplicatesNothing) {
  constexpr int kWriters = 6, kSets = 60, kSerials = 10;
  int go[2], progress[2];
  ASSERT_EQ(::pipe(go), 0);
  ASSERT_EQ(::pipe(progress), 0);
  const std::string dir = tmp.path.string(), uri = pg->uri();
  auto pids = fork_writers(kWriters, dir, go[0], go[1], [&](int w, WriterResult& r) {
    ::close(progress[0]);
    OpenOptions o;
    o.retry_budget = std::chrono::seconds(90);  // the server is away for a few seconds, plus crash recovery
    Store s(uri, o, test::test_actor());
    s.set_test_hook([&r](const char* p) {
      if (std::string(p) == "set-row") ++r.attempts;
    });
    for (int i = 0; i < kSets; ++i) {
      const std::string serial = std::string("K").append(std::to_string(100 + (i + 5 * w) % kSerials));
      auto run = test::bench_run();
      run.uid = "crash-" + std::to_string(w) + "-" + std::to_string(i);
      const auto st = s.store_bench({"ADIS16488A", serial, ""}, run,
                                    test::payload(serial, test::random_errors(static_cast<unsigned>(w * 1000 + i))));
      if (st.set_id <= 0 || st.version < 1) throw std::runtime_error("bad StoredSet");
      ++r.stored;
      r.existed += st.existed;
      (void)!::write(progress[1], "x", 1);
    }
  });
  ::close(go[0]);
  ::close(progress[1]);
  ::close(go[1]);  // start
  // Kill the server once a third of the sets are in: every writer is then in the middle of a store.
  int done = 0;
  char buf[64];
  while (done < kWriters * kSets / 3) {
    const ssize_t n = ::read(progress[0], buf, sizeof buf);
    ASSERT_GT(n, 0) << "the writers stopped before the kill";
    done += static_cast<int>(n);
  }
  const auto t_kill = Clock::now();
  pg->kill();
  std::this_thread::sleep_for(std::chrono::seconds(2));  // away: the writers' attempts fail and back off
  const std::string port = pg->port();
  ASSERT_EQ(pg->start(), port) << "restarted on another port: the writers cannot find it";
  const double away = std::chrono::duration<double>(Clock::now() - t_kill).count();
  const WriterResult all = join_writers(pids, dir, kSets);
  const int stored = all.stored, existed = all.existed, attempts = all.attempts;
  for (ssize_t n; (n = ::read(progress[0], buf, sizeof buf)) > 0;) done += static_cast<int>(n);
  ::close(progress[0]);
  const double total = std::chrono::duration<double>(Clock::now() - t_kill).count();
  EXPECT_LT(done - kWriters * kSets / 3, kWriters * kSets) << "nothing was left to store after the kill";
  {  // the server crashed and recovered (not a clean shutdown)
    std::ifstream log(pg->dir() + "/server.log");
    std::stringstream ss;
    ss << log.rdbuf();
    EXPECT_NE(ss.str().find("automatic recovery in progress"), std::string::npos) << "no crash recovery in server.log";
  }

  Store s(pg->uri(), {}, test::test_actor());
  auto& c = s.connection();
  // Physical integrity: every B-tree index of the store's tables (heapallindexed: every heap tuple
  // has its index entry) and the tables' heaps.
  c.exec("CREATE EXTENSION IF NOT EXISTS amcheck");
  const char* store_tables =
      "SELECT c.oid FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace WHERE n.nspname = 'public' "
      "AND c.relkind = 'r'";
  auto idx = c.prepare(std::string("SELECT ic.relname, bt_index_check(ic.oid, true) IS NULL FROM pg_index i "
                                   "JOIN pg_class ic ON ic.oid = i.indexrelid JOIN pg_am am ON am.oid = ic.relam "
                                   "WHERE am.amname = 'btree' AND i.indrelid IN (") + store_tables + ")");
  int indexes = 0;
  while (idx.step()) ++indexes;  // bt_index_check raises an error on corruption (step throws)
  EXPECT_GE(indexes, 15) << "amcheck saw too few indexes";
  EXPECT_EQ(scalar(c, (std::string("SELECT COUNT(*) FROM (") + store_tables +
                       ") t, LATERAL verify_heapam(t.oid)").c_str()),
            0)
      << "heap corruption";
  // Logical integrity: whole sets, gapless versions, every intended store exactly once.
  expect_sets_whole(c, true);
  EXPECT_EQ(expect_gapless_versions(c, "K", kSerials), kWriters * kSets);
  EXPECT_EQ(s.count("coefficient_sets"), kWriters * kSets);
  EXPECT_EQ(s.count("bench_runs"), kWriters * kSets);
  EXPECT_EQ(scalar(c, "SELECT COUNT(DISTINCT uid) FROM coefficient_sets WHERE uid LIKE 'crash-%/set'"), kWriters * kSets);
  EXPECT_EQ(scalar(c, "SELECT COUNT(DISTINCT uid) FROM bench_runs WHERE uid LIKE 'crash-%'"), kWriters * kSets);
  EXPECT_EQ(stored, kWriters * kSets);
  std::printf("[ figures  ] server SIGKILLed after %d of %d sets, back after %.1f s (crash recovery done); all "
              "writers done %.1f s after the kill; %d set rows inserted for %d sets (%d re-runs); %d stores found "
              "their uid already committed (commit outcome unknown to the writer); %d indexes pass bt_index_check\n",
              kWriters * kSets / 3, kWriters * kSets, away, total, attempts, kWriters * kSets,
              attempts - kWriters * kSets, existed, indexes);
}

// A TCP relay between a client and the server that, once armed, lets the next COMMIT through to
// the server, waits for the server's answer (the commit is then durable) and closes both sides
// instead of passing the answer on: the client's commit has an unknown outcome, the one case a
// retry can duplicate. It reads the frontend protocol (v3) only to find that COMMIT.
class CommitDropProxy {
 public:
  explicit CommitDropProxy(int upstream_port) : upstream_(upstream_port) {
    lfd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof a;
    if (lfd_ < 0 || ::bind(lfd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(lfd_, 8) != 0 ||
        ::getsockname(lfd_, reinterpret_cast<sockaddr*>(&a), &len) != 0)
      throw std::runtime_error("proxy: listen");
    port_ = ntohs(a.sin_port);
    thread_ = std::thread([this] { accept_loop(); });
  }
  ~CommitDropProxy() {
    stop_ = true;
    ::shutdown(lfd_, SHUT_RDWR);
    ::close(lfd_);
    thread_.join();
    for (auto& t : conns_) t.join();
  }
  int port() const { return port_; }
  void arm() { armed_ = true; }
  int dropped() const { return dropped_; }

 private:
  void accept_loop() {
    for (;;) {
      const int c = ::accept(lfd_, nullptr, nullptr);
      if (c < 0) return;  // closed
      conns_.emplace_back([this, c] { relay(c); });
    }
  }
  static bool send_all(int fd, const char* p, std::size_t n) {
    while (n > 0) {
      const ssize_t k = ::send(fd, p, n, MSG_NOSIGNAL);
      if (k <= 0) return false;
      p += k;
      n -= static_cast<std::size_t>(k);
    }
    return true;
  }
  void relay(int c) {
    const int s = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<std::uint16_t>(upstream_));
    if (::connect(s, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
      ::close(s);
      ::close(c);
      return;
    }
    std::string in;  // client bytes not yet forwarded (whole messages are forwarded)
    bool startup = true, drop_answer = false;
    char buf[65536];
    while (!stop_) {
      pollfd p[2] = {{c, POLLIN, 0}, {s, POLLIN, 0}};
      if (::poll(p, 2, 200) < 0) break;
      if (p[1].revents) {  // server -> client
        const ssize_t n = ::recv(s, buf, sizeof buf, 0);
        if (n <= 0) break;
        if (drop_answer) {  // the COMMIT's answer: committed; the client never hears of it
          ++dropped_;
          break;
        }
        if (!send_all(c, buf, static_cast<std::size_t>(n))) break;
      }
      if (p[0].revents) {  // client -> server, message by message
        const ssize_t n = ::recv(c, buf, sizeof buf, 0);
        if (n <= 0) break;
        in.append(buf, static_cast<std::size_t>(n));
        bool ok = true;
        for (;;) {
          const std::size_t head = startup ? 0 : 1;
          if (in.size() < head + 4) break;
          std::uint32_t len = 0;
          std::memcpy(&len, in.data() + head, 4);
          len = ntohl(len);
          if (in.size() < head + len) break;
          const std::string msg = in.substr(0, head + len);
          in.erase(0, head + len);
          startup = false;
          if (armed_ && msg[0] == 'Q' && std::strcmp(msg.c_str() + 5, "COMMIT") == 0) {
            armed_ = false;
            drop_answer = true;
          }
          if (!send_all(s, msg.data(), msg.size())) ok = false;
        }
        if (!ok) break;
      }
    }
    ::close(s);
    ::close(c);
  }
  int upstream_, port_ = 0, lfd_ = -1;
  std::atomic<bool> stop_{false}, armed_{false};
  std::atomic<int> dropped_{0};
  std::thread thread_;
  std::vector<std::thread> conns_;
};

// A client that reaches the server through CommitDropProxy over TCP (password authentication).
struct AmbiguousCommit : PgFixture {
  std::unique_ptr<CommitDropProxy> proxy;
  std::string uri;
  void SetUp() override {
    PgFixture::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    auto c = open_connection(pg->uri(), {});
    c->exec("ALTER ROLE calbench_admin PASSWORD 'proxy-test-only'");
    proxy = std::make_unique<CommitDropProxy>(std::stoi(pg->port()));
    uri = "postgresql://calbench_admin:proxy-test-only@127.0.0.1:" + std::to_string(proxy->port()) +
          "/calbench?sslmode=disable&gssencmode=disable";
  }
  void TearDown() override {
    proxy.reset();
    PgFixture::TearDown();
  }
};

TEST_F(AmbiguousCommit, ARetriedSetWithAUidIsStoredOnce) {
  Store s(uri, {}, test::test_actor());
  const DeviceInfo dev{"ADIS16488A", "A1", ""};
  s.store_set(dev, SetSource::bench, test::payload("A1", test::random_errors(1)));
  proxy->arm();
  const auto st = s.store_set(dev, SetSource::bench, test::payload("A1", test::random_errors(2)), std::nullopt, "amb-1");
  EXPECT_EQ(proxy->dropped(), 1) << "the COMMIT's answer was not dropped: the test did not test anything";
  EXPECT_TRUE(st.existed) << "the re-run did not find the committed set by its uid";
  EXPECT_EQ(st.version, 2);
  EXPECT_EQ(s.count("coefficient_sets"), 2);
  // A bench run and its set, the same way.
  auto run = test::bench_run();
  run.uid = "amb-run-1";
  proxy->arm();
  const auto b = s.store_bench(dev, run, test::payload("A1", test::random_errors(3)));
  EXPECT_EQ(proxy->dropped(), 2);
  EXPECT_TRUE(b.existed);
  EXPECT_EQ(b.version, 3);
  EXPECT_EQ(s.count("coefficient_sets"), 3);
  EXPECT_EQ(s.count("bench_runs"), 1);
  expect_sets_whole(s.connection(), false);
}

// A store without a uid of the caller's (the station's own `--db` store, store_set from the CLI)
// draws its uid once, before the transaction: the retry after a COMMIT whose answer was lost finds
// the run it stored instead of storing the set a second time (version n and n+1).
TEST_F(AmbiguousCommit, ARetriedStoreWithoutAUidIsStoredOnce) {
  Store s(uri, {}, test::test_actor());
  const DeviceInfo dev{"ADIS16488A", "A2", ""};
  proxy->arm();
  const auto b = s.store_bench(dev, test::bench_run(), test::payload("A2", test::random_errors(4)));
  EXPECT_EQ(proxy->dropped(), 1);
  EXPECT_EQ(s.count("bench_runs"), 1);
  EXPECT_EQ(s.count("coefficient_sets"), 1) << "stored twice; the store returned version " << b.version;
}

}  // namespace
}  // namespace calbench::db
