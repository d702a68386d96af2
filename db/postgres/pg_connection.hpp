// The PostgreSQL backend of db/connection.hpp (libpq): the central fleet store.
//
// Target: a libpq URI, postgresql://USER@HOST[:PORT]/DB[?param=…]. The password comes from
// PGPASSFILE / ~/.pgpass or PGPASSWORD (libpq's own rules), never from calbench's arguments into
// a message: path() is the URI without its password.
//
// Dialect: `?` parameters become $1, $2, … (outside quoted text); every statement is sent with
// PQexecParams (text parameters, typed by the server); booleans read as 0/1 and timestamptz as
// "YYYY-MM-DDTHH:MM:SS.mmmZ" (the session's time zone is UTC), as the SQLite store writes them.
// Write transactions are SERIALIZABLE: serialization failures, deadlocks and a lost connection are
// BusyError/ConnectionLost, retried by Connection::write_transaction (the connection is re-opened).
// A refusal by GRANT or row rule (SQLSTATE 42501) is a PermissionError naming the role.
#pragma once
#include <string_view>

#include "db/connection.hpp"

struct pg_conn;
struct pg_result;

namespace calbench::db {

class PgConnection : public Connection {
 public:
  PgConnection(const std::string& uri, const OpenOptions& opt);
  ~PgConnection() override;

  Dialect dialect() const override { return Dialect::postgres; }
  Statement prepare(std::string_view sql) override;
  void exec(const char* sql) override;
  const char* now_sql() const override { return "now()"; }
  // The role this connection is logged in as (session_user).
  const std::string& role() const { return role_; }

  // Throws the DbError subclass that fits a failed result (consumes nothing; the caller clears it).
  [[noreturn]] void throw_result(pg_result* r, std::string_view context);
  pg_conn* handle() { return conn_; }

 protected:
  void begin(bool write) override;
  void commit() override;
  void rollback() noexcept override;
  void reconnect() override;

 private:
  void connect();
  std::string uri_;
  pg_conn* conn_ = nullptr;
  std::string role_;
};

// `sql` with each `?` outside quotes replaced by $1, $2, …; `count` receives the number.
std::string pg_numbered_parameters(std::string_view sql, int* count);

}  // namespace calbench::db
