// The SQLite backend of db/connection.hpp: one database file, the embedded default.
// A missing file (without OpenOptions::create) is an InputError.
//
// Busy policy: every connection has a busy timeout (SQLite sleeps and retries while another
// connection holds the write lock) and every write transaction goes through `write_transaction()`,
// which retries the whole body with back-off when SQLite still reports SQLITE_BUSY. A writer never
// sees "database is locked" unless the lock is held for longer than the whole retry budget, and
// then it gets a BusyError that says so.
#pragma once
#include <string_view>

#include "db/connection.hpp"

struct sqlite3;

namespace calbench::db {

class SqliteConnection : public Connection {
 public:
  SqliteConnection(const std::string& path, const OpenOptions& opt);
  ~SqliteConnection() override;

  Dialect dialect() const override { return Dialect::sqlite; }
  Statement prepare(std::string_view sql) override;
  void exec(const char* sql) override;
  const char* now_sql() const override { return "strftime('%Y-%m-%dT%H:%M:%fZ', 'now')"; }
  sqlite3* handle() { return db_; }

 protected:
  void begin(bool write) override;
  void commit() override;
  void rollback() noexcept override;

 private:
  sqlite3* db_ = nullptr;
};

// Throw DbError/BusyError for a failing result code.
[[noreturn]] void throw_sqlite(sqlite3* db, int rc, std::string_view context);

}  // namespace calbench::db
