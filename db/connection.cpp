#include "db/connection.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <thread>

#include "db/postgres/pg_connection.hpp"
#include "db/sqlite.hpp"

namespace calbench::db {

Statement& Statement::bind(int i, double v) {
  if (!std::isfinite(v)) return bind_null(i);
  p_->bind_double(i, v);
  return *this;
}

void Statement::run() {
  while (step()) {
  }
}

double Statement::real(int col) const { return is_null(col) ? NAN : p_->real(col); }
std::optional<std::int64_t> Statement::opt_int64(int col) const {
  if (is_null(col)) return std::nullopt;
  return int64(col);
}
std::optional<double> Statement::opt_real(int col) const {
  if (is_null(col)) return std::nullopt;
  return p_->real(col);
}

void Connection::with_retries(const std::function<void()>& attempt) {
  const auto start = std::chrono::steady_clock::now();
  std::minstd_rand rng(static_cast<unsigned>(::getpid()) ^ static_cast<unsigned>(start.time_since_epoch().count()));
  int delay_ms = 2;
  for (;;) {
    try {
      attempt();
      return;
    } catch (const BusyError& e) {
      const bool lost = dynamic_cast<const ConnectionLost*>(&e) != nullptr;
      if (std::chrono::steady_clock::now() - start > opt_.retry_budget) {
        const std::string s = std::to_string(opt_.retry_budget.count() / 1000) + " s";
        if (lost) throw ConnectionLost(e.code(), path_ + ": the database server stayed unreachable for more than " + s +
                                                     "; nothing was written (" + e.what() + ")", e.sqlstate());
        throw BusyError(e.code(), path_ + ": another process kept the database busy for more than " + s +
                                      "; nothing was written", e.sqlstate());
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms / 2 + static_cast<int>(rng() % (delay_ms + 1))));
      delay_ms = std::min(delay_ms * 2, lost ? 2000 : 200);
      if (lost) {
        try {
          reconnect();
        } catch (const ConnectionLost&) {
          // still away: the next attempt fails fast and waits again
        }
      }
    }
  }
}

void Connection::transaction(bool write, const std::function<void()>& body) {
  if (in_tx_) {  // nested: part of the enclosing transaction
    body();
    return;
  }
  with_retries([&] {
    begin(write);
    in_tx_ = true;
    try {
      body();
      commit();
      in_tx_ = false;
    } catch (...) {
      in_tx_ = false;
      rollback();
      throw;
    }
  });
}

void Connection::write_transaction(const std::function<void()>& body) { transaction(true, body); }
void Connection::read_transaction(const std::function<void()>& body) { transaction(false, body); }

bool is_postgres_uri(std::string_view t) {
  return t.rfind("postgresql://", 0) == 0 || t.rfind("postgres://", 0) == 0;
}

std::string redact_uri(const std::string& uri) {
  if (!is_postgres_uri(uri)) return uri;
  std::string u = uri;
  const auto scheme = u.find("://") + 3;
  const auto end = u.find_first_of("/?", scheme);
  const auto at = u.rfind('@', end == std::string::npos ? std::string::npos : end);
  if (at != std::string::npos && at >= scheme) {
    const auto colon = u.find(':', scheme);
    if (colon != std::string::npos && colon < at) u.erase(colon, at - colon);
  }
  // A password given as a query parameter.
  if (const auto q = u.find('?'); q != std::string::npos) {
    std::string query, part;
    std::size_t i = q + 1;
    while (i <= u.size()) {
      const auto amp = std::min(u.find('&', i), u.size());
      part = u.substr(i, amp - i);
      if (!part.empty() && part.rfind("password=", 0) != 0) query += (query.empty() ? "" : "&") + part;
      i = amp + 1;
    }
    u = u.substr(0, q) + (query.empty() ? "" : "?" + query);
  }
  return u;
}

std::unique_ptr<Connection> open_connection(const std::string& target, const OpenOptions& opt) {
  if (is_postgres_uri(target)) return std::make_unique<PgConnection>(target, opt);
  return std::make_unique<SqliteConnection>(target, opt);
}

}  // namespace calbench::db
