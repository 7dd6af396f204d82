// Canonical form of a loop, the key for de-duplication: the same linkage
// written down in any way gives the same key. Equivalent representations are the
// cyclic relabellings, the reversal of the loop, the flips of joint-axis
// directions (loop.hpp), scale, and the sign of the twist at every link the
// key writes as zero length (a_k / L quantised to 0, i.e. below half the
// tolerance): there the common normal's direction is free, and alpha_k and
// -alpha_k (theta_k and theta_{k+1} turned by pi) are the same loop; and,
// between axes it treats as parallel (|sin alpha_k| below half the
// tolerance), where the common normal lies along them: the offsets are read
// with it centred (centred_parallel_normals, loop.hpp) before anything else.
//
// Every one of the 2n * 2^n representations is scaled to length_scale 1, its
// twists wrapped to (-pi, pi], its values quantised to `tolerance` (lengths
// relative to L, twists in radians), and the lexicographically smallest
// quantised vector (a, alpha, d) is the canonical one, each twist at a
// zero-length link taken with the sign that quantises smaller. Key format:
//
//     "4R a=0.632456,1.264911,0.632456,1.264911 alpha=0.523599,1.570796,... d=0,0,0,0"
//
// n, then each list with as many decimals as the tolerance has (6 for 1e-6).
//
// Known limit: a value within the tolerance of a quantisation boundary can
// round either way in two representations of the same loop (twists near +-pi are
// snapped to +pi and -0 to 0, which removes the commonest case). A
// de-duplicator should therefore also compare candidate geometries
// numerically (canonical geometries within a few tolerances are the same).
#pragma once

#include <cstdint>
#include <string>

#include "loopfarm/core/loop.hpp"

namespace loopfarm {

struct CanonicalForm {
  LoopGeometry geometry;    // the chosen representation, scaled to length scale 1 (unquantised)
  double scale = 1.0;       // length_scale of the input (its parallel axes' normals centred)
  int shift = 0;            // the transformation applied: relabelled by shift,
  bool reversed = false;    // then reversed,
  std::uint32_t flips = 0;  // then these axes flipped,
  // then the twists of these zero-length links (in the representation's
  // labels) negated
  std::uint32_t negated_twists = 0;
  std::string key;
};

// Throws std::invalid_argument for a geometry validate_geometry rejects or a
// tolerance that is not in (0, 1).
CanonicalForm canonical_form(const LoopGeometry& geometry, double tolerance = 1e-6);

// True when some link of `geometry` joins axes the key treats as parallel
// (|sin alpha_k| at most half of `tolerance`): there canonical_form reads the
// offsets with the common normal centred (centred_parallel_normals, loop.hpp),
// wherever the normal was left. Throws as canonical_form does.
bool has_parallel_link(const LoopGeometry& geometry, double tolerance = 1e-6);

// True when some link of `geometry` is one the key writes as zero length
// (a_k / L quantised to 0 at `tolerance`): where canonical_form takes the
// twist with either sign. Throws as canonical_form does.
bool has_zero_length_link(const LoopGeometry& geometry, double tolerance = 1e-6);

// The representation a person reads, for display only (the key and the
// de-duplication are canonical_form's): among every representation scaled to
// length scale 1, the one with the fewest negative twists (alpha in (-pi, pi],
// negative below -tolerance), then the fewest negative offsets (below
// -tolerance), then the smallest quantised (a, alpha, d) as canonical_form
// orders them; the twist at a zero-length link is made positive where that
// is all it takes. A Bennett loop, whose canonical twists are all negative, reads
// with all of them positive. `key` is the canonical key, the same for both
// forms. Throws as canonical_form does.
CanonicalForm conventional_form(const LoopGeometry& geometry, double tolerance = 1e-6);

// Joint angles of the input mapped to the canonical (or conventional)
// representation (a negated twist turns the joints on either side of its link
// by +pi and -pi; the angles are not wrapped).
JointVector canonical_angles(const CanonicalForm& form, const JointVector& theta);

}  // namespace loopfarm
