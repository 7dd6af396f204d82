// The stiff-limit equilibrium of an elastic loop at one input angle.
//
// With springs along each link's length a_i and about its twist alpha_i (the
// paper's model; optionally along the offsets d_i too), the loop held at input
// angle theta_in settles where the elastic energy is least. In the stiff limit
// that is the equality-constrained least-norm problem (docs/design.md, "The
// equilibrium at one input angle")
//
//     E(theta_in) = min over passive angles q and deformations delta of
//                   1/2 delta^T K delta   subject to   closure(theta_in, q, p + delta) = 0,
//
// solved exactly (no penalty stiffness to tune). Everything is dimensionless:
// lengths are measured in the loop's length scale L (see length_scale), so a
// length deformation enters as delta_a / L with stiffness 1, and a twist
// deformation (radians) with stiffness k_t / (k_a L^2) = torsion_stiffness_ratio.
// The energy is E / (k_a L^2).
//
// The solver is a primal-dual Newton (SQP) method on the KKT system with the
// exact constraint curvature, made robust where the closure Jacobian loses
// rank (flat-folded poses) by a stabilised, regularised KKT system and an
// augmented-Lagrangian merit line search. See src/core/equilibrium.cpp.
#pragma once

#include <string>

#include "loopfarm/core/loop.hpp"
#include "loopfarm/core/types.hpp"

namespace loopfarm {

// Which geometric parameters are springy.
enum class Compliance {
  paper,  // a_i and alpha_i: the paper's axial and torsion springs (default)
  full,   // a_i, alpha_i and d_i
};
const char* to_string(Compliance compliance);
// Parses "paper" or "full"; throws std::invalid_argument otherwise.
Compliance compliance_from_string(const std::string& text);

enum class SolveStatus {
  converged,           // KKT conditions met to the tolerances
  max_iterations,      // iteration limit reached first
  line_search_failed,  // no step decreased the merit function
  singular,            // the KKT system could not be factorised even when regularised
  non_finite,          // a NaN or infinity appeared (bad input or overflow)
};
const char* to_string(SolveStatus status);

struct EquilibriumOptions {
  Compliance compliance = Compliance::paper;
  // k_t / (k_a L^2): torsion stiffness relative to the axial one.
  double torsion_stiffness_ratio = 1.0;
  // The driven joint (0-based); every other joint is passive.
  int input_joint = 0;
  // Converged when the closure residual (rotation [rad], translation / L) has
  // max-norm <= closure_tolerance and the gradient of the Lagrangian has
  // max-norm <= stationarity_tolerance.
  double closure_tolerance = 1e-13;
  double stationarity_tolerance = 1e-11;
  int max_iterations = 100;
  // Where the multipliers are negligible (every movable loop), take the
  // Newton step through two small systems (6 x 6 and the passive angles')
  // instead of the general m x m factorisation: the same step to round-off,
  // at about two thirds of the Bennett cycle's instructions (src/core/equilibrium.cpp).
  // Off only to compare the two (tests, benchmarks).
  bool structured_step = true;
  // Near the solution (KKT residual <= 1e-8), reuse the last exact
  // factorisation for the step (simplified Newton: three triangular solves
  // instead of the constraint curvature and a new factorisation), as long as
  // each such step gains two digits. The same solution to the tolerances, at
  // 9 % fewer instructions over the bench's generic cycles (39.9 M -> 36.3 M,
  // bench/cycle_breakdown [--full-newton] under callgrind; src/core/equilibrium.cpp).
  // Off only to compare (tests, benchmarks).
  bool simplified_newton = true;

  // Throws std::invalid_argument naming the first invalid option.
  void validate() const;
};

// The constant part of the problem: the geometry, normalised to L = 1, and the
// layout of the unknowns. Built once per geometry; const afterwards.
//
// Deformations are ordered by kind: (delta a_1..a_n, delta alpha_1..alpha_n)
// and, for Compliance::full, then (delta d_1..d_n). Length deformations are in
// units of L, twist deformations in radians.
class LoopModel {
 public:
  LoopModel(const LoopGeometry& geometry, const EquilibriumOptions& options = {});

  const LoopGeometry& geometry() const { return geometry_; }
  // The geometry with every length divided by length_scale().
  const LoopGeometry& normalized_geometry() const { return normalized_; }
  double length_scale() const { return length_scale_; }
  const EquilibriumOptions& options() const { return options_; }
  int joints() const { return geometry_.joints(); }
  int deformation_count() const { return deformation_count_; }
  // Unknowns of one solve: n - 1 passive angles plus the deformations.
  int unknown_count() const { return unknown_count_; }

  // Chain element of unknown u (ascending chain order).
  int unknown_element(int u) const { return unknown_element_[u]; }
  // All of them, as a list for residual_jacobian.
  std::span<const int> unknown_elements() const {
    return {unknown_element_.data(), static_cast<size_t>(unknown_count_)};
  }
  // For unknown u: its deformation slot, or -1 for a passive angle.
  int unknown_deformation(int u) const { return unknown_deformation_[u]; }
  // For unknown u: the joint whose angle it is, or -1 for a deformation.
  int unknown_joint(int u) const { return unknown_joint_[u]; }
  // Chain element deformed by deformation slot k.
  int deformation_element(int k) const { return deformation_element_[k]; }
  // Stiffness of deformation slot k (1 for lengths, the torsion ratio for twists).
  double deformation_stiffness(int k) const { return deformation_stiffness_[k]; }
  // The chain elements whose constraint curvature a Newton step needs: the
  // unknowns' and the input joint's (for the path tangent), in chain order,
  // as a list for residual_hessian.
  std::span<const int> hessian_elements() const {
    return {hessian_element_.data(), static_cast<size_t>(unknown_count_ + 1)};
  }
  // Position of unknown u, and of the input joint, in hessian_elements().
  int unknown_hessian_index(int u) const { return unknown_hessian_index_[u]; }
  int input_hessian_index() const { return input_hessian_index_; }

 private:
  LoopGeometry geometry_;
  LoopGeometry normalized_;
  double length_scale_ = 1.0;
  EquilibriumOptions options_;
  int deformation_count_ = 0;
  int unknown_count_ = 0;
  std::array<int, kMaxUnknowns> unknown_element_{};
  std::array<int, kMaxUnknowns> unknown_deformation_{};
  std::array<int, kMaxUnknowns> unknown_joint_{};
  std::array<int, kMaxUnknowns + 1> hessian_element_{};
  std::array<int, kMaxUnknowns> unknown_hessian_index_{};
  int input_hessian_index_ = 0;
  std::array<int, kMaxDeformations> deformation_element_{};
  std::array<double, kMaxDeformations> deformation_stiffness_{};
};

// A point of the problem: every joint angle (the input joint's entry is the
// input angle), the deformations and the closure multipliers. A solve's answer
// and the next solve's warm start.
struct EquilibriumState {
  JointVector theta;
  DeformationVector deformations;
  Vector6 multipliers = Vector6::Zero();

  // Angles as given, deformations and multipliers zero.
  static EquilibriumState at_angles(const LoopModel& model, const JointVector& theta);
};

struct EquilibriumSummary {
  SolveStatus status = SolveStatus::max_iterations;
  int iterations = 0;               // Newton iterations
  int residual_evaluations = 0;     // evaluations of the loop product
  double energy = 0.0;              // E / (k_a L^2)
  double closure_residual = 0.0;    // max-norm of (rotation, translation / L)
  double stationarity = 0.0;        // max-norm of the Lagrangian gradient
  int gauss_newton_steps = 0;       // iterations that fell back to the Gauss-Newton model
  int structured_steps = 0;         // iterations that took the structured step (options.structured_step)
  int simplified_steps = 0;         // iterations that reused the last factorisation (simplified Newton)
  double max_regularization = 0.0;  // largest primal regularisation used
  EquilibriumState state;           // the solution (deformations, angles, multipliers)
  // d state / d theta_in along the equilibrium path (theta: 1 for the input
  // joint), from the KKT factorisation of the last Newton step, so accurate
  // to about that step's length: a predictor for the continuation, at no
  // extra factorisation. Set when the solve converged after at least one step.
  bool has_tangent = false;
  EquilibriumState tangent;
};

// Every buffer a solve needs, allocated once for a model's size.
struct EquilibriumWorkspace {
  explicit EquilibriumWorkspace(const LoopModel& model);

  ChainKinematics chain;
  ChainMatrix chain_hessian;
  UnknownMatrix hessian;  // H = W + sigma AᵀA + rho I, then its Cholesky factor L (diagonal inverted)
  UnknownMatrix normal;   // AᵀA (lower triangle)
  Matrix6U jacobian;      // closure Jacobian A with respect to the unknowns
  // [L^-1 Aᵀ | L^-1 g | 0] with H = L Lᵀ: row-major, 8 wide, so that the
  // triangular solve updates whole rows (SIMD-friendly, no short loops).
  Eigen::Matrix<double, Eigen::Dynamic, 8, Eigen::RowMajor, kMaxUnknowns, 8> solved;
  UnknownVector gradient;  // gradient of the Lagrangian
  UnknownVector step;
  UnknownVector scratch;
  Matrix6 schur;
  EquilibriumState trial;
  JointVector theta;  // deformed-geometry buffers
  LoopGeometry deformed;
};

// Limits of one solve, beyond the model's options.
struct SolveLimits {
  // > 0: overrides the model's iteration limit (EquilibriumOptions::max_iterations).
  int max_iterations = 0;
  // >= 0: the solve gives up (status max_iterations) instead of taking one
  // Gauss-Newton step more than this: a caller with a cheaper way on (the
  // continuation bisects, or lands) uses it to stop a solve that has left the
  // region where the exact Hessian is positive definite on the constraints'
  // null space, from which such solves creep.
  int max_gauss_newton_steps = -1;
  // > 0: the solve also ends as converged once, after at least one Newton
  // step (so that it has a tangent), the closure residual and the
  // stationarity are both at most this. For a point that is only a stepping
  // stone of a continuation (a bisection's midpoint, which is no sample): the
  // next solve starts from it anyway, and its last Newton steps would buy
  // digits nobody reads. The summary's closure_residual and stationarity say
  // how far it got.
  double stepping_tolerance = 0.0;
};

// Solves the stiff-limit equilibrium at input angle theta_in from `guess`
// (whose input-joint angle is ignored). Never throws for a failed solve: the
// status says what happened. No heap allocation.
EquilibriumSummary solve_equilibrium(const LoopModel& model, EquilibriumWorkspace& workspace, double theta_in,
                                     const EquilibriumState& guess, const SolveLimits& limits = {});

// d state / d theta_in at a solved equilibrium `solution` (as
// EquilibriumSummary::tangent, but from a factorisation at `solution` itself).
// False where the path has no tangent: the reduced Hessian is not positive
// definite (a fold of the path, or not a minimum). No heap allocation.
bool equilibrium_tangent(const LoopModel& model, EquilibriumWorkspace& workspace, const EquilibriumState& solution,
                         EquilibriumState& tangent);

// The normalised geometry deformed by `deformations`, in `out` (same size).
void deformed_geometry(const LoopModel& model, const DeformationVector& deformations, LoopGeometry& out);

// Physical deformation of slot k: length deformations times L, twists in radians.
double physical_deformation(const LoopModel& model, const DeformationVector& deformations, int k);

// Name of deformation slot k, 1-based as people read it: "a1", "alpha3", "d2".
std::string deformation_name(const LoopModel& model, int k);

}  // namespace loopfarm
