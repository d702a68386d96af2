// The console's limits on password guessing (issue 54 item 7), in server memory only.
//
// Every login attempt is reserved with begin() BEFORE its password is checked and settled with
// finish() afterwards, so attempts still being checked count against the login's limit: 40 parallel
// guesses get at most `per_login` password checks, not 40. Limits:
//  * per login: `per_login` failures within `window` lock the login for `lockout` (the right password
//    is refused meanwhile); at most `parallel_per_login` attempts of one login are checked at once;
//  * per client address: at most `parallel_per_address` checks at once (further attempts wait up to
//    `address_wait` for a turn), and `failures_per_address` failures within `window` stop that
//    address's attempts until the window has passed (guessing across many logins);
//  * memory: at most `max_entries` logins and as many addresses are tracked. When full, entries
//    that hold nothing (no failure in the window, no lock, no attempt in flight) are dropped, then the
//    oldest that is neither locked nor in flight; a lock is never dropped. If every entry is locked
//    or in flight, a new login or address is refused (429) until one expires.
#pragma once
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <map>
#include <mutex>
#include <string>

namespace calbench::console {

struct LoginLimits {
  int per_login = 5;
  std::chrono::seconds window{15 * 60};
  std::chrono::seconds lockout{15 * 60};
  int parallel_per_login = 2;
  int parallel_per_address = 4;
  std::chrono::milliseconds address_wait{30000};
  int failures_per_address = 30;
  std::size_t max_entries = 100000;
};

class LoginGuard {
 public:
  using Clock = std::chrono::steady_clock;
  enum class Outcome { success, failure, no_verdict };  // no_verdict: a server error, not a guess
  struct Settled {
    bool locked_now = false;          // this failure locked the login (audit a lock-out)
    bool address_blocked_now = false; // this failure reached the address's limit
  };

  explicit LoginGuard(LoginLimits l = {}) : lim_(l) {}
  // Reserves one attempt of `login` from `address`: "" when reserved (then call finish() exactly
  // once), else why not (the console answers 429). May wait up to address_wait for a turn.
  std::string begin(const std::string& login, const std::string& address);
  Settled finish(const std::string& login, const std::string& address, Outcome o);
  std::size_t logins_tracked();
  std::size_t addresses_tracked();

 private:
  struct Entry {
    int failures = 0;
    Clock::time_point first_failure{}, last{}, locked_until{};
    int in_flight = 0;  // reserved: being checked or waiting for a turn
    int checking = 0;   // addresses: being checked now
  };
  using Table = std::map<std::string, Entry>;
  bool locked(const Entry& e, Clock::time_point now) const { return e.locked_until > now; }
  void expire(Entry& e, Clock::time_point now) const;
  // The entry of `key`, made room for when new (nullptr: the table is full of locked or busy entries).
  Entry* slot(Table& t, const std::string& key, Clock::time_point now);
  static std::string minutes_left(Clock::time_point until, Clock::time_point now);

  LoginLimits lim_;
  std::mutex m_;
  std::condition_variable turn_;
  Table logins_, addresses_;
};

}  // namespace calbench::console
