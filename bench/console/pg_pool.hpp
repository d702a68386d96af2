// The PostgreSQL console's database connections (issue 54 item 11): a bounded pool. A session is not
// tied to a connection: a request leases one open as its login (an idle one of that login, or a new
// one opened with the session's password), and gives it back when answered. At most `max` are open
// in all (`calbench serve --db-connections`); one idle for `idle` is closed; when all are busy a
// request waits up to `wait`, then PoolBusy (the console answers 503 "try again"). An idle connection
// of another login is closed to make room. A login attempt always opens a new connection (that is
// the password check), never reuses one.
#pragma once
#include <chrono>
#include <condition_variable>
#include <list>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>

#include "db/store.hpp"

namespace calbench::console {

class PoolBusy : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class PgPool {
  struct Conn {
    std::string login;
    std::unique_ptr<db::Store> store;
    std::chrono::steady_clock::time_point idle_since;
    bool busy = true;
  };

 public:
  PgPool(std::string uri, std::size_t max, std::chrono::seconds idle, std::chrono::milliseconds wait)
      : uri_(std::move(uri)), max_(max), idle_(idle), wait_(wait), reaper_([this] { reap(); }) {}
  ~PgPool();

  // A connection lent to one request; given back (or closed, when broken) by its destructor.
  class Lease {
   public:
    Lease() = default;
    Lease(Lease&& o) noexcept : pool_(o.pool_), it_(o.it_) { o.pool_ = nullptr; }
    Lease& operator=(Lease&& o) noexcept;
    ~Lease() { release(); }
    explicit operator bool() const { return pool_ != nullptr; }
    db::Store& store() { return *it_->store; }
    // The connection failed (lost): close it instead of keeping it.
    void broken() { broken_ = true; }
    void release();

   private:
    friend class PgPool;
    PgPool* pool_ = nullptr;
    std::list<Conn>::iterator it_;
    bool broken_ = false;
  };

  // A connection as `login`. fresh: always open a new one (a login attempt: the password is checked).
  // Throws PoolBusy, or the db::DbError of a failed connect (db::PermissionError with SQLSTATE
  // 28P01: the server refused the credentials).
  Lease acquire(const std::string& login, std::string_view password, const db::Actor& who, bool fresh);
  std::size_t open_connections();

 private:
  void give_back(std::list<Conn>::iterator it, bool broken);
  void close_idle_locked(std::chrono::steady_clock::time_point now);
  void reap();  // the reaper thread: closes idle connections
  std::unique_ptr<db::Store> connect(const std::string& login, std::string_view password, const db::Actor& who);

  std::string uri_;
  std::size_t max_;
  std::chrono::seconds idle_;
  std::chrono::milliseconds wait_;
  std::mutex m_;
  std::condition_variable freed_;
  std::list<Conn> conns_;
  std::size_t opening_ = 0;  // connects under way (counted against max_)
  bool stopping_ = false;
  std::thread reaper_;  // last: started when the rest is ready
};

}  // namespace calbench::console
