// Small RAII layer over the SQLite C API: a connection, prepared statements, write transactions.
// A missing file (without OpenOptions::create) is an InputError. Only prepared statements with
// bound parameters are offered (no SQL text built from data).
//
// Busy policy: every connection has a busy timeout (SQLite sleeps and retries while another
// connection holds the write lock) and every write transaction goes through `write_transaction()`,
// which retries the whole body with back-off when SQLite still reports SQLITE_BUSY. A writer never
// sees "database is locked" unless the lock is held for longer than the whole retry budget, and
// then it gets a BusyError that says so.
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

struct sqlite3;
struct sqlite3_stmt;

namespace calbench::db {

// Any SQLite failure. `code` is the (extended) SQLite result code.
class DbError : public std::runtime_error {
 public:
  DbError(int code, const std::string& what) : std::runtime_error(what), code_(code) {}
  int code() const { return code_; }

 private:
  int code_;
};
// The database stayed locked by another writer for longer than the retry budget.
class BusyError : public DbError {
 public:
  using DbError::DbError;
};

class Statement;

struct OpenOptions {
  bool create = false;     // create the file when missing (else: error "no database at …")
  bool read_only = false;  // open read-only (reports, listings)
  std::chrono::milliseconds busy_timeout{5000};  // per-statement wait inside SQLite
  std::chrono::milliseconds retry_budget{60000};  // total time write_transaction() keeps retrying
};

class Connection {
 public:
  Connection(const std::string& path, const OpenOptions& opt);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  Statement prepare(std::string_view sql);
  // Run a fixed SQL text without parameters (pragmas, DDL). Never pass data in `sql`.
  void exec(const char* sql);
  std::int64_t last_insert_rowid() const;
  int changes() const;
  const std::string& path() const { return path_; }
  sqlite3* handle() { return db_; }

  // Run `body` inside BEGIN IMMEDIATE … COMMIT. On any exception the transaction is rolled back
  // and the exception propagates; on SQLITE_BUSY the whole body is re-run after a back-off, until
  // the retry budget is spent (then BusyError). `body` must therefore be safe to re-run (it only
  // touches the database, or its side effects are idempotent).
  void write_transaction(const std::function<void()>& body);
  // A consistent read snapshot (BEGIN DEFERRED … COMMIT), with the same busy retries.
  void read_transaction(const std::function<void()>& body);

 private:
  // BEGIN <mode> … COMMIT with rollback on exception and busy retries; nested calls join the
  // enclosing transaction.
  void transaction(const char* begin_sql, const std::function<void()>& body);
  std::string path_;
  sqlite3* db_ = nullptr;
  OpenOptions opt_;
  bool in_tx_ = false;
};

// A prepared statement. Bind indices are 1-based, as in SQLite.
class Statement {
 public:
  Statement(sqlite3* db, std::string_view sql);
  ~Statement();
  Statement(Statement&& o) noexcept;
  Statement& operator=(Statement&&) = delete;
  Statement(const Statement&) = delete;

  Statement& bind(int i, std::int64_t v);
  Statement& bind(int i, int v) { return bind(i, static_cast<std::int64_t>(v)); }
  Statement& bind(int i, double v);  // non-finite values are stored as NULL
  Statement& bind(int i, std::string_view v);
  Statement& bind(int i, const char* v) { return bind(i, std::string_view(v)); }
  Statement& bind(int i, const std::string& v) { return bind(i, std::string_view(v)); }
  Statement& bind_null(int i);
  template <class T>
  Statement& bind(int i, const std::optional<T>& v) {
    return v ? bind(i, *v) : bind_null(i);
  }

  // Advance: true when a row is available, false when done. Throws DbError (BusyError on BUSY).
  bool step();
  // Execute a statement that returns no rows.
  void run();
  void reset();

  bool is_null(int col) const;
  std::int64_t int64(int col) const;
  double real(int col) const;  // NULL → NaN
  std::string text(int col) const;  // NULL → ""
  std::optional<std::int64_t> opt_int64(int col) const;
  std::optional<double> opt_real(int col) const;

 private:
  sqlite3* db_;
  sqlite3_stmt* st_ = nullptr;
};

// Throw DbError/BusyError for a failing result code.
[[noreturn]] void throw_sqlite(sqlite3* db, int rc, std::string_view context);

}  // namespace calbench::db
