// One interface to the coefficient store's database, two backends: SQLite (a file; the embedded
// default, db/sqlite.cpp) and PostgreSQL (a libpq URI; the central fleet store,
// db/postgres/pg_connection.cpp). open_connection() picks the backend from the target text.
//
// The store's SQL is written once, in the subset both dialects share: `?` parameters (the
// PostgreSQL backend numbers them $1, $2, …), double-quoted identifiers, ON CONFLICT, CAST. The
// few differences (the current time, the schema version, last inserted id) are methods here.
//
// Only prepared statements with bound parameters are offered (no SQL text built from data).
//
// Transactions: every write goes through write_transaction(), which re-runs the whole body with a
// jittered back-off when the database reports a transient conflict (SQLite: busy/locked;
// PostgreSQL: serialization failure, deadlock, lost connection — the connection is re-opened),
// until the retry budget is spent (then BusyError). The body must therefore be safe to re-run.
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace calbench::db {

// Any database failure. `code` is SQLite's extended result code (0 for PostgreSQL); `sqlstate` is
// PostgreSQL's five-character SQLSTATE ("" for SQLite).
class DbError : public std::runtime_error {
 public:
  DbError(int code, const std::string& what, std::string sqlstate = {})
      : std::runtime_error(what), code_(code), sqlstate_(std::move(sqlstate)) {}
  int code() const { return code_; }
  const std::string& sqlstate() const { return sqlstate_; }

 private:
  int code_;
  std::string sqlstate_;
};
// A transient conflict (locked, serialization failure, deadlock, lost connection); after the retry
// budget: the database stayed busy or away for longer than that.
class BusyError : public DbError {
 public:
  using DbError::DbError;
};
// The connection to the server was lost or could not be made (retryable inside a write).
class ConnectionLost : public BusyError {
 public:
  using BusyError::BusyError;
};
// The database refused the operation to this role (PostgreSQL GRANTs and row rules).
class PermissionError : public DbError {
 public:
  using DbError::DbError;
};

enum class Dialect { sqlite, postgres };

struct OpenOptions {
  bool create = false;     // SQLite: create the file when missing (else: error "no database at …")
  bool read_only = false;  // open read-only (reports, listings)
  std::chrono::milliseconds busy_timeout{5000};   // SQLite: per-statement wait inside SQLite
  std::chrono::milliseconds retry_budget{60000};  // total time write_transaction() keeps retrying
};

// One backend's prepared statement (see Statement).
class StatementImpl {
 public:
  virtual ~StatementImpl() = default;
  virtual void bind_int64(int i, std::int64_t v) = 0;
  virtual void bind_double(int i, double v) = 0;  // finite
  virtual void bind_text(int i, std::string_view v) = 0;
  virtual void bind_null(int i) = 0;
  virtual bool step() = 0;
  virtual void reset() = 0;
  virtual bool is_null(int col) const = 0;
  virtual std::int64_t int64(int col) const = 0;  // booleans read as 0/1
  virtual double real(int col) const = 0;
  virtual std::string text(int col) const = 0;  // timestamps as ISO 8601 UTC with milliseconds
};

// A prepared statement. Bind indices are 1-based, as in SQLite.
class Statement {
 public:
  explicit Statement(std::unique_ptr<StatementImpl> p) : p_(std::move(p)) {}
  Statement(Statement&&) noexcept = default;
  Statement& operator=(Statement&&) = delete;

  Statement& bind(int i, std::int64_t v) { p_->bind_int64(i, v); return *this; }
  Statement& bind(int i, int v) { return bind(i, static_cast<std::int64_t>(v)); }
  Statement& bind(int i, double v);  // non-finite values are stored as NULL
  Statement& bind(int i, std::string_view v) { p_->bind_text(i, v); return *this; }
  Statement& bind(int i, const char* v) { return bind(i, std::string_view(v)); }
  Statement& bind(int i, const std::string& v) { return bind(i, std::string_view(v)); }
  Statement& bind_null(int i) { p_->bind_null(i); return *this; }
  template <class T>
  Statement& bind(int i, const std::optional<T>& v) {
    return v ? bind(i, *v) : bind_null(i);
  }

  // Advance: true when a row is available, false when done. Throws DbError (BusyError on conflicts).
  bool step() { return p_->step(); }
  // Execute a statement that returns no rows.
  void run();
  // Clear the bindings and start again.
  void reset() { p_->reset(); }

  bool is_null(int col) const { return p_->is_null(col); }
  std::int64_t int64(int col) const { return p_->int64(col); }
  double real(int col) const;  // NULL → NaN
  std::string text(int col) const { return p_->text(col); }  // NULL → ""
  std::optional<std::int64_t> opt_int64(int col) const;
  std::optional<double> opt_real(int col) const;

 private:
  std::unique_ptr<StatementImpl> p_;
};

class Connection {
 public:
  virtual ~Connection() = default;
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  virtual Dialect dialect() const = 0;
  virtual Statement prepare(std::string_view sql) = 0;
  // Run fixed SQL text without parameters (pragmas, DDL; several statements allowed). Never pass data in `sql`.
  virtual void exec(const char* sql) = 0;
  // What to show for this database in messages: the file, or the URI without its password.
  const std::string& path() const { return path_; }
  // SQL expression for "now" as stored in the created_at/at columns.
  virtual const char* now_sql() const = 0;

  // Run `body` in a write transaction (SQLite: BEGIN IMMEDIATE; PostgreSQL: SERIALIZABLE). On any
  // exception it is rolled back and the exception propagates; on a transient conflict the whole
  // body is re-run after a back-off until the retry budget is spent (then BusyError). Nested calls
  // join the enclosing transaction.
  void write_transaction(const std::function<void()>& body);
  // A consistent read snapshot, with the same retries.
  void read_transaction(const std::function<void()>& body);
  bool in_transaction() const { return in_tx_; }

 protected:
  Connection(std::string path, const OpenOptions& opt) : path_(std::move(path)), opt_(opt) {}
  virtual void begin(bool write) = 0;
  virtual void commit() = 0;
  virtual void rollback() noexcept = 0;
  // Called before a retry after ConnectionLost: re-open (may throw ConnectionLost again).
  virtual void reconnect() {}
  // Run `attempt` again after a jittered exponential back-off while it throws BusyError (after a
  // ConnectionLost, reconnect() first), until the retry budget is spent: then the BusyError says so.
  void with_retries(const std::function<void()>& attempt);
  std::string path_;
  OpenOptions opt_;

 private:
  void transaction(bool write, const std::function<void()>& body);
  bool in_tx_ = false;
};

// "postgresql://…" or "postgres://…" (a libpq URI); anything else is an SQLite file path.
bool is_postgres_uri(std::string_view target);
// The URI without its password (for messages, logs and the audit trail).
std::string redact_uri(const std::string& uri);
// Checks the form of `target` without opening it (a malformed PostgreSQL URI is an InputError).
void check_target(const std::string& target);
// Opens `target` with the backend it names. Bad targets are InputErrors naming them.
std::unique_ptr<Connection> open_connection(const std::string& target, const OpenOptions& opt);

}  // namespace calbench::db
