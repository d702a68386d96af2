// The web console's sessions and lock-out (issue 38), in server memory only: a session is a random
// 256-bit token (the cookie) with its own random CSRF token (every form carries it, every POST is
// checked against it), the signed-in person and that person's open store (PostgreSQL: a connection
// as the login; the credentials live only in that connection). A session ends at logout, after
// kIdle without a request or kLifetime after login. Lock-out: kMaxFailures wrong passwords in a row
// for one login lock that login for kLockout (a right password is refused meanwhile); a restart of
// the server clears it.
#pragma once
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "db/store.hpp"

namespace calbench::console {

using Clock = std::chrono::steady_clock;
inline constexpr int kMaxFailures = 5;
inline constexpr std::chrono::minutes kLockout{15};
inline constexpr std::chrono::hours kLifetime{12};

struct Session {
  std::string login, name, role;  // role: qc | station | provisioning ("" on PostgreSQL: the database decides)
  std::string csrf;
  Clock::time_point created, last;
  std::mutex m;                  // one request at a time uses the store
  std::unique_ptr<db::Store> store;
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
  // Lock-out: "" if `login` may try, else why not (until when).
  std::string locked(const std::string& login);
  void failed(const std::string& login);
  void succeeded(const std::string& login);

 private:
  std::chrono::seconds idle_;
  std::mutex m_;
  std::map<std::string, std::shared_ptr<Session>> by_token_;
  struct Failures {
    int count = 0;
    Clock::time_point until{};
  };
  std::map<std::string, Failures> failures_;
};

}  // namespace calbench::console
