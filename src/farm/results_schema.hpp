// The results database's schema (docs/guide/database.md): the SQL that creates it,
// the column lists the store binds in, and the checks that a file is a sound
// loopfarm database of this schema version. Private to the store.
#pragma once

#include <sqlite3.h>

#include <string>
#include <vector>

namespace loopfarm::store {

class Statement;
struct CanonicalEntry;

// a1..a8, alpha1_deg..alpha8_deg, d1..d8, each with `prefix` and `suffix`;
// the three lists separated by `list_separator`.
std::string geometry_columns(const std::string& prefix, const std::string& suffix,
                             const std::string& list_separator = ", ");

// A candidate row's values for `n` joints read into c.values (a, alpha [rad]
// from its stored degrees, d), its geometry_columns starting at column
// `first` of `row`. False when one of those n-joint values is NULL (a row
// without its geometry; the value read is then 0).
bool read_canonical_values(const Statement& row, int first, int n, CanonicalEntry& c);

// The candidate columns that describe the representative start, in bind order
// (the geometry expands to its 24 columns); everything but candidate_id and hits.
std::vector<std::string> candidate_columns();

// Every CREATE statement of schema version kDatabaseSchemaVersion.
std::string schema_sql();

// The statements that upgrade a database of schema version `from_version` to
// the next (the caller sets PRAGMA user_version, in the same transaction).
// Empty where the step is C++ only (5 to 6: ResultsDatabase::Impl::upgrade_schema).
std::string schema_upgrade_sql(int from_version);

// The schema version of a loopfarm database (kOldestDatabaseSchemaVersion to
// kDatabaseSchemaVersion), or 0 for an empty database (no schema objects, no
// application_id: a file this program may initialise when `allow_empty`).
// Refuses everything else, a file without a table, index or view of its
// version included (check_schema_objects, not strict). Reads only.
int check_identity(const std::string& path, sqlite3* db, bool allow_empty);

// Refuses, as damaged and naming it, a file of schema version `version` that
// lacks one of that version's tables, indexes or views (objects a user added
// are allowed). A schema SQLite cannot read is refused as damaged when
// `strict`, and left to the integrity check otherwise. Reads only.
void check_schema_objects(const std::string& path, sqlite3* db, int version, bool strict);

// PRAGMA quick_check; damage is refused with a few of its problems on one
// line. Then check_schema_objects for the file's schema version.
void check_integrity(const std::string& path, sqlite3* db);

}  // namespace loopfarm::store
