// The results database's state behind ResultsDatabase (one connection and its
// prepared statements). Private to the store: results_database.cpp writes,
// results_queries.cpp reads.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "candidate_index.hpp"
#include "loopfarm/farm/results_database.hpp"
#include "sqlite_support.hpp"

namespace loopfarm {

struct ResultsDatabase::Impl {
  std::string path;
  DatabaseMode mode = DatabaseMode::read;
  store::Connection connection;  // first, so that it is closed after the statements

  store::Statement insert_start;
  store::Statement insert_candidate;
  store::Statement replace_candidate;
  store::Statement hit_candidate;
  store::Statement select_by_key;
  store::Statement select_by_cell;
  store::Statement select_all;
  store::Statement select_by_id;
  store::Statement data_version;
  store::Statement highest_candidate;
  // Every candidate's key and grid cell, for de-duplication (candidate_index.hpp).
  store::CandidateIndex candidate_index;

  // PRAGMA user_version of the file: older ones are read as they are, and
  // upgraded by the first write that needs the newer schema (open_run).
  int schema_version = kDatabaseSchemaVersion;

  std::int64_t session_id = 0;  // 0: no open session
  std::int64_t session_run = 0;
  bool checkpoint_on_close = false;  // a writer whose open succeeded

  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  // Copies every committed page from the WAL into the file and empties the
  // WAL, so that the file alone holds everything (a copy of it is whole) and
  // the checkpoint that closing does under an EXCLUSIVE lock finds nothing
  // left to copy (open_connection). A reader still on an old snapshot delays
  // it up to 1 s, then it is left to the close or the next writer: the WAL
  // keeps the commits either way.
  ~Impl() {
    if (!checkpoint_on_close || connection.db == nullptr) return;
    sqlite3_busy_timeout(connection.db, 1000);
    sqlite3_exec(connection.db, "PRAGMA wal_checkpoint(TRUNCATE)", nullptr, nullptr, nullptr);
  }

  sqlite3* db() const { return connection.db; }

  void require_write(const char* what) const {
    if (mode == DatabaseMode::read) store::fail(path, std::string(what) + ": the database is open read-only");
  }

  store::Statement& prepared(store::Statement& s, const std::string& sql) {
    if (!s.prepared()) s.prepare(path, db(), sql);
    return s.reset();
  }

  // Upgrades the file to kDatabaseSchemaVersion inside the caller's
  // transaction; schema_version follows once it commits (upgraded_schema).
  void upgrade_schema();
  void upgraded_schema() { schema_version = kDatabaseSchemaVersion; }
  // Schema versions 5 and 6 to 7 (results_rekey.cpp): every candidate whose
  // stored canonical geometry has a link the key reads as zero length, or one
  // joining parallel axes, keyed again as a run keys a new start, and the
  // rows that then name one linkage merged as one run would have stored
  // them. Inside the caller's transaction.
  void rekey_candidates();
  // Folds candidate `other` into `survivor` (the lower id): hits added, the
  // earlier representative kept, the starts re-pointed, `other` deleted.
  void merge_candidate_rows(std::int64_t survivor, std::int64_t other);

  struct StoredCandidate {
    store::CanonicalEntry entry;
    std::string grid_cell;
  };
  void refresh_candidate_index();
  std::optional<StoredCandidate> read_candidate(std::int64_t id);
  void index_candidate(std::int64_t id, const store::CanonicalEntry& c, const store::CellOptions& own_cell);
  // `exclude`: a candidate_id never returned (the row being looked up itself), 0 for none.
  std::optional<store::CanonicalEntry> find_candidate(const store::CanonicalEntry& incoming, double tolerance,
                                                      std::int64_t exclude = 0);
  std::int64_t place_candidate(std::int64_t run_id, const StartRecord& r, double tolerance, CommitSummary& summary);
  void bind_candidate(store::Statement& s, std::int64_t run_id, const StartRecord& r, const std::string& grid_cell);
};

}  // namespace loopfarm
