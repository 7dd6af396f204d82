#include "loopfarm/core/equilibrium.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "small_dense.hpp"

namespace loopfarm {
namespace {

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument(what); }

// Tuning of the Newton iteration. None of these changes the answer (every
// fixed point is an exact KKT point); they only decide how fast and how
// robustly it is reached.
constexpr double kInitialAugmentation = 1.0;  // sigma: weight of A^T A added to the Hessian
constexpr double kMaxAugmentation = 1e4;
constexpr double kMinRegularization = 1e-10;
constexpr double kMaxRegularization = 1e10;       // rho: primal (Levenberg) regularisation cap
constexpr double kMinDualRegularization = 1e-14;  // mu: stabilisation of the dual block
constexpr double kMaxDualRegularization = 1e-6;
constexpr double kMaxStep = 1.0;  // cap on |dx|_inf [rad, or units of L]
constexpr double kArmijo = 1e-4;
constexpr int kMaxBacktracks = 40;
// Multipliers (max-norm) below which the constraint curvature they weight is
// left out of the Newton Hessian.
constexpr double kNegligibleMultiplier = 1e-6;
// The structured step (below) is used only where its two small factorisations
// are well conditioned: every Cholesky pivot at least this fraction of its
// diagonal entry. Elsewhere (a planar loop, whose link axes span only five
// of the six directions of a deformation; a flat-folded pose) the general
// factorisation, regularised as it is, takes over.
constexpr double kStructuredPivotRatio = 1e-8;
// Simplified Newton: where the KKT residual is at most this, the step reuses
// the last exact factorisation (see solve_equilibrium), as long as each such
// step shrinks the residual by at least kSimplifiedContraction. Over the
// bench's 8 generic 4R cycles at N = 32 (bench/cycle_breakdown under
// valgrind --tool=callgrind, instructions in cycle_energy): without it 1,895
// Newton iterations and 47.4 M instructions; from 1e-6 2,241 iterations (more,
// but cheap ones) and 44.3 M; from 1e-8 1,947 and 43.5 M, every E_mean the
// same to the 10 digits printed.
constexpr double kSimplifiedResidual = 1e-8;
constexpr double kSimplifiedContraction = 1e-2;

double max_abs(const Vector6& v) { return v.cwiseAbs().maxCoeff(); }

// Loads the residual, the energy and (optionally) the closure Jacobian of
// `state` into the workspace. Returns the energy.
double evaluate(const LoopModel& model, EquilibriumWorkspace& ws, const EquilibriumState& state, bool with_jacobian) {
  deformed_geometry(model, state.deformations, ws.deformed);
  compute_chain(ws.deformed, state.theta, ws.chain);
  double energy = 0.0;
  for (int k = 0; k < model.deformation_count(); ++k) {
    energy += 0.5 * model.deformation_stiffness(k) * state.deformations[k] * state.deformations[k];
  }
  if (with_jacobian) residual_jacobian(ws.chain, model.unknown_elements(), ws.jacobian);
  return energy;
}

// Gradient of the Lagrangian f + lambda^T c with respect to the unknowns.
void lagrangian_gradient(const LoopModel& model, EquilibriumWorkspace& ws, const EquilibriumState& s) {
  ws.gradient.noalias() = ws.jacobian.transpose() * s.multipliers;
  for (int u = 0; u < model.unknown_count(); ++u) {
    const int k = model.unknown_deformation(u);
    if (k >= 0) ws.gradient[u] += model.deformation_stiffness(k) * s.deformations[k];
  }
}

// Moves `from` by `scale * step` (unknowns) and `scale * dual` (multipliers) into `to`.
void take_step(const LoopModel& model, const EquilibriumState& from, const UnknownVector& step, const Vector6& dual,
               double scale, EquilibriumState& to) {
  to.theta = from.theta;
  to.deformations = from.deformations;
  for (int u = 0; u < model.unknown_count(); ++u) {
    const int k = model.unknown_deformation(u);
    if (k >= 0) {
      to.deformations[k] += scale * step[u];
    } else {
      to.theta[model.unknown_joint(u)] += scale * step[u];
    }
  }
  to.multipliers = from.multipliers + scale * dual;
}

bool finite(const EquilibriumState& s) {
  return s.theta.allFinite() && s.deformations.allFinite() && s.multipliers.allFinite();
}

}  // namespace

const char* to_string(Compliance compliance) {
  switch (compliance) {
    case Compliance::paper:
      return "paper";
    case Compliance::full:
      return "full";
  }
  return "unknown";
}

Compliance compliance_from_string(const std::string& text) {
  if (text == "paper") return Compliance::paper;
  if (text == "full") return Compliance::full;
  fail("compliance: expected 'paper' or 'full', got '" + text + "'");
}

const char* to_string(SolveStatus status) {
  switch (status) {
    case SolveStatus::converged:
      return "converged";
    case SolveStatus::max_iterations:
      return "max_iterations";
    case SolveStatus::line_search_failed:
      return "line_search_failed";
    case SolveStatus::singular:
      return "singular";
    case SolveStatus::non_finite:
      return "non_finite";
  }
  return "unknown";
}

void EquilibriumOptions::validate() const {
  if (!(torsion_stiffness_ratio > 0.0) || !std::isfinite(torsion_stiffness_ratio)) {
    fail("torsion_stiffness_ratio: must be a finite number > 0, got " + std::to_string(torsion_stiffness_ratio));
  }
  if (!(closure_tolerance > 0.0) || !std::isfinite(closure_tolerance)) {
    fail("closure_tolerance: must be a finite number > 0, got " + std::to_string(closure_tolerance));
  }
  if (!(stationarity_tolerance > 0.0) || !std::isfinite(stationarity_tolerance)) {
    fail("stationarity_tolerance: must be a finite number > 0, got " + std::to_string(stationarity_tolerance));
  }
  if (max_iterations < 1) fail("max_iterations: must be >= 1, got " + std::to_string(max_iterations));
}

LoopModel::LoopModel(const LoopGeometry& geometry, const EquilibriumOptions& options)
    : geometry_(geometry), options_(options) {
  validate_geometry(geometry);
  options.validate();
  const int n = geometry.joints();
  if (options.input_joint < 0 || options.input_joint >= n) {
    fail("input_joint: must be in [0, " + std::to_string(n - 1) + "], got " + std::to_string(options.input_joint));
  }
  length_scale_ = loopfarm::length_scale(geometry);
  normalized_ = scaled(geometry, length_scale_);

  // Deformation slots, grouped by kind: a, alpha, then d for the full set.
  const bool full = options.compliance == Compliance::full;
  deformation_count_ = (full ? 3 : 2) * n;
  for (int i = 0; i < n; ++i) {
    deformation_element_[i] = chain_index(i, ChainParameter::a);
    deformation_stiffness_[i] = 1.0;
    deformation_element_[n + i] = chain_index(i, ChainParameter::alpha);
    deformation_stiffness_[n + i] = options.torsion_stiffness_ratio;
    if (full) {
      deformation_element_[2 * n + i] = chain_index(i, ChainParameter::d);
      deformation_stiffness_[2 * n + i] = 1.0;
    }
  }
  // Unknowns in ascending chain order: the Hessian routine walks the chain.
  unknown_count_ = 0;
  for (int e = 0; e < kElementsPerJoint * n; ++e) {
    const int joint = e / kElementsPerJoint;
    const auto kind = static_cast<ChainParameter>(e % kElementsPerJoint);
    int slot = -1;
    for (int k = 0; k < deformation_count_; ++k) {
      if (deformation_element_[k] == e) slot = k;
    }
    const bool passive_angle = kind == ChainParameter::theta && joint != options.input_joint;
    if (!passive_angle && slot < 0) continue;
    unknown_element_[unknown_count_] = e;
    unknown_deformation_[unknown_count_] = slot;
    unknown_joint_[unknown_count_] = passive_angle ? joint : -1;
    ++unknown_count_;
  }
  // The Hessian's elements: the unknowns with the input joint's angle slotted
  // in at its place in the chain.
  const int input_element = chain_index(options.input_joint, ChainParameter::theta);
  int row = 0;
  for (int u = 0; u < unknown_count_; ++u) {
    if (row == u && unknown_element_[u] > input_element) {
      input_hessian_index_ = row;
      hessian_element_[row++] = input_element;
    }
    unknown_hessian_index_[u] = row;
    hessian_element_[row++] = unknown_element_[u];
  }
  if (row == unknown_count_) {
    input_hessian_index_ = row;
    hessian_element_[row] = input_element;
  }
}

EquilibriumState EquilibriumState::at_angles(const LoopModel& model, const JointVector& theta) {
  if (theta.size() != model.joints()) {
    fail("theta: expected " + std::to_string(model.joints()) + " joint angles, got " + std::to_string(theta.size()));
  }
  EquilibriumState s;
  s.theta = theta;
  s.deformations = DeformationVector::Zero(model.deformation_count());
  s.multipliers.setZero();
  return s;
}

EquilibriumWorkspace::EquilibriumWorkspace(const LoopModel& model) {
  const int m = model.unknown_count();
  chain_hessian.resize(m, m);
  hessian.resize(m, m);
  normal.resize(m, m);
  jacobian.resize(6, m);
  solved.resize(m, 8);
  gradient.resize(m);
  step.resize(m);
  scratch.resize(m);
  trial = EquilibriumState::at_angles(model, JointVector::Zero(model.joints()));
  theta = JointVector::Zero(model.joints());
  deformed = model.normalized_geometry();
}

void deformed_geometry(const LoopModel& model, const DeformationVector& deformations, LoopGeometry& out) {
  // The slots are grouped by kind (LoopModel's constructor): a_1..a_n, then
  // alpha_1..alpha_n, then, for the full set, d_1..d_n.
  const LoopGeometry& g = model.normalized_geometry();
  const int n = model.joints();
  out.a = g.a + deformations.head(n);
  out.alpha = g.alpha + deformations.segment(n, n);
  if (model.deformation_count() == 3 * n) {
    out.d = g.d + deformations.segment(2 * n, n);
  } else {
    out.d = g.d;
  }
}

double physical_deformation(const LoopModel& model, const DeformationVector& deformations, int k) {
  const auto kind = static_cast<ChainParameter>(model.deformation_element(k) % kElementsPerJoint);
  return kind == ChainParameter::alpha ? deformations[k] : deformations[k] * model.length_scale();
}

std::string deformation_name(const LoopModel& model, int k) {
  const int e = model.deformation_element(k);
  const std::string joint = std::to_string(e / kElementsPerJoint + 1);
  switch (static_cast<ChainParameter>(e % kElementsPerJoint)) {
    case ChainParameter::a:
      return "a" + joint;
    case ChainParameter::alpha:
      return "alpha" + joint;
    case ChainParameter::d:
      return "d" + joint;
    case ChainParameter::theta:
      break;
  }
  return "theta" + joint;
}

namespace {

// Inner products of the solved columns [Y | z | L^-1 b] with Y's six (the
// rest of their Gram matrix is never used): rows 0-5 are YᵀY, row 6 is zᵀY,
// row 7 is (L^-1 b)ᵀY.
using SolvedGram = Eigen::Matrix<double, 8, 6>;

// x <- L^-1 x for a factor from dense::cholesky_in_place (inverted diagonal).
template <class Matrix, class Vector>
void solve_lower_vector(const Matrix& lower, int n, Vector& x) {
  for (int i = 0; i < n; ++i) {
    double sum = x[i];
    for (int k = 0; k < i; ++k) sum -= lower(i, k) * x[k];
    x[i] = sum * lower(i, i);
  }
}

// The Cholesky factor of the 6 x 6 Schur complement A H^-1 Aᵀ (+ mu I), with
// the solver's own kernels (dense::cholesky_in_place, compiled for size 6):
// Eigen's LLT runs its general unblocked loop at this fixed size, which a
// profile put at 8 % of a generic cycle's time (perf record on
// loopfarm_bench --benchmark_filter='Cycle_Generic/32$').
class SchurFactor {
 public:
  // False where the matrix is not positive definite.
  bool compute(const Matrix6& schur) {
    factor_ = schur;
    return dense::cholesky_in_place(factor_, 6);
  }
  // (L Lᵀ)^-1 b.
  Vector6 solve(const Vector6& b) const {
    Vector6 x = b;
    solve_lower_vector(factor_, 6, x);
    dense::solve_lower_transposed(factor_, 6, x);
    return x;
  }

 private:
  Matrix6 factor_;
};

// AᵀA, lower triangle, into ws.normal.
void normal_matrix(const LoopModel& model, EquilibriumWorkspace& ws) {
  const int m = model.unknown_count();
  for (int j = 0; j < m; ++j) {
    for (int i = j; i < m; ++i) ws.normal(i, j) = ws.jacobian.col(i).dot(ws.jacobian.col(j));
  }
}

// Factorises H = W + sigma AᵀA + rho I in place in ws.hessian (W with the
// constraint curvature from ws.chain_hessian if `curvature`, else the springs'
// stiffness alone). False if H is not positive definite.
bool factor_hessian(const LoopModel& model, EquilibriumWorkspace& ws, double sigma, bool curvature, double rho) {
  const int m = model.unknown_count();
  // Lower triangle only: that is all the factorisation reads.
  for (int j = 0; j < m; ++j) {
    for (int i = j; i < m; ++i) {
      const double w =
          curvature ? ws.chain_hessian(model.unknown_hessian_index(i), model.unknown_hessian_index(j)) : 0.0;
      ws.hessian(i, j) = w + sigma * ws.normal(i, j);
    }
    const int k = model.unknown_deformation(j);
    ws.hessian(j, j) += rho + (k >= 0 ? model.deformation_stiffness(k) : 0.0);
  }
  return dense::cholesky_in_place(ws.hessian, m);
}

// With H = L Lᵀ from factor_hessian: ws.solved = L^-1 [Aᵀ | g | b], b = d g /
// d theta_in (the Hessian's input-joint column, zero unless `curvature`; it
// rides along in the SIMD-wide solve for the path tangent), and `gram` their
// products with Y = L^-1 Aᵀ: its 6 x 6 block is the Schur complement
// A H^-1 Aᵀ = YᵀY, rows 6 and 7 hold (Yᵀ L^-1 g)ᵀ and (Yᵀ L^-1 b)ᵀ.
void solve_columns(const LoopModel& model, EquilibriumWorkspace& ws, const UnknownVector& g, bool curvature,
                   SolvedGram& gram) {
  const int m = model.unknown_count();
  ws.solved.leftCols<6>() = ws.jacobian.transpose();
  ws.solved.col(6) = g;
  for (int u = 0; u < m; ++u) {
    ws.solved(u, 7) = curvature ? ws.chain_hessian(model.unknown_hessian_index(u), model.input_hessian_index()) : 0.0;
  }
  dense::solve_lower_rows(ws.hessian, m, ws.solved);
  gram.setZero();
  for (int u = 0; u < m; ++u) {
    const Eigen::Matrix<double, 1, 8> row = ws.solved.row(u);
    gram.noalias() += row.transpose() * row.head<6>();
  }
}

// The path tangent t from its components in unknown order (`unknowns`) and
// its multiplier part `dual`; d theta_in / d theta_in = 1. False if any is
// not finite.
bool tangent_from_unknowns(const LoopModel& model, const EquilibriumState& x, const UnknownVector& unknowns,
                           const Vector6& dual, EquilibriumState& t) {
  t.theta.setZero(x.theta.size());
  t.theta[model.options().input_joint] = 1.0;
  t.deformations.setZero(x.deformations.size());
  for (int u = 0; u < model.unknown_count(); ++u) {
    const int k = model.unknown_deformation(u);
    if (k >= 0) {
      t.deformations[k] = unknowns[u];
    } else {
      t.theta[model.unknown_joint(u)] = unknowns[u];
    }
  }
  t.multipliers = dual;
  return t.theta.allFinite() && t.deformations.allFinite() && t.multipliers.allFinite();
}

// The tangent of the equilibrium path, d(x, lambda)/d theta_in, from
// differentiating the KKT conditions: [W Aᵀ; A 0] [dx; dl] = -[b; c_t] with
// b = d g / d theta_in and c_t = d c / d theta_in. Solved with the last Newton
// step's factorisation (H = W + sigma AᵀA = L Lᵀ, `gram` holding its solved
// columns), the same elimination as the step: W is that of the previous
// iterate, which is all a predictor needs.
bool path_tangent(const LoopModel& model, EquilibriumWorkspace& ws, const EquilibriumState& x, const SolvedGram& gram,
                  const SchurFactor& schur_factor, double sigma, EquilibriumState& t) {
  const int m = model.unknown_count();
  const int input = model.options().input_joint;
  const Vector6 c_t = residual_derivative(ws.chain, chain_index(input, ChainParameter::theta));
  Vector6 dual = schur_factor.solve(c_t - gram.row(7).transpose());
  for (int u = 0; u < m; ++u) ws.scratch[u] = ws.solved(u, 7) + ws.solved.row(u).head<6>().dot(dual);
  ws.scratch = -ws.scratch;
  dense::solve_lower_transposed(ws.hessian, m, ws.scratch);
  dual -= sigma * c_t;  // the shift the sigma AᵀA term makes, as in the step
  return tangent_from_unknowns(model, x, ws.scratch, dual, t);
}

// The Newton step where the Hessian of the Lagrangian is the springs' alone,
// W = blockdiag(0, K) on (passive angles q, deformations delta), as it is
// wherever the multipliers are negligible (on every movable loop, the ones
// the search is after), or that plus rho I (a Gauss-Newton step). With
// K_rho = K + rho I, the stabilised KKT system
//
//     [rho I  0      A_qᵀ ] [dq]   [r_q]
//     [0      K_rho  A_dᵀ ] [dd] = [r_d]
//     [A_q    A_d    -mu I] [dl]   [r_c]
//
// reduces, K being diagonal, to two small positive definite systems: with
// S = A_d K_rho^-1 A_dᵀ + mu I (6 x 6) and q = A_d K_rho^-1 r_d - r_c,
// S dl = A_q dq + q, and (rho I + A_qᵀ S^-1 A_q) dq = r_q - A_qᵀ S^-1 q (n - 1
// square); then dd = K_rho^-1 (r_d - A_dᵀ dl). Exactly the step the general
// path computes through the m x m matrix H = W + sigma AᵀA + rho I (m = 11
// for a 4R loop), at a fraction of its cost: no m x m factorisation, no
// m-row solves.
struct StructuredFactors {
  Matrix6 constraint;  // S = L_S L_Sᵀ, factor with inverted diagonal
  // Y = L_S^-1 A_q in the first `passive` columns (row-major and 8 wide, so
  // that the triangular solve runs on whole rows).
  Eigen::Matrix<double, 6, 8, Eigen::RowMajor> solved_passive;
  Eigen::Matrix<double, kMaxJoints - 1, kMaxJoints - 1> passive;  // rho I + YᵀY = L_M L_Mᵀ, factor
  int passive_count = 0;
  double rho = 0.0;
};
static_assert(kMaxJoints - 1 <= 8, "the passive angles' columns fit the 8-wide rows");

// Cholesky in place (dense::cholesky_in_place) of a matrix whose diagonal
// was shifted by `shift` (the dual regularisation mu), which also refuses a
// pivot less than `shift` above kStructuredPivotRatio of its diagonal entry:
// the conditioning judged is the unshifted matrix's. (A direction that only
// the shift makes positive is one the general path handles through the
// passive angles' columns; solving it here with the shift alone, up to
// 1e-6, changes the iterates: on the kite of the stability tests at an
// unreachable input angle it made the assembly converge where the general
// path does not.)
template <class Matrix>
bool well_conditioned_cholesky(Matrix& a, int n, double shift) {
  std::array<double, 8> diagonal{};
  for (int i = 0; i < n; ++i) diagonal[static_cast<size_t>(i)] = a(i, i);
  if (!dense::cholesky_in_place(a, n)) return false;
  for (int i = 0; i < n; ++i) {
    // a(i, i) now holds 1 / L(i, i): the pivot is L(i, i)^2.
    const double pivot = 1.0 / (a(i, i) * a(i, i));
    if (!(pivot - shift >= kStructuredPivotRatio * (diagonal[static_cast<size_t>(i)] - shift))) return false;
  }
  return true;
}

// Factors S and rho I + A_qᵀ S^-1 A_q from the workspace's closure Jacobian.
// False where either is not well conditioned, or there are more passive
// angles than closure equations (n = 8: A_qᵀ S^-1 A_q is singular).
bool factor_structured(const LoopModel& model, const EquilibriumWorkspace& ws, double mu, double rho,
                       StructuredFactors& f) {
  const int m = model.unknown_count();
  const int passive = model.joints() - 1;
  if (passive > 6) return false;
  f.passive_count = passive;
  f.rho = rho;
  // Lower triangles only: all that the factorisations read. Written out
  // (fixed 6 x 6 loops the compiler unrolls): Eigen's products of these
  // dynamic-width blocks dispatch at run time, which cost more than the sums.
  Matrix6& S = f.constraint;
  S.setZero();
  int column = 0;
  for (int u = 0; u < m; ++u) {
    const int k = model.unknown_deformation(u);
    const auto a = ws.jacobian.col(u);
    if (k < 0) {
      f.solved_passive.col(column++) = a;
      continue;
    }
    const double compliance = 1.0 / (model.deformation_stiffness(k) + rho);
    for (int j = 0; j < 6; ++j) {
      const double scaled = compliance * a[j];
      for (int i = j; i < 6; ++i) S(i, j) += scaled * a[i];
    }
  }
  S.diagonal().array() += mu;
  if (!well_conditioned_cholesky(S, 6, mu)) return false;
  dense::solve_lower_rows(S, 6, f.solved_passive);
  for (int j = 0; j < passive; ++j) {
    for (int i = j; i < passive; ++i) f.passive(i, j) = f.solved_passive.col(i).dot(f.solved_passive.col(j));
    f.passive(j, j) += rho;
  }
  // rho judged as a shift too: where only it makes the passive block definite
  // (the passive angles' columns dependent), the general path takes over.
  return well_conditioned_cholesky(f.passive, passive, rho);
}

// Solves the structured system above for the right-hand side (r_q, r_d, r_c)
// given in unknown order in `rhs` and `r_c`: the step in `step` (unknown
// order), the multiplier step in `dual`.
void solve_structured(const LoopModel& model, const EquilibriumWorkspace& ws, const StructuredFactors& f,
                      const UnknownVector& rhs, const Vector6& r_c, UnknownVector& step, Vector6& dual) {
  const int m = model.unknown_count();
  const int passive = f.passive_count;
  Vector6 z = -r_c;
  for (int u = 0; u < m; ++u) {
    const int k = model.unknown_deformation(u);
    if (k >= 0) z += (rhs[u] / (model.deformation_stiffness(k) + f.rho)) * ws.jacobian.col(u);
  }
  solve_lower_vector(f.constraint, 6, z);  // z = L_S^-1 q
  // (rho I + YᵀY) dq = r_q - Yᵀ z.
  Eigen::Matrix<double, kMaxJoints - 1, 1> dq;
  for (int u = 0, i = 0; u < m; ++u) {
    if (model.unknown_deformation(u) < 0) {
      dq[i] = rhs[u] - f.solved_passive.col(i).dot(z);
      ++i;
    }
  }
  solve_lower_vector(f.passive, passive, dq);
  auto dq_head = dq.head(passive);
  dense::solve_lower_transposed(f.passive, passive, dq_head);
  // dl = L_S^-ᵀ (Y dq + z).
  dual = z;
  for (int i = 0; i < passive; ++i) dual += dq[i] * f.solved_passive.col(i);
  dense::solve_lower_transposed(f.constraint, 6, dual);
  for (int u = 0, i = 0; u < m; ++u) {
    const int k = model.unknown_deformation(u);
    step[u] = k >= 0 ? (rhs[u] - ws.jacobian.col(u).dot(dual)) / (model.deformation_stiffness(k) + f.rho) : dq[i++];
  }
}

// The path tangent (as path_tangent) from the structured factors of the last
// step: b = 0 (no curvature), so the right-hand side is (0, 0, -c_t).
bool structured_path_tangent(const LoopModel& model, EquilibriumWorkspace& ws, const EquilibriumState& x,
                             const StructuredFactors& f, EquilibriumState& t) {
  const int m = model.unknown_count();
  const int input = model.options().input_joint;
  const Vector6 c_t = residual_derivative(ws.chain, chain_index(input, ChainParameter::theta));
  UnknownVector rhs = UnknownVector::Zero(m);
  Vector6 dual;
  solve_structured(model, ws, f, rhs, -c_t, ws.scratch, dual);
  return tangent_from_unknowns(model, x, ws.scratch, dual, t);
}

// The simplified Newton step: the KKT system of the last exact general step
// (its factor L of H in ws.hessian, Y = L^-1 Aᵀ in ws.solved, the Schur
// complement's factor) solved for the current gradient g (ws.gradient) and
// residual c, the same elimination as the full step. From an iterate within
// e of the solution whose factorisation is d away, the error falls to about
// d e instead of e^2: one such step after a full one takes a continuation
// solve from 1e-10 to round-off, at the cost of three triangular solves.
void simplified_step(const LoopModel& model, EquilibriumWorkspace& ws, const SchurFactor& schur_factor, double sigma,
                     const Vector6& c, Vector6& dual, double& step_curvature) {
  const int m = model.unknown_count();
  ws.scratch = ws.gradient;
  solve_lower_vector(ws.hessian, m, ws.scratch);  // z = L^-1 g
  Vector6 yz = Vector6::Zero();                   // Yᵀ z
  for (int u = 0; u < m; ++u) yz += ws.scratch[u] * ws.solved.row(u).head<6>().transpose();
  dual = schur_factor.solve(c - yz);
  for (int u = 0; u < m; ++u) ws.scratch[u] += ws.solved.row(u).head<6>().dot(dual);
  step_curvature = ws.scratch.squaredNorm();
  ws.step = -ws.scratch;
  dense::solve_lower_transposed(ws.hessian, m, ws.step);
  dual -= sigma * c;  // the augmentation's shift, as in the full step
}

}  // namespace

EquilibriumSummary solve_equilibrium(const LoopModel& model, EquilibriumWorkspace& ws, double theta_in,
                                     const EquilibriumState& guess, const SolveLimits& limits) {
  const int m = model.unknown_count();
  const EquilibriumOptions& opt = model.options();
  EquilibriumSummary summary;
  EquilibriumState& x = summary.state;
  x.theta = guess.theta;
  x.deformations = guess.deformations;
  x.multipliers = guess.multipliers;
  x.theta[opt.input_joint] = theta_in;

  double sigma = kInitialAugmentation;  // augmentation weight, grows only when needed
  double rho_last = 0.0;                // last primal regularisation that worked
  double merit_weight = 0.0;            // nu of the merit function, nondecreasing
  double sigma_last = sigma;            // sigma of the last factorisation

  double energy = evaluate(model, ws, x, true);
  ++summary.residual_evaluations;
  SchurFactor schur_factor;
  // Gram matrix of the solved columns [L^-1 Aᵀ | L^-1 g | L^-1 b] (below);
  // kept with the factorisation for the path tangent.
  SolvedGram gram;
  bool last_step_exact = false;         // the last factorisation holds the exact Hessian
  bool last_step_gauss_newton = false;  // the last step fell back to the Gauss-Newton model
  bool last_step_structured = false;    // the last step was the structured one (factors below)
  StructuredFactors structured_factors;
  bool reusable_factorization = false;  // a simplified step may reuse the last factorisation
  bool last_step_simplified = false;
  double last_kkt_residual = 0.0;  // at the start of the last iteration

  for (;;) {
    const Vector6 c = ws.chain.residual;
    lagrangian_gradient(model, ws, x);
    summary.energy = energy;
    summary.closure_residual = max_abs(c);
    summary.stationarity = m > 0 ? ws.gradient.cwiseAbs().maxCoeff() : 0.0;
    if (!std::isfinite(energy) || !c.allFinite() || !std::isfinite(summary.stationarity) || !finite(x)) {
      summary.status = SolveStatus::non_finite;
      break;
    }
    const bool at_tolerance =
        summary.closure_residual <= opt.closure_tolerance && summary.stationarity <= opt.stationarity_tolerance;
    const bool at_stepping_tolerance = summary.iterations > 0 &&
                                       summary.closure_residual <= limits.stepping_tolerance &&
                                       summary.stationarity <= limits.stepping_tolerance;
    if (at_tolerance || at_stepping_tolerance) {
      summary.status = SolveStatus::converged;
      if (summary.iterations > 0 && last_step_exact) {
        summary.has_tangent = last_step_structured
                                  ? structured_path_tangent(model, ws, x, structured_factors, summary.tangent)
                                  : path_tangent(model, ws, x, gram, schur_factor, sigma_last, summary.tangent);
      }
      break;
    }
    if (summary.iterations >= (limits.max_iterations > 0 ? limits.max_iterations : opt.max_iterations)) {
      summary.status = SolveStatus::max_iterations;
      break;
    }
    ++summary.iterations;

    const double kkt_residual = std::max(summary.closure_residual, summary.stationarity);
    // Hessian of the Lagrangian: constraint curvature weighted by the
    // multipliers, plus the springs' stiffness on the deformations.
    // Where the multipliers are negligible (a loop that closes without
    // deforming, as every movable one does) so is the curvature term: the
    // Hessian is K alone, to a relative 1e-9 that leaves the convergence
    // quadratic at these tolerances, and the chain's second derivatives
    // are skipped.
    const bool curvature = max_abs(x.multipliers) > kNegligibleMultiplier;
    Vector6 dual;
    double step_curvature = 0.0;  // stepᵀ H step, for the merit's weight
    bool structured = false;
    // Simplified Newton: close to the solution the last exact factorisation
    // still gives a step that gains many digits (simplified_step), without
    // the constraint curvature, the factorisation and the solves for Y. Used
    // while the residual is small and each such step shrinks it by
    // kSimplifiedContraction; a step that fails that, or the line search,
    // hands back to the full step.
    // Not where the multipliers are negligible: there the structured step is
    // as cheap and converges quadratically (on the Bennett cycle simplified
    // steps took 776 iterations instead of 504).
    const bool simplified = opt.simplified_newton && reusable_factorization && kkt_residual <= kSimplifiedResidual &&
                            curvature &&
                            !(last_step_simplified && kkt_residual > kSimplifiedContraction * last_kkt_residual);
    last_kkt_residual = kkt_residual;
    last_step_simplified = simplified;
    if (simplified) {
      ++summary.simplified_steps;
      simplified_step(model, ws, schur_factor, sigma_last, c, dual, step_curvature);
    } else {
      if (curvature) residual_hessian(ws.chain, x.multipliers, model.hessian_elements(), ws.chain_hessian);
      // Stabilised SQP: a dual regularisation proportional to the KKT residual
      // keeps the step defined where the closure Jacobian loses rank, and
      // vanishes at the solution so that convergence stays quadratic.
      const double mu = std::clamp(kkt_residual * kkt_residual, kMinDualRegularization, kMaxDualRegularization);

      // Solve [H Aᵀ; A -mu I] [dx; dl] = -[g; c] with H = W + sigma AᵀA + rho I.
      // First choice, rho = 0: the exact Newton step. Adding sigma AᵀA leaves dx
      // unchanged (A dx = -c) and makes H positive definite wherever W is so on
      // the null space of A (the second-order condition); Cholesky then
      // certifies it, sigma growing a little where needed. Far from a minimum W
      // is indefinite on that null space and no sigma helps; then the
      // Gauss-Newton model, which keeps only the springs' stiffness K, gives a
      // least-norm projection step towards closure, defined once a small rho
      // covers the passive angles (K has no block for them).
      //
      // Where W is the springs' alone, W = blockdiag(0, K) (negligible
      // multipliers: every movable loop) or blockdiag(rho I, K + rho I) (a
      // Gauss-Newton step), the structured step (above) gives the same step
      // through two small systems, where they are well conditioned. It
      // reproduces sigma's shift of the multipliers too: the general path takes
      // dl = dl' - sigma c from the augmented system, which is the solution of
      // the unaugmented [W Aᵀ; A -mu' I] [dx; nu] = -[g; c s], s = 1 / (1 +
      // sigma mu), mu' = mu s, as dl = s (nu + sigma c) - sigma c. (Solving the
      // plain system with mu instead changes the iterates by O(mu); where a
      // solve is far from converging, mu = 1e-6, that sent the stability tests'
      // kite at an unreachable input angle elsewhere.)
      bool exact = true;
      double rho = 0.0;
      // sigma's shrink factor s = 1 / (1 + sigma mu), set with the structured
      // factorisation it belongs to and used by its step below (sigma does not
      // change once that factorisation succeeds).
      double shrink = 1.0;
      auto try_structured = [&](double regularization) {
        shrink = 1.0 / (1.0 + sigma * mu);
        return opt.structured_step && factor_structured(model, ws, mu * shrink, regularization, structured_factors);
      };
      structured = !curvature && try_structured(0.0);
      bool factored = structured;
      if (!structured) {
        normal_matrix(model, ws);
        // H is positive definite for a sigma only if it is so for every larger
        // one (sigma AᵀA is positive semidefinite). After a Gauss-Newton step the
        // exact Hessian was indefinite on the null space of A, which no sigma
        // cures, and usually still is (a landing after a fold takes tens of such
        // steps): one factorisation at the largest sigma tells, where the ladder
        // would fail at every rung. The sigma chosen is the one the ladder alone
        // would choose, so the iterates do not change; over the bench's generic
        // cycles this saves a third of the factorisations.
        const bool hopeless = last_step_gauss_newton && sigma < kMaxAugmentation &&
                              !factor_hessian(model, ws, kMaxAugmentation, curvature, 0.0);
        for (double trial_sigma = sigma; !hopeless && trial_sigma <= kMaxAugmentation && !factored;
             trial_sigma *= 10.0) {
          sigma = trial_sigma;
          factored = factor_hessian(model, ws, sigma, curvature, 0.0);
        }
      }
      if (!factored) {
        sigma = kInitialAugmentation;
        exact = false;
        if (limits.max_gauss_newton_steps >= 0 && summary.gauss_newton_steps >= limits.max_gauss_newton_steps) {
          summary.status = SolveStatus::max_iterations;
          break;
        }
        ++summary.gauss_newton_steps;
        rho = std::max(kMinRegularization, rho_last / 4.0);
        structured = try_structured(rho);
        factored = structured;
        for (; !structured && rho <= kMaxRegularization && !factored; rho *= 10.0) {
          factored = factor_hessian(model, ws, sigma, false, rho);
          if (factored) break;
        }
      }
      if (!factored) {
        summary.status = SolveStatus::singular;
        break;
      }
      rho_last = rho;
      last_step_gauss_newton = !exact;
      last_step_exact = exact;
      last_step_structured = structured;
      sigma_last = sigma;
      summary.max_regularization = std::max(summary.max_regularization, rho);

      if (structured) {
        ++summary.structured_steps;
        const double s = shrink;
        ws.scratch = -ws.gradient;
        solve_structured(model, ws, structured_factors, ws.scratch, -s * c, ws.step, dual);
        dual = s * (dual + sigma * c) - sigma * c;
        // stepᵀ (W + rho I) step; sigma |A step|^2 is added below, once A step
        // is known. The general path reads the whole stepᵀ H step off its
        // factorisation.
        step_curvature = rho * ws.step.squaredNorm();
        for (int u = 0; u < m; ++u) {
          const int k = model.unknown_deformation(u);
          if (k >= 0) step_curvature += model.deformation_stiffness(k) * ws.step[u] * ws.step[u];
        }
      } else {
        // With H = L Lᵀ, Y = L^-1 Aᵀ and z = L^-1 g: the Schur complement
        // A H^-1 Aᵀ is YᵀY, and the step -H^-1 (g + Aᵀ dl) is -L^-ᵀ (z + Y dl).
        solve_columns(model, ws, ws.gradient, exact && curvature, gram);
        ws.schur = gram.topLeftCorner<6, 6>();
        ws.schur.diagonal().array() += mu;
        if (!schur_factor.compute(ws.schur)) {
          summary.status = SolveStatus::singular;
          break;
        }
        dual = schur_factor.solve(c - gram.row(6).transpose());
        for (int u = 0; u < m; ++u) ws.scratch[u] = ws.solved(u, 6) + ws.solved.row(u).head<6>().dot(dual);
        step_curvature = ws.scratch.squaredNorm();
        ws.step = -ws.scratch;
        dense::solve_lower_transposed(ws.hessian, m, ws.step);
        // The sigma AᵀA term leaves dx the Newton step but shifts the multiplier
        // step: W dx + Aᵀ(dl - sigma c) = -g when A dx = -c (exactly so for mu = 0).
        // Undo the shift, or the multipliers (and with them x) converge only
        // linearly.
        dual -= sigma * c;
      }
      // The next step may reuse this factorisation if it is the exact
      // Hessian's, with Y and the Schur complement's factor (the general path).
      reusable_factorization = exact && !structured;
    }
    if (!ws.step.allFinite() || !dual.allFinite()) {
      summary.status = SolveStatus::non_finite;
      break;
    }

    // Merit: augmented Lagrangian f + l+ᵀc + nu/2 |c|^2 with the new
    // multipliers l+ = l + dl; nu grows until the step is a descent direction.
    const Vector6 lambda_plus = x.multipliers + dual;
    Vector6 jacobian_step = ws.jacobian * ws.step;
    if (structured) step_curvature += sigma * jacobian_step.squaredNorm();
    double energy_slope = 0.0;
    for (int u = 0; u < m; ++u) {
      const int k = model.unknown_deformation(u);
      if (k >= 0) energy_slope += model.deformation_stiffness(k) * x.deformations[k] * ws.step[u];
    }
    const double slope0 = energy_slope + lambda_plus.dot(jacobian_step);
    const double slope1 = c.dot(jacobian_step);
    merit_weight = std::max(merit_weight, 1.0);
    if (slope0 + merit_weight * slope1 > -0.1 * step_curvature && slope1 < 0.0) {
      merit_weight = std::max(merit_weight, (slope0 + 0.1 * step_curvature) / -slope1 * 2.0);
    }
    const double slope = slope0 + merit_weight * slope1;
    const double merit0 = energy + lambda_plus.dot(c) + 0.5 * merit_weight * c.squaredNorm();

    // Cap the step: a Newton step of more than about a radian only happens far
    // from the solution, where its length means nothing.
    const double step_norm = ws.step.cwiseAbs().maxCoeff();
    double alpha = step_norm > kMaxStep ? kMaxStep / step_norm : 1.0;
    bool accepted = false;
    for (int backtrack = 0; backtrack < kMaxBacktracks; ++backtrack) {
      take_step(model, x, ws.step, dual, alpha, ws.trial);
      const double trial_energy = evaluate(model, ws, ws.trial, false);
      ++summary.residual_evaluations;
      const Vector6& tc = ws.chain.residual;
      const double merit = trial_energy + lambda_plus.dot(tc) + 0.5 * merit_weight * tc.squaredNorm();
      // The slack admits steps whose change of merit is lost in round-off, as
      // the last steps of a solve with nonzero energy are: the energy and
      // lambᵀc (c is O(1) in normalised units) are only known to that level.
      const double slack = 10.0 * std::numeric_limits<double>::epsilon() * (std::abs(merit0) + lambda_plus.lpNorm<1>());
      if (std::isfinite(merit) && merit <= merit0 + kArmijo * alpha * std::min(slope, 0.0) + slack) {
        accepted = true;
        energy = trial_energy;
        break;
      }
      alpha *= 0.5;
    }
    if (!accepted) {
      // Restore the chain at x. A simplified step's direction is only as
      // good as its old factorisation: the full step takes over. Otherwise
      // stop: no step along this direction helps.
      energy = evaluate(model, ws, x, true);
      ++summary.residual_evaluations;
      if (simplified) {
        reusable_factorization = false;
        continue;
      }
      lagrangian_gradient(model, ws, x);
      summary.energy = energy;
      summary.status = SolveStatus::line_search_failed;
      break;
    }
    std::swap(x, ws.trial);
    // The accepted trial point's chain is already in the workspace: only its
    // Jacobian columns are new.
    residual_jacobian(ws.chain, model.unknown_elements(), ws.jacobian);
  }

  for (int i = 0; i < model.joints(); ++i) x.theta[i] = wrap_angle(x.theta[i]);
  x.theta[opt.input_joint] = theta_in;
  return summary;
}

bool equilibrium_tangent(const LoopModel& model, EquilibriumWorkspace& ws, const EquilibriumState& solution,
                         EquilibriumState& tangent) {
  evaluate(model, ws, solution, true);
  lagrangian_gradient(model, ws, solution);
  residual_hessian(ws.chain, solution.multipliers, model.hessian_elements(), ws.chain_hessian);
  normal_matrix(model, ws);
  double sigma = kInitialAugmentation;
  bool factored = false;
  for (; sigma <= kMaxAugmentation && !factored; sigma *= 10.0) {
    factored = factor_hessian(model, ws, sigma, true, 0.0);
    if (factored) break;
  }
  if (!factored) return false;  // not a strict local minimum: no tangent to follow
  SolvedGram gram;
  solve_columns(model, ws, ws.gradient, true, gram);
  ws.schur = gram.topLeftCorner<6, 6>();
  ws.schur.diagonal().array() += kMinDualRegularization;
  SchurFactor schur_factor;
  if (!schur_factor.compute(ws.schur)) return false;
  return path_tangent(model, ws, solution, gram, schur_factor, sigma, tangent);
}

}  // namespace loopfarm
