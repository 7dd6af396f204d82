// How the store finds the stored candidate of the same linkage as a new
// verified start: the canonical geometry as the database holds it, the
// distance between two of them, and the grid cells a lookup tries. Private to
// the store.
#pragma once

#include <array>
#include <cstdint>
#include <string>
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

// Per value, the cells a geometry within `tolerance` may occupy (the first is
// the value's own).
std::vector<std::vector<long>> cell_options(const CanonicalEntry& c, double tolerance);

// The name of one combination of cells: `choice` picks one option per value.
std::string cell_name(const std::vector<std::vector<long>>& options, const std::vector<size_t>& choice);

// The grid cell a candidate is stored under.
std::string grid_cell(const CanonicalEntry& c);

// Twists are stored in degrees; a record's twist goes through its stored value
// so that it compares with a stored row exactly as the row would.
double stored_twist(double radians);
double twist_from_stored(double degrees);

// The entry of a verified record's canonical geometry, first start (run_id, r.index).
CanonicalEntry canonical_entry(const StartRecord& r, std::int64_t run_id);

}  // namespace loopfarm::store
