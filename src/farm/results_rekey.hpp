// The canonical key of a stored candidate computed again: schema version 6
// takes the twist at a zero-length link with either sign, and version 7 reads
// the offsets between parallel axes with their common normal centred
// (canonical.hpp), which keys written before did not. Private to the store.
#pragma once

#include <optional>
#include <string>

#include "candidate_index.hpp"
#include "loopfarm/core/loop.hpp"

namespace loopfarm::store {

// A stored candidate keyed again: what a run stores for a start of that
// geometry (the key, the canonical geometry, the grid cell) and the entry
// de-duplication compares.
struct RekeyedCandidate {
  CanonicalEntry entry;   // the new key and values; id, first_run, first_start as stored
  LoopGeometry geometry;  // the canonical geometry, length scale 1, twists in radians
  std::string grid_cell;
};

// `stored` (a candidate's canonical geometry as the database holds it, twists
// through their stored degrees) keyed again with the functions a run uses for
// a new verified start (canonical_form, canonical_entry, grid_cell), when it
// has a link the key reads as zero length or one joining parallel axes and
// its key then differs from the stored one. Empty otherwise, and for values
// that are no loop canonical_form takes: such a row is left as it is.
std::optional<RekeyedCandidate> rekey_candidate(const CanonicalEntry& stored);

}  // namespace loopfarm::store
