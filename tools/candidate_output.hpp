// How `loopfarm start` and `loopfarm verify` show what is known of a zero:
// verification, family with every family's residual, canonical key, local
// dimension; as readable lines or as JSON fields.
#pragma once

#include <string>

#include "loopfarm/start.hpp"

namespace loopfarm::cli {

// Indented lines for the human-readable story.
void print_candidate(const CandidateAnalysis& candidate);

// The JSON fields (without braces, each preceded by a comma): family, setup,
// verified, rigid_residual, family_residuals, local_dimension, and more.
// With `analysed` false the fields are present and null (or false), so that
// every object has the same keys.
std::string candidate_json_fields(const CandidateAnalysis& candidate, bool analysed);

// "2, 4, 2, 4" for a geometry's a, alpha (degrees) and d.
std::string lengths_text(const JointVector& values);
std::string degrees_text(const JointVector& radians);

// {"a":[...],"alpha_deg":[...],"d":[...]}
std::string geometry_json(const LoopGeometry& geometry);

}  // namespace loopfarm::cli
