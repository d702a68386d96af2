#include "db/sqlite.hpp"

#include "common/input_error.hpp"

#include <sqlite3.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>

namespace calbench::db {

void throw_sqlite(sqlite3* db, int rc, std::string_view context) {
  std::string msg(context);
  msg += ": ";
  msg += db ? sqlite3_errmsg(db) : sqlite3_errstr(rc);
  const int primary = rc & 0xff;
  if (primary == SQLITE_BUSY || primary == SQLITE_LOCKED) throw BusyError(rc, msg);
  throw DbError(rc, msg);
}

namespace {
bool is_busy(int rc) { return (rc & 0xff) == SQLITE_BUSY || (rc & 0xff) == SQLITE_LOCKED; }

class SqliteStatement : public StatementImpl {
 public:
  SqliteStatement(sqlite3* db, std::string_view sql) : db_(db) {
    const int rc = sqlite3_prepare_v2(db, sql.data(), static_cast<int>(sql.size()), &st_, nullptr);
    if (rc != SQLITE_OK) throw_sqlite(db, rc, "prepare");
  }
  ~SqliteStatement() override {
    if (st_) sqlite3_finalize(st_);
  }
  void bind_int64(int i, std::int64_t v) override { check(sqlite3_bind_int64(st_, i, v)); }
  void bind_double(int i, double v) override { check(sqlite3_bind_double(st_, i, v)); }
  void bind_text(int i, std::string_view v) override {
    check(sqlite3_bind_text(st_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
  }
  void bind_null(int i) override { check(sqlite3_bind_null(st_, i)); }
  bool step() override {
    const int rc = sqlite3_step(st_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    sqlite3_reset(st_);
    throw_sqlite(db_, rc, "SQL");
  }
  void reset() override {
    sqlite3_reset(st_);
    sqlite3_clear_bindings(st_);
  }
  bool is_null(int col) const override { return sqlite3_column_type(st_, col) == SQLITE_NULL; }
  std::int64_t int64(int col) const override { return sqlite3_column_int64(st_, col); }
  double real(int col) const override { return sqlite3_column_double(st_, col); }
  std::string text(int col) const override {
    const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(st_, col));
    return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(st_, col))) : std::string();
  }

 private:
  void check(int rc) {
    if (rc != SQLITE_OK) throw_sqlite(db_, rc, "bind");
  }
  sqlite3* db_;
  sqlite3_stmt* st_ = nullptr;
};

}  // namespace

SqliteConnection::SqliteConnection(const std::string& path, const OpenOptions& opt) : Connection(path, opt) {
  if (const auto p = path.find("://"); p != std::string::npos && p > 0 && path.find('/') > p)
    throw InputError(path, 0, "", "not a database: neither a SQLite file nor a postgresql:// (or postgres://) URI");
  if (!opt.create && !std::filesystem::exists(path))
    throw InputError(path, 0, "", "no database here (create it with `calbench db init`, or give --db / CALBENCH_DB)");
  // SQLite takes an empty file for a new database and would write a schema into it: only commands
  // that create one (db init, those that store) may.
  if (!opt.create && std::filesystem::is_regular_file(path) && std::filesystem::file_size(path) == 0)
    throw InputError(path, 0, "", "not a calbench database (an empty file): give the database with --db or CALBENCH_DB; "
                                  "`calbench db init --db FILE` creates one");
  int flags = opt.read_only ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE;
  if (opt.create && !opt.read_only) flags |= SQLITE_OPEN_CREATE;
  flags |= SQLITE_OPEN_NOMUTEX;
  if (std::filesystem::is_directory(path))
    throw InputError(path, 0, "", "is a folder, not a database file (give the database file with --db or CALBENCH_DB)");
  if (const auto dir = std::filesystem::path(path).parent_path(); !dir.empty() && !std::filesystem::is_directory(dir))
    throw InputError(path, 0, "", "cannot create the database: the folder " + dir.string() + " does not exist");
  if (opt.create && !std::filesystem::exists(path)) {
    const auto dir = std::filesystem::path(path).parent_path();
    if (::access(dir.empty() ? "." : dir.c_str(), W_OK) != 0)
      throw InputError(path, 0, "", "cannot create the database in " + (dir.empty() ? std::string(".") : dir.string()) + ": " +
                                        std::strerror(errno) + " (give another --db)");
  }
  const int rc = sqlite3_open_v2(path.c_str(), &db_, flags, nullptr);
  if (rc != SQLITE_OK) {
    std::string msg = path + ": cannot open database: " + (db_ ? sqlite3_errmsg(db_) : sqlite3_errstr(rc));
    sqlite3_close(db_);
    db_ = nullptr;
    if ((rc & 0xff) == SQLITE_CANTOPEN) throw InputError(path, 0, "", std::string("cannot open the database: ") + sqlite3_errstr(rc));
    throw DbError(rc, msg);
  }
  sqlite3_extended_result_codes(db_, 1);
  sqlite3_busy_timeout(db_, static_cast<int>(opt.busy_timeout.count()));
  try {
    with_retries([&] {
      exec("PRAGMA foreign_keys = ON");
      if (!opt_.create) {
        // Reads the header (another kind of file fails here, named below). Schema version 0 is another
        // program's SQLite database: refused before the journal mode below would change it.
        SqliteStatement v(db_, "PRAGMA user_version");
        if (v.step() && v.int64(0) == 0)
          throw InputError(path_, 0, "", "not a calbench database (another program's SQLite database): give the database "
                                         "with --db or CALBENCH_DB; `calbench db init --db FILE` creates one");
      }
      if (!opt_.read_only) {
        // WAL: readers never block the writer; the setting persists in the file.
        SqliteStatement wal(db_, "PRAGMA journal_mode = WAL");
        if (wal.step() && wal.text(0) != "wal")
          throw DbError(SQLITE_ERROR, path_ + ": cannot switch the database to WAL mode");
        // FULL: a committed transaction survives a power cut, not only a process crash.
        exec("PRAGMA synchronous = FULL");
      }
    });
  } catch (const DbError& e) {
    sqlite3_close(db_);
    db_ = nullptr;
    // Another file given as the database (a recording's CSV, a JSON): bad input, named.
    if ((e.code() & 0xff) == SQLITE_NOTADB)
      throw InputError(path_, 0, "", "not a calbench database: the file is not an SQLite database (give the database with "
                                     "--db or CALBENCH_DB; `calbench db init --db FILE` creates one)");
    throw;
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

SqliteConnection::~SqliteConnection() {
  if (db_) sqlite3_close_v2(db_);
}

Statement SqliteConnection::prepare(std::string_view sql) { return Statement(std::make_unique<SqliteStatement>(db_, sql)); }

void SqliteConnection::exec(const char* sql) {
  char* err = nullptr;
  const int rc = sqlite3_exec(db_, sql, nullptr, nullptr, &err);
  if (rc != SQLITE_OK) {
    std::string msg = path_ + ": " + (err ? err : sqlite3_errstr(rc));
    sqlite3_free(err);
    if (is_busy(rc)) throw BusyError(rc, msg);
    throw DbError(rc, msg);
  }
}

void SqliteConnection::begin(bool write) { exec(write ? "BEGIN IMMEDIATE" : "BEGIN DEFERRED"); }
void SqliteConnection::commit() { exec("COMMIT"); }
void SqliteConnection::rollback() noexcept {
  if (!sqlite3_get_autocommit(db_)) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
}

}  // namespace calbench::db
