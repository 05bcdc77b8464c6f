#pragma once

// Private helpers for database_reader.cc and database_writer.cc: RAII for prepared
// statements and one place that turns SQLite result codes into exceptions.

#include <sqlite3.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>

namespace cwloc::colmap::internal {

struct StmtFinalizer {
  void operator()(sqlite3_stmt* stmt) const { sqlite3_finalize(stmt); }
};
using StmtPtr = std::unique_ptr<sqlite3_stmt, StmtFinalizer>;

// "<what>: SQLite error: <message> (code N)". The connection's message is more specific
// than sqlite3_errstr when there is one.
inline std::string SqliteErrorMessage(sqlite3* db, int rc, std::string_view what) {
  std::string message(what);
  message += ": SQLite error: ";
  message += (db != nullptr && sqlite3_errcode(db) == rc) ? sqlite3_errmsg(db) : sqlite3_errstr(rc);
  message += " (code " + std::to_string(rc) + ")";
  return message;
}

// Throws Error (InputError in the reader, runtime_error in the writer) unless rc is one of
// the success codes.
template <typename Error = std::runtime_error>
int CheckSqlite(sqlite3* db, int rc, std::string_view what) {
  if (rc != SQLITE_OK && rc != SQLITE_ROW && rc != SQLITE_DONE) {
    throw Error(SqliteErrorMessage(db, rc, what));
  }
  return rc;
}

template <typename Error = std::runtime_error>
StmtPtr Prepare(sqlite3* db, std::string_view sql, std::string_view what) {
  sqlite3_stmt* stmt = nullptr;
  const int rc = sqlite3_prepare_v3(db, sql.data(), static_cast<int>(sql.size()),
                                    SQLITE_PREPARE_PERSISTENT, &stmt, nullptr);
  if (rc != SQLITE_OK) {
    sqlite3_finalize(stmt);
    throw Error(SqliteErrorMessage(db, rc, what));
  }
  return StmtPtr(stmt);
}

// Resets a reused statement and drops its bindings when the scope ends, also on a throw,
// so that the next use starts clean and no read transaction stays open.
class StmtScope {
 public:
  explicit StmtScope(sqlite3_stmt* stmt) : stmt_(stmt) {}
  ~StmtScope() {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
  }
  StmtScope(const StmtScope&) = delete;
  StmtScope& operator=(const StmtScope&) = delete;

 private:
  sqlite3_stmt* stmt_;
};

}  // namespace cwloc::colmap::internal
