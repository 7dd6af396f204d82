// SQLite at the store's edge (sqlite_support.hpp).
#include "sqlite_support.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace loopfarm::store {

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw DatabaseError("results database " + path + ": " + what);
}

std::string error_text(sqlite3* db) {
  if (db == nullptr) return "out of memory";
  std::string text = sqlite3_errmsg(db);
  const int system_errno = sqlite3_system_errno(db);
  if (system_errno != 0) text += std::string(" (") + std::strerror(system_errno) + ")";
  return text;
}

DatabaseError::Cause cause_of(int rc) {
  switch (rc & 0xff) {
    case SQLITE_IOERR:
    case SQLITE_FULL:
    case SQLITE_NOMEM:
    case SQLITE_BUSY:
    case SQLITE_LOCKED:
      return DatabaseError::Cause::failed;
    default:
      return DatabaseError::Cause::refused;
  }
}

[[noreturn]] void fail_code(const std::string& path, sqlite3* db, int rc, const std::string& what) {
  throw DatabaseError("results database " + path + ": " + what + ": " + error_text(db), cause_of(rc));
}

[[noreturn]] void fail_sqlite(const std::string& path, sqlite3* db, const std::string& what) {
  if (db == nullptr)
    throw DatabaseError("results database " + path + ": " + what + ": out of memory", DatabaseError::Cause::failed);
  fail_code(path, db, sqlite3_extended_errcode(db), what);
}

// SQLite's own words for a damaged file ("database disk image is
// malformed") do not say which file or that it is the file's fault: say both.
[[noreturn]] void fail_read(const std::string& path, int rc, const std::string& what, const std::string& message) {
  if ((rc & 0xff) == SQLITE_NOTADB) fail(path, "not an SQLite database");
  if ((rc & 0xff) == SQLITE_CORRUPT) fail(path, "damaged (" + what + ": " + message + ")");
  throw DatabaseError("results database " + path + ": " + what + ": " + message, DatabaseError::Cause::failed);
}

// std::to_chars with a precision writes what printf writes (the C++ standard
// says so, and a test compares them), several times faster.
std::string format_double(double value) {
  char buffer[40];
  const auto written = std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::general, 17);
  return std::string(buffer, written.ptr);
}

// Opens `path` (or the URI `filename` for it); errors name `path`.
void open_connection(Connection& c, const std::string& path, int flags, const std::string& filename) {
  // NOMUTEX: a connection is used by one thread at a time (one ResultsDatabase
  // per thread), so SQLite need not lock it on every call (a commit binds
  // about 40 values a start).
  const int rc =
      sqlite3_open_v2((filename.empty() ? path : filename).c_str(), &c.db, flags | SQLITE_OPEN_NOMUTEX, nullptr);
  if (rc != SQLITE_OK) fail_sqlite(path, c.db, "cannot open");
  sqlite3_extended_result_codes(c.db, 1);
  sqlite3_busy_timeout(c.db, kDatabaseBusyTimeoutMs);
  // The last connection to close a WAL database checkpoints and deletes the
  // WAL under an EXCLUSIVE lock on the file, and a reader that opens the file
  // in that moment without a busy timeout (the sqlite3 shell) fails with
  // "database is locked": 30 of 4696 and 49 of 3768 plain sqlite3 reads
  // across 40 short runs did (docs/quality/reliability-faults.md). A read-only connection cannot
  // checkpoint anyway, so it does not try; the writer checkpoints before it
  // closes (~Impl), without that lock, and keeps it for a few microseconds
  // only (deleting the empty WAL).
  if ((flags & SQLITE_OPEN_READONLY) != 0) sqlite3_db_config(c.db, SQLITE_DBCONFIG_NO_CKPT_ON_CLOSE, 1, nullptr);
}

// An SQLite URI that opens `path` read-only as immutable: no locks, no WAL,
// no companion files. '%', '?' and '#' are escaped; an absolute path gets an
// empty authority ("file:///...").
std::string immutable_uri(const std::string& path) {
  std::string uri = path.rfind('/', 0) == 0 ? "file://" : "file:";
  for (const char c : path) {
    if (c == '%' || c == '?' || c == '#') {
      char escaped[4];
      std::snprintf(escaped, sizeof escaped, "%%%02X", static_cast<unsigned char>(c));
      uri += escaped;
    } else {
      uri += c;
    }
  }
  return uri + "?immutable=1";
}

// NAME-wal exists and is not empty: commits may be there and not yet in the file.
bool has_commits_in_wal(const std::string& path) {
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(path + "-wal", error);
  return !error && size > 0;
}

std::string directory_of(const std::string& path) {
  const std::filesystem::path directory = std::filesystem::path(path).parent_path();
  return directory.empty() ? std::string(".") : directory.string();
}

FileAccess file_access(const std::string& path) {
  FileAccess access;
  struct stat status {};
  if (::stat(path.c_str(), &status) == 0) {
    access.exists = true;
    access.mode = static_cast<unsigned>(status.st_mode & 07777);
    // A write bit as well as permission: a file made read-only on purpose
    // (chmod a-w) counts as read-only for root too, whom permissions do not stop.
    access.file_writable = (status.st_mode & (S_IWUSR | S_IWGRP | S_IWOTH)) != 0 && ::access(path.c_str(), W_OK) == 0;
  }
  const std::string directory = directory_of(path);
  struct stat directory_status {};
  access.directory_exists = ::stat(directory.c_str(), &directory_status) == 0 && S_ISDIR(directory_status.st_mode);
  access.directory_writable = access.directory_exists && ::access(directory.c_str(), W_OK | X_OK) == 0;
  for (const char* suffix : {"-wal", "-shm"}) {
    const std::string companion = path + suffix;
    if (::lstat(companion.c_str(), &status) != 0) continue;
    access.companions.push_back(companion);
    if (::access(companion.c_str(), R_OK | W_OK) != 0) access.locked_companions.push_back(companion);
  }
  return access;
}

ReaderConnection reader_connection(const FileAccess& access) {
  if (!access.companions.empty()) return ReaderConnection::read_only;
  return access.file_writable && access.directory_writable ? ReaderConnection::read_write : ReaderConnection::immutable;
}

void check_writer_access(const std::string& path, const FileAccess& access, bool file_too) {
  if (file_too && access.exists && !access.file_writable) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", access.mode);
    fail(path, std::string("a read-only file (mode ") + mode + "): nothing is written to it (make it writable first)");
  }
  const std::string directory = directory_of(path);
  if (!access.directory_exists) fail(path, "its directory " + directory + " does not exist");
  if (!access.directory_writable) {
    fail(path, "its directory " + directory +
                   " is not writable: the journal beside the file cannot be created, so nothing is written to it");
  }
  if (!access.locked_companions.empty()) {
    std::string names;
    for (size_t i = 0; i < access.locked_companions.size(); ++i) {
      names += (i == 0 ? "" : " and ") + access.locked_companions[i];
    }
    const bool one = access.locked_companions.size() == 1;
    // An empty WAL is what a read-only connection that could not remove
    // it leaves; one holding commits is a writer's, not to be removed.
    const std::string advice = has_commits_in_wal(path)
                                   ? path + "-wal holds commits not yet in the file: open it as their owner first"
                                   : std::string("if nothing has the database open, remove ") + (one ? "it" : "them");
    fail(path, names + (one ? " beside it is" : " beside it are") + " not writable, so nothing is written to it (" +
                   advice + ")");
  }
}

void exec(const std::string& path, sqlite3* db, const std::string& sql, const char* what) {
  char* message = nullptr;
  const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message);
  if (rc != SQLITE_OK) {
    sqlite3_free(message);
    fail_code(path, db, rc, what);
  }
}

std::int64_t query_integer(const std::string& path, sqlite3* db, const std::string& sql) {
  Statement s;
  s.prepare(path, db, sql);
  if (!s.step(sql.c_str())) fail(path, sql + " returned no row");
  return s.integer(0);
}

std::string query_text(const std::string& path, sqlite3* db, const std::string& sql) {
  Statement s;
  s.prepare(path, db, sql);
  if (!s.step(sql.c_str())) fail(path, sql + " returned no row");
  return s.text(0);
}

}  // namespace loopfarm::store
