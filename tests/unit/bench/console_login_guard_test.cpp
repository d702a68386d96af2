// The console's limits on password guessing (bench/console/login_guard.hpp, issue 54 item 7).
#include "bench/console/login_guard.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <string>
#include <thread>
#include <vector>

using calbench::console::LoginGuard;
using calbench::console::LoginLimits;
using Outcome = LoginGuard::Outcome;

// 40 parallel attempts of one login: each is reserved before its check, so at most `per_login` are
// ever checked however they interleave, and the login ends locked.
TEST(ConsoleLoginGuard, ParallelGuessesAreCountedBeforeTheirCheck) {
  LoginGuard g;
  std::atomic<int> checked{0}, refused{0};
  std::vector<std::thread> t;
  std::atomic<bool> go{false};
  for (int i = 0; i < 40; ++i)
    t.emplace_back([&] {
      while (!go) std::this_thread::yield();
      if (!g.begin("bob", "10.0.0.1").empty()) {
        ++refused;
        return;
      }
      ++checked;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));  // the password check
      g.finish("bob", "10.0.0.1", Outcome::failure);
    });
  go = true;
  for (auto& x : t) x.join();
  EXPECT_LE(checked.load(), 5);
  EXPECT_EQ(checked + refused, 40);
  // Whatever got through, a sequence of wrong passwords reaches exactly 5 and locks.
  int more = 0;
  while (g.begin("bob", "10.0.0.1").empty()) {
    ++more;
    g.finish("bob", "10.0.0.1", Outcome::failure);
  }
  EXPECT_EQ(checked + more, 5);
  EXPECT_NE(g.begin("bob", "10.0.0.1").find("locked"), std::string::npos);
}

TEST(ConsoleLoginGuard, ServerErrorsAreNotFailures) {
  LoginGuard g;
  for (int i = 0; i < 20; ++i) {
    ASSERT_EQ(g.begin("bob", "a"), "");
    g.finish("bob", "a", Outcome::no_verdict);
  }
  ASSERT_EQ(g.begin("bob", "a"), "");
  g.finish("bob", "a", Outcome::success);
}

TEST(ConsoleLoginGuard, OneAddressGuessingAcrossLoginsIsStopped) {
  LoginLimits lim;
  lim.failures_per_address = 10;
  LoginGuard g(lim);
  int allowed = 0;
  for (int i = 0; i < 30; ++i) {
    const std::string login = "user" + std::to_string(i);
    if (!g.begin(login, "10.0.0.9").empty()) continue;
    ++allowed;
    g.finish(login, "10.0.0.9", Outcome::failure);
  }
  EXPECT_EQ(allowed, 10);
  EXPECT_EQ(g.begin("someone", "10.0.0.10"), "");  // another address is not affected
}

// A flood of invented logins fills the table: entries are evicted, locks never are (the old code
// cleared the whole table past 100 000 entries, unlocking every login).
TEST(ConsoleLoginGuard, FullTableKeepsEveryLock) {
  LoginLimits lim;
  lim.max_entries = 100;
  lim.failures_per_address = 1000000;
  LoginGuard g(lim);
  for (int i = 0; i < 5; ++i) {
    ASSERT_EQ(g.begin("bob", "a"), "");
    g.finish("bob", "a", Outcome::failure);
  }
  ASSERT_NE(g.begin("bob", "a").find("locked"), std::string::npos);
  for (int i = 0; i < 5000; ++i) {
    const std::string login = "invented" + std::to_string(i);
    if (g.begin(login, "b").empty()) g.finish(login, "b", Outcome::failure);
  }
  EXPECT_LE(g.logins_tracked(), 100u);
  EXPECT_NE(g.begin("bob", "a").find("locked"), std::string::npos);
}

// When every entry is locked, a new login is refused rather than a lock dropped.
TEST(ConsoleLoginGuard, TableOfLocksRefusesNewLogins) {
  LoginLimits lim;
  lim.max_entries = 10;
  lim.per_login = 1;
  lim.failures_per_address = 1000000;
  LoginGuard g(lim);
  for (int i = 0; i < 10; ++i) {
    const std::string login = "l" + std::to_string(i);
    ASSERT_EQ(g.begin(login, "a"), "");
    g.finish(login, "a", Outcome::failure);
  }
  EXPECT_NE(g.begin("new", "a"), "");
  for (int i = 0; i < 10; ++i) EXPECT_NE(g.begin("l" + std::to_string(i), "a").find("locked"), std::string::npos);
}
