// The web console's sessions (issue 38, 54), in server memory only: a session is a random 256-bit
// token (the cookie) with its own random CSRF token (every form carries it, every POST is checked
// against it) and the signed-in person. SQLite: the session's own store and the account's password
// hash at login (every request is checked against the account as it is now). PostgreSQL: the login's
// password in locked memory (libsodium), to open a connection from the bounded pool when a request
// needs one (bench/console/pg_pool.hpp). A session ends at logout, after the idle time without a
// request, kLifetime after login, or when its account's role or password changed (all of the
// account's sessions). Lock-outs: bench/console/login_guard.hpp.
#pragma once
#include <atomic>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "db/store.hpp"

namespace calbench::console {

using Clock = std::chrono::steady_clock;
inline constexpr std::chrono::hours kLifetime{12};

// A password kept in guarded, locked memory (sodium_malloc: not swapped, zeroed when freed).
class Secret {
 public:
  explicit Secret(std::string_view s);
  ~Secret();
  Secret(const Secret&) = delete;
  Secret& operator=(const Secret&) = delete;
  std::string_view view() const { return {p_, n_}; }

 private:
  char* p_ = nullptr;
  std::size_t n_ = 0;
};

// One open live-page event stream: `stop` asks it to end (a newer stream of the same session took
// its place); its destructor gives back the server-wide slot.
struct StreamTicket {
  std::atomic<bool> stop{false};
  std::atomic<int>* open = nullptr;
  ~StreamTicket() {
    if (open) --*open;
  }
};

struct Session {
  std::string login, name, role;  // role: qc | station | provisioning (PostgreSQL: calbench_users' role, "" unmapped)
  std::string csrf;
  std::string credential;          // SQLite: the account's password hash at login
  std::unique_ptr<Secret> password;  // PostgreSQL: to open pooled connections as the login
  Clock::time_point created, last;
  std::mutex m;                    // one request at a time uses the session's store
  std::unique_ptr<db::Store> store;  // SQLite: the session's own store
  std::vector<std::weak_ptr<StreamTicket>> streams;  // its open live streams (guarded by the console's stream mutex)
};

// 32 random bytes as 64 hex digits (libsodium randombytes).
std::string random_token();
// Constant-time comparison of two tokens.
bool same_token(const std::string& a, const std::string& b);

class Sessions {
 public:
  explicit Sessions(std::chrono::seconds idle) : idle_(idle) {}
  std::string add(std::shared_ptr<Session> s);  // returns the token
  // The live session of `token`, its idle clock restarted (touch: a person's request; a live page's
  // stream does not keep a session alive); null when unknown or expired.
  std::shared_ptr<Session> find(const std::string& token, bool touch = true);
  void remove(const std::string& token);
  // Ends every session of `login` (its role or password changed, or the account is gone).
  int remove_login(const std::string& login);

 private:
  std::chrono::seconds idle_;
  std::mutex m_;
  std::map<std::string, std::shared_ptr<Session>> by_token_;
};

}  // namespace calbench::console
