// SQLite at the store's edge: connections, prepared statements, transactions
// and errors that name the database file. Private to the store (src/farm/);
// nothing outside the results database includes it.
#pragma once

#include <sqlite3.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "loopfarm/farm/results_database.hpp"

namespace loopfarm::store {

// Throws DatabaseError "results database PATH: WHAT" (the file's fault: refused).
[[noreturn]] void fail(const std::string& path, const std::string& what);
// SQLite's message for `db`, with the system's error where one was the cause:
// "disk I/O error (No space left on device)".
std::string error_text(sqlite3* db);
// The system's failure (I/O, a full disk, memory, a lock never released) or
// the file's fault (anything else, a path that cannot be opened included:
// refused), from an SQLite result code.
DatabaseError::Cause cause_of(int rc);
// Throws DatabaseError "results database PATH: WHAT: error_text(db)" with the
// cause of `rc`.
[[noreturn]] void fail_code(const std::string& path, sqlite3* db, int rc, const std::string& what);
// The same for the last error on `db`.
[[noreturn]] void fail_sqlite(const std::string& path, sqlite3* db, const std::string& what);
// The result code `rc` of a read, said in words that name the file: "not an
// SQLite database", "damaged (...)" (both refused), else a failure of the
// system (DatabaseError::Cause::failed).
[[noreturn]] void fail_read(const std::string& path, int rc, const std::string& what, const std::string& message);

// %.17g: every double reads back as itself.
std::string format_double(double value);

// An open sqlite3 connection; closed (with sqlite3_close_v2, so that order
// against statements does not matter) when it goes.
struct Connection {
  sqlite3* db = nullptr;

  Connection() = default;
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;
  ~Connection() { sqlite3_close_v2(db); }
};

// Opens `path` (or the URI `filename` for it); errors name `path`.
void open_connection(Connection& c, const std::string& path, int flags, const std::string& filename = {});

// An SQLite URI that opens `path` read-only as immutable: no locks, no WAL,
// no companion files.
std::string immutable_uri(const std::string& path);

// NAME-wal exists and is not empty: commits may be there and not yet in the file.
bool has_commits_in_wal(const std::string& path);

// What this process may do to a database file and beside it: the facts
// the choice of a connection rests on, apart from the system that gives
// them (file_access), so that the choice can be tested for any answer.
struct FileAccess {
  bool exists = false;
  unsigned mode = 0;           // the file's permission bits (07777), 0 when missing
  bool file_writable = false;  // write permission and a write bit in its mode
  bool directory_exists = false;
  bool directory_writable = false;             // NAME-wal and NAME-shm can be created there
  std::vector<std::string> companions;         // NAME-wal, NAME-shm: those that exist
  std::vector<std::string> locked_companions;  // of those, the ones this process may not write
};

// The directory of `path` ("." for a bare name).
std::string directory_of(const std::string& path);

// What the system says for `path`, for this process.
FileAccess file_access(const std::string& path);

// How a reader connects to an existing database file.
enum class ReaderConnection {
  // Nothing has it open (no companions) and this process may write the
  // file and its directory: read-write with query_only on, whose close,
  // the last, removes the companions it created.
  read_write,
  // Companions there (a writer has it open, or one crashed): read-only,
  // leaving them as they are.
  read_only,
  // Nothing has it open, but the file or its directory is not writable, so
  // that a connection's companions could not be removed (or not created):
  // immutable, which creates none.
  immutable,
};
ReaderConnection reader_connection(const FileAccess& access);

// Refuses (DatabaseError naming `path`) a writer that could not write:
// when `file_too`, an existing file without write permission or write bit;
// a directory missing or not writable (the journal beside the file cannot
// be created); a companion this process may not write (a read-only reader
// leaves NAME-wal and NAME-shm with the file's mode when it cannot remove
// them, and SQLite then refuses every write with "attempt to write a
// readonly database").
void check_writer_access(const std::string& path, const FileAccess& access, bool file_too);

// Runs `sql` (any number of statements); on error fails naming `what`.
void exec(const std::string& path, sqlite3* db, const std::string& sql, const char* what);

// A prepared statement, reset (bindings cleared) before every use.
class Statement {
 public:
  Statement() = default;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  ~Statement() { sqlite3_finalize(stmt_); }

  bool prepared() const { return stmt_ != nullptr; }

  void prepare(const std::string& path, sqlite3* db, const std::string& sql) {
    path_ = &path;
    db_ = db;
    if (sqlite3_prepare_v3(db, sql.c_str(), -1, SQLITE_PREPARE_PERSISTENT, &stmt_, nullptr) != SQLITE_OK) {
      fail_sqlite(path, db, "cannot prepare \"" + sql.substr(0, 60) + "...\"");
    }
  }

  Statement& reset() {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
    return *this;
  }

  void bind_null(int i) { check(sqlite3_bind_null(stmt_, i)); }
  void bind(int i, std::int64_t value) { check(sqlite3_bind_int64(stmt_, i, value)); }
  void bind(int i, int value) { check(sqlite3_bind_int64(stmt_, i, value)); }
  void bind(int i, bool value) { check(sqlite3_bind_int64(stmt_, i, value ? 1 : 0)); }
  // NaN and infinities are NULL: SQL has no NaN, and a residual that does not
  // apply (+inf) reads best as "no value".
  void bind(int i, double value) {
    check(std::isfinite(value) ? sqlite3_bind_double(stmt_, i, value) : sqlite3_bind_null(stmt_, i));
  }
  void bind(int i, const std::string& value) {
    check(sqlite3_bind_text(stmt_, i, value.data(), static_cast<int>(value.size()), SQLITE_TRANSIENT));
  }
  void bind(int i, const char* value) { check(sqlite3_bind_text(stmt_, i, value, -1, SQLITE_TRANSIENT)); }
  // A column of another statement's current row, as it is (type and value).
  void bind_value(int i, const sqlite3_value* value) { check(sqlite3_bind_value(stmt_, i, value)); }

  // True for a row, false when done; throws on an error (the statement is
  // reset, so that it holds no lock).
  bool step(const char* what) {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    const std::string message = error_text(db_);
    sqlite3_reset(stmt_);
    throw DatabaseError("results database " + *path_ + ": " + what + ": " + message, cause_of(rc));
  }
  void run(const char* what) {
    step(what);
    sqlite3_reset(stmt_);
  }
  // The result code of one step (extended), the statement reset: for callers
  // that explain particular errors themselves.
  int step_code(std::string& message) {
    const int rc = sqlite3_step(stmt_);
    if (rc != SQLITE_ROW && rc != SQLITE_DONE) message = error_text(db_);
    sqlite3_reset(stmt_);
    return rc;
  }

  std::int64_t integer(int column) const { return sqlite3_column_int64(stmt_, column); }
  // Valid until the statement steps or is reset.
  sqlite3_value* value(int column) const { return sqlite3_column_value(stmt_, column); }
  bool is_null(int column) const { return sqlite3_column_type(stmt_, column) == SQLITE_NULL; }
  double real(int column) const { return sqlite3_column_double(stmt_, column); }
  std::string text(int column) const {
    const auto* bytes = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, column));
    return bytes ? std::string(bytes, static_cast<size_t>(sqlite3_column_bytes(stmt_, column))) : std::string();
  }

 private:
  void check(int rc) const {
    if (rc != SQLITE_OK) fail_sqlite(*path_, db_, "cannot bind a parameter");
  }

  const std::string* path_ = nullptr;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* stmt_ = nullptr;
};

// The first column of the first row of `sql`.
std::int64_t query_integer(const std::string& path, sqlite3* db, const std::string& sql);
std::string query_text(const std::string& path, sqlite3* db, const std::string& sql);

// BEGIN IMMEDIATE on construction; ROLLBACK when it goes without commit().
class Transaction {
 public:
  Transaction(const std::string& path, sqlite3* db) : path_(path), db_(db) {
    exec(path, db, "BEGIN IMMEDIATE", "cannot begin a transaction");
  }
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  ~Transaction() {
    if (open_) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
  }
  void commit() {
    exec(path_, db_, "COMMIT", "cannot commit");
    open_ = false;
  }

 private:
  const std::string& path_;
  sqlite3* db_;
  bool open_ = true;
};

}  // namespace loopfarm::store
