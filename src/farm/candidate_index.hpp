// How the store finds the stored candidate of the same linkage as a new
// verified start: the canonical geometry as the database holds it, the
// distance between two of them, the grid cells a lookup tries, and the
// in-memory index of every candidate's key and cell that answers, without
// SQLite, that no stored candidate can match (nearly every new linkage).
// Private to the store.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "loopfarm/core/types.hpp"
#include "loopfarm/farm/results.hpp"

namespace loopfarm::store {

// What de-duplication compares of one candidate: its canonical geometry as the
// database holds it (twists through their stored degrees, so that a record
// compares with a stored row exactly as the row would) and its first start.
struct CanonicalEntry {
  std::int64_t id = 0;
  std::string key;
  int joints = 0;
  std::array<double, 3 * kMaxJoints> values{};  // a, alpha [rad], d
  std::int64_t first_run = 0;
  std::int64_t first_start = 0;
};

// The largest difference between two canonical geometries of n joints
// (twists wrapped), stopping early once it exceeds `tolerance`.
double canonical_distance(const CanonicalEntry& x, const CanonicalEntry& y, double tolerance);

// geometry: every value (a and d at L = 1, twists in radians) cut into cells
// of width kGridCell, twists on a circle of whole cells so that -pi and pi
// meet. Two geometries within the tolerance (< kGridCell) of each other lie
// in the same cell or, for each value near a cell edge, the neighbouring one:
// the lookup tries every such combination (usually one or two cells), so its
// cost does not grow with the number of candidates, not even when thousands
// share a value (searches that end on a bound).
constexpr double kGridCell = 1e-3;
constexpr long kTwistCells = 6283;  // round(2 pi / kGridCell): twists wrap on whole cells
constexpr size_t kMaxCellCombinations = 4096;

// Per value, the cells a geometry within `tolerance` may occupy (the first is
// the value's own, then the one below and the one above when that is near).
struct CellOptions {
  int values = 0;  // 3 n
  std::array<std::array<long, 3>, 3 * kMaxJoints> cells{};
  std::array<std::uint8_t, 3 * kMaxJoints> count{};

  // How many combinations of one cell per value, at most kMaxCellCombinations + 1.
  size_t combinations() const;
};
CellOptions cell_options(const CanonicalEntry& c, double tolerance);

// One combination of cells: `choice` picks one option per value.
using CellChoice = std::array<std::uint8_t, 3 * kMaxJoints>;
// The next combination in odometer order; false after the last (then `choice` is all zero again).
bool next_choice(const CellOptions& options, CellChoice& choice);

// The name of one combination ("12,-3,...": the grid_cell column's text).
std::string cell_name(const CellOptions& options, const CellChoice& choice);

// The grid cell a candidate is stored under.
std::string grid_cell(const CanonicalEntry& c);

// Twists are stored in degrees; a record's twist goes through its stored value
// so that it compares with a stored row exactly as the row would.
double stored_twist(double radians);
double twist_from_stored(double degrees);

// The entry of a verified record's canonical geometry, first start (run_id, r.index).
CanonicalEntry canonical_entry(const StartRecord& r, std::int64_t run_id);

// 64-bit hashes of a candidate's (joints, canonical_key) and of its (joints,
// grid cell), the latter from the cells or from the grid_cell text.
std::uint64_t key_hash(int joints, std::string_view key);
std::uint64_t cell_hash(int joints, const CellOptions& options, const CellChoice& choice);
// False when `text` is not a list of 3 n integers.
bool cell_hash_of_name(int joints, std::string_view text, std::uint64_t& hash);

// Every stored candidate under the hash of its key and the hash of its cell,
// mapped to its candidate_id: an open-addressing table of (hash, id) pairs,
// 16 bytes a slot, at most half full, so about 64 bytes per candidate.
//
// It may say more than is true, never less: a hash names the ids that may
// match, the store reads those rows back and keeps only what really matches
// (the key or the cell equal), so a hash collision, an entry left behind by
// a representative that moved (a replaced candidate keeps its old entries) or
// by a transaction rolled back costs a read, not a wrong answer. What it must
// never miss is a candidate's current key and cell: the store adds them with
// every insert and replace, and reloads the index from the table when another
// connection may have written (PRAGMA data_version) or the table holds an id
// it has not seen.
class CandidateIndex {
 public:
  bool loaded() const { return loaded_; }
  void clear();
  // Marks it loaded (possibly empty): what the table held has been added.
  void set_loaded(std::int64_t data_version) {
    loaded_ = true;
    data_version_ = data_version;
  }
  std::int64_t data_version() const { return data_version_; }
  std::int64_t highest_id() const { return highest_id_; }

  void add(std::uint64_t hash, std::int64_t id);
  // Calls visit(id) for every id stored under `hash` (in no particular order, repeats possible).
  template <class Visit>
  void for_each(std::uint64_t hash, Visit&& visit) const {
    if (slots_.empty()) return;
    const std::uint64_t h = hash == 0 ? 1 : hash;
    const size_t mask = slots_.size() - 1;
    for (size_t i = h & mask; slots_[i].hash != 0; i = (i + 1) & mask) {
      if (slots_[i].hash == h) visit(slots_[i].id);
    }
  }
  size_t entries() const { return entries_; }

 private:
  struct Slot {
    std::uint64_t hash = 0;  // 0: empty
    std::int64_t id = 0;
  };
  void grow();

  std::vector<Slot> slots_;  // a power of two long
  size_t entries_ = 0;
  std::int64_t highest_id_ = 0;
  std::int64_t data_version_ = 0;
  bool loaded_ = false;
};

}  // namespace loopfarm::store
