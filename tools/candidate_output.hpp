// How `loopfarm start` and `loopfarm verify` show what is known of a zero:
// verification, family with every family's residual, canonical key, local
// dimension; as readable lines or as JSON fields.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "loopfarm/search/start.hpp"

namespace loopfarm::cli {

// Indented lines for the human-readable story: verification with every
// circuit, family (claimed only for a verified loop), canonical key.
void print_candidate(const CandidateAnalysis& candidate);
// The local dimension line (only meaningful at a zero of the cycle energy);
// "unknown" when the Jacobian has an entry that is not finite.
void print_local_dimension(const LocalDimension& dimension);

// Adds the JSON fields to `object`, in this order: family, setup,
// verified, rigid_residual, circuits, family_residuals, local_dimension, and
// more. A family is named only for a verified loop (else
// family_conditions_hold names it); local_dimension and singular_values are
// null unless the loop is verified and its local dimension known. With `analysed` false the fields are
// present and null (or false), so that every object has the same keys.
void add_candidate_json(nlohmann::ordered_json& object, const CandidateAnalysis& candidate, bool analysed);

// "2, 4, 2, 4" for a geometry's a, alpha (degrees) and d.
std::string lengths_text(const JointVector& values);
std::string degrees_text(const JointVector& radians);

// [theta1_deg, ...]
nlohmann::ordered_json degrees_json(const JointVector& radians);

// {"a":[...],"alpha_deg":[...],"d":[...]}
nlohmann::ordered_json geometry_json(const LoopGeometry& geometry);

// A polish onto the motion as JSON (converged, iterations, poses, the
// residuals before and after, displacement, message): the same keys whether
// or not one was run, every value null when `ran` is false.
nlohmann::ordered_json polish_json(const GeometryPolishSummary& polish, bool ran);

}  // namespace loopfarm::cli
