// What the farm keeps of one start: a flat, self-contained record of a
// StartSummary (strings and numbers only), so that it can cross MPI as bytes
// and be written to the results database without the analysis types.
//
// Records are deterministic functions of (job, seed, start index) except for
// `seconds`: two runs of the same job give equal records whatever the number
// of ranks, the chunking or the timing (the farm's tests compare them).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "loopfarm/core/loop.hpp"

namespace loopfarm {

struct StartSummary;

// A verified zero: what the candidates table holds of it. Residuals that do
// not apply (a family check that has no value, e.g. Bennett for n != 4, or
// trivial without a frozen joint) are +infinity, stored as NULL.
struct CandidateRecord {
  std::string family;             // "bennett", "planar", "spherical", "trivial", "unclassified"
  std::string setup;              // Bennett: "asymmetric" / "line_symmetric"; otherwise "none"
  std::string detail;             // e.g. "axes 1 and 3 coincide; joints 2, 4 frozen"
  std::string families;           // every family whose conditions hold, comma-separated, `family` first
  double family_residual = 0.0;   // of the family found (of the nearest family when unclassified)
  double bennett_residual = 0.0;  // every family's residual (classify.hpp's checks)
  double planar_residual = 0.0;
  double spherical_residual = 0.0;
  double trivial_residual = 0.0;
  double rigid_residual = 0.0;  // worst rigid-closure residual of the verification
  bool full_turn = false;       // the input turns fully
  double range_lo_deg = 0.0;    // input range covered, unwrapped, degrees
  double range_hi_deg = 0.0;
  int local_dimension = 0;  // dimension of the zero set among the free parameters; -1: unknown (LocalDimension)
  int free_parameters = 0;
  std::vector<double> singular_values;  // of the deformation Jacobian, descending
  std::string canonical_key;            // canonical.hpp's key (quantised to 1e-6)
  LoopGeometry canonical_geometry;      // the canonical representation, length scale 1 (unquantised)
};

struct StartRecord {
  std::uint64_t index = 0;
  std::string status;   // to_string(SearchStatus)
  double E_mean = 0.0;  // unsteered, at the final geometry (NaN when it could not be evaluated)
  double E_max = 0.0;
  double objective = 0.0;  // the minimised (steered) value
  int evaluations = 0;
  double seconds = 0.0;         // wall time of the start (the only timing-dependent field)
  bool zero = false;            // E_mean <= the job's zero threshold
  bool verified = false;        // zero and rigidly verified: it has a candidate
  LoopGeometry final_geometry;  // in the job's units
  JointVector final_angles;     // assembled pose at theta0 [rad]
  CandidateRecord candidate;    // meaningful when `verified`
};

StartRecord make_start_record(const StartSummary& summary);

// Bytes for MPI (native endianness and doubles: every rank of one run is the
// same build on the same kind of machine). decode throws std::runtime_error
// on a malformed buffer, naming what was wrong.
void encode_records(const std::vector<StartRecord>& records, std::string& out);
std::vector<StartRecord> decode_records(std::string_view bytes);

}  // namespace loopfarm
