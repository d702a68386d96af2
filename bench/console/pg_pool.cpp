#include "bench/console/pg_pool.hpp"

#include <sodium.h>

#include <algorithm>

#include "common/percent_encode.hpp"

namespace calbench::console {
using Clock = std::chrono::steady_clock;

PgPool::~PgPool() {
  {
    const std::lock_guard<std::mutex> l(m_);
    stopping_ = true;
  }
  freed_.notify_all();
  reaper_.join();
  const std::lock_guard<std::mutex> l(m_);
  conns_.clear();
}

void PgPool::reap() {
  std::unique_lock<std::mutex> l(m_);
  while (!stopping_) {
    freed_.wait_for(l, std::chrono::seconds(std::max<long long>(1, idle_.count() / 2)));
    close_idle_locked(Clock::now());
  }
}

PgPool::Lease& PgPool::Lease::operator=(Lease&& o) noexcept {
  if (this != &o) {
    release();
    pool_ = o.pool_, it_ = o.it_, broken_ = o.broken_;
    o.pool_ = nullptr;
  }
  return *this;
}

void PgPool::Lease::release() {
  if (pool_) pool_->give_back(it_, broken_);
  pool_ = nullptr;
}

std::unique_ptr<db::Store> PgPool::connect(const std::string& login, std::string_view password, const db::Actor& who) {
  // The URI with the credentials exists only for the connect (libpq keeps its own copy while the
  // connection is open); it is wiped afterwards.
  std::string pw = percent_encode(password);
  std::string uri = uri_ + (uri_.find('?') == std::string::npos ? "?" : "&") + "user=" + percent_encode(login) + "&password=" + pw;
  const auto wipe = [&] {
    sodium_memzero(pw.data(), pw.size());
    sodium_memzero(uri.data(), uri.size());
  };
  try {
    auto s = std::make_unique<db::Store>(uri, db::OpenOptions{}, who);
    wipe();
    return s;
  } catch (...) {
    wipe();
    throw;
  }
}

void PgPool::close_idle_locked(Clock::time_point now) {
  for (auto it = conns_.begin(); it != conns_.end();)
    it = !it->busy && now - it->idle_since > idle_ ? conns_.erase(it) : std::next(it);
}

PgPool::Lease PgPool::acquire(const std::string& login, std::string_view password, const db::Actor& who, bool fresh) {
  std::unique_lock<std::mutex> l(m_);
  const auto deadline = Clock::now() + wait_;
  for (;;) {
    close_idle_locked(Clock::now());
    if (!fresh)
      for (auto it = conns_.begin(); it != conns_.end(); ++it)
        if (!it->busy && it->login == login) {
          it->busy = true;
          it->store->set_actor(who);
          Lease lease;
          lease.pool_ = this, lease.it_ = it;
          return lease;
        }
    if (conns_.size() + opening_ >= max_) {  // make room: the longest idle connection of any login
      auto oldest = conns_.end();
      for (auto it = conns_.begin(); it != conns_.end(); ++it)
        if (!it->busy && (oldest == conns_.end() || it->idle_since < oldest->idle_since)) oldest = it;
      if (oldest != conns_.end()) conns_.erase(oldest);
    }
    if (conns_.size() + opening_ < max_) break;
    if (freed_.wait_until(l, deadline) == std::cv_status::timeout && conns_.size() + opening_ >= max_)
      throw PoolBusy("all " + std::to_string(max_) + " database connections of the console are in use");
  }
  ++opening_;
  l.unlock();
  std::unique_ptr<db::Store> store;
  try {
    store = connect(login, password, who);
  } catch (...) {
    l.lock();
    --opening_;
    freed_.notify_all();
    throw;
  }
  l.lock();
  --opening_;
  conns_.push_front(Conn{login, std::move(store), Clock::now(), true});
  Lease lease;
  lease.pool_ = this, lease.it_ = conns_.begin();
  return lease;
}

void PgPool::give_back(std::list<Conn>::iterator it, bool broken) {
  const std::lock_guard<std::mutex> l(m_);
  if (broken) {
    conns_.erase(it);
  } else {
    it->busy = false;
    it->idle_since = Clock::now();
  }
  freed_.notify_all();
}

std::size_t PgPool::open_connections() {
  const std::lock_guard<std::mutex> l(m_);
  return conns_.size() + opening_;
}

}  // namespace calbench::console
