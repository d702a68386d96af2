#include "bench/console/login_guard.hpp"

#include <algorithm>
#include <vector>

namespace calbench::console {

std::string LoginGuard::minutes_left(Clock::time_point until, Clock::time_point now) {
  const auto s = std::chrono::duration_cast<std::chrono::seconds>(until - now).count();
  return std::to_string(std::max<long long>(1, (s + 59) / 60)) + " min";
}

void LoginGuard::expire(Entry& e, Clock::time_point now) const {
  if (locked(e, now)) return;
  if (e.locked_until != Clock::time_point{}) {  // a lock (or an address's block) has run out
    e.locked_until = {};
    e.failures = 0;
  }
  if (e.failures > 0 && now - e.first_failure > lim_.window) e.failures = 0;
}

LoginGuard::Entry* LoginGuard::slot(Table& t, const std::string& key, Clock::time_point now) {
  if (const auto it = t.find(key); it != t.end()) return &it->second;
  if (t.size() >= lim_.max_entries) {
    const auto held = [&](const Entry& e) { return e.in_flight > 0 || locked(e, now); };
    // First what holds nothing: no failure within the window, no lock, nothing in flight.
    for (auto it = t.begin(); it != t.end();) {
      Entry& e = it->second;
      expire(e, now);
      it = !held(e) && e.failures == 0 ? t.erase(it) : std::next(it);
    }
    // Then the oldest unlocked entries (their failures are forgotten; a lock never is), down to 90 %.
    const std::size_t target = lim_.max_entries - std::max<std::size_t>(1, lim_.max_entries / 10);
    if (t.size() > target) {
      std::vector<std::pair<Clock::time_point, Table::iterator>> free;
      for (auto it = t.begin(); it != t.end(); ++it)
        if (!held(it->second)) free.emplace_back(it->second.last, it);
      const std::size_t n = std::min(free.size(), t.size() - target);
      std::nth_element(free.begin(), free.begin() + static_cast<std::ptrdiff_t>(n), free.end(),
                       [](const auto& a, const auto& b) { return a.first < b.first; });
      for (std::size_t i = 0; i < n; ++i) t.erase(free[i].second);
    }
    if (t.size() >= lim_.max_entries) return nullptr;
  }
  Entry& e = t[key];
  e.last = now;
  return &e;
}

std::string LoginGuard::begin(const std::string& login, const std::string& address) {
  std::unique_lock<std::mutex> l(m_);
  auto now = Clock::now();
  Entry* lg = slot(logins_, login, now);
  if (!lg) return "too many logins are locked or being tried at the moment; try again later";
  expire(*lg, now);
  if (locked(*lg, now))
    return "login '" + login + "' is locked after " + std::to_string(lim_.per_login) + " wrong passwords; try again in " +
           minutes_left(lg->locked_until, now);
  if (lg->in_flight >= lim_.parallel_per_login || lg->failures + lg->in_flight >= lim_.per_login)
    return "login '" + login + "' has attempts being checked at this moment; try again in a few seconds";
  Entry* ad = slot(addresses_, address, now);
  if (!ad) return "too many addresses are trying to log in at the moment; try again later";
  expire(*ad, now);
  if (locked(*ad, now))
    return "too many failed logins from your address (" + std::to_string(lim_.failures_per_address) + " within " +
           std::to_string(lim_.window.count() / 60) + " min); try again in " + minutes_left(ad->locked_until, now);
  // Reserved: this attempt counts against the login from now on, also while it waits for its turn.
  ++lg->in_flight;
  ++ad->in_flight;  // held while waiting too, so that neither entry is evicted meanwhile
  if (!turn_.wait_for(l, lim_.address_wait, [&] { return ad->checking < lim_.parallel_per_address; })) {
    --lg->in_flight;
    --ad->in_flight;
    return "too many logins are being checked from your address at this moment; try again in a few seconds";
  }
  ++ad->checking;
  return "";
}

LoginGuard::Settled LoginGuard::finish(const std::string& login, const std::string& address, Outcome o) {
  Settled out;
  const std::lock_guard<std::mutex> l(m_);
  const auto now = Clock::now();
  const auto lg = logins_.find(login);
  const auto ad = addresses_.find(address);
  if (lg == logins_.end() || ad == addresses_.end()) return out;  // not reserved (a caller's bug): nothing to settle
  --lg->second.in_flight;
  --ad->second.in_flight;
  --ad->second.checking;
  turn_.notify_all();
  const auto fail = [&](Entry& e, int limit, std::chrono::seconds lock) {
    expire(e, now);
    if (e.failures == 0) e.first_failure = now;
    e.last = now;
    if (++e.failures >= limit && !locked(e, now)) {
      e.locked_until = lock.count() > 0 ? now + lock : e.first_failure + lim_.window;
      return true;
    }
    return false;
  };
  if (o == Outcome::success) {
    lg->second.failures = 0;
    lg->second.last = now;
  } else if (o == Outcome::failure) {
    out.locked_now = fail(lg->second, lim_.per_login, lim_.lockout);
    out.address_blocked_now = fail(ad->second, lim_.failures_per_address, std::chrono::seconds(0));
  }
  return out;
}

std::size_t LoginGuard::logins_tracked() {
  const std::lock_guard<std::mutex> l(m_);
  return logins_.size();
}

std::size_t LoginGuard::addresses_tracked() {
  const std::lock_guard<std::mutex> l(m_);
  return addresses_.size();
}

}  // namespace calbench::console
