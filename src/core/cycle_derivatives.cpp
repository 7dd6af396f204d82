// Implicit differentiation of a cycle (cycle.hpp): the gradient of the cycle
// energy by the envelope theorem, and the Jacobian of every sample's
// deformations with respect to the geometry from its KKT conditions.
#include "loopfarm/core/cycle.hpp"

#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "small_dense.hpp"

namespace loopfarm {
namespace {

// d normalised parameter / d parameter, D = diag(scale) - length dLᵀ:
// p~ = p / L(p) for the lengths a and d (scale 1 / L, length p / L^2), alpha
// unchanged (scale 1, length 0). Diagonal plus rank one, so it is applied in
// O(3n) per row without forming D.
class Normalization {
 public:
  explicit Normalization(const LoopModel& model) : dL_(length_scale_gradient(model.geometry())) {
    const LoopGeometry& g = model.geometry();
    const int n = g.joints();
    const double L = model.length_scale();
    scale_.setOnes(3 * n);
    length_.setZero(3 * n);
    for (int i = 0; i < n; ++i) {
      scale_[i] = 1.0 / L;
      scale_[2 * n + i] = 1.0 / L;
      length_[i] = g.a[i] / (L * L);
      length_[2 * n + i] = g.d[i] / (L * L);
    }
  }

  // v <- v D for a row vector v, which is v <- Dᵀ v for a column (a gradient).
  template <class Vector>
  void apply(Vector&& v) const {
    const int size = static_cast<int>(scale_.size());
    double along = 0.0;
    for (int i = 0; i < size; ++i) along += v(i) * length_[i];
    for (int j = 0; j < size; ++j) v(j) = v(j) * scale_[j] - along * dL_[j];
  }

  const GeometryVector& scale() const { return scale_; }
  const GeometryVector& length() const { return length_; }
  const GeometryVector& dL() const { return dL_; }

 private:
  GeometryVector dL_;
  GeometryVector scale_;
  GeometryVector length_;
};

// Chain element of geometric parameter j in GeometryVector order.
int parameter_element(int n, int j) {
  const int joint = j % n;
  switch (j / n) {
    case 0:
      return chain_index(joint, ChainParameter::a);
    case 1:
      return chain_index(joint, ChainParameter::alpha);
    default:
      return chain_index(joint, ChainParameter::d);
  }
}

// B <- L^-ᵀ B for a row-major B of n rows and a fixed number of columns, L
// from dense::cholesky_in_place (inverted diagonal): the back-substitution
// matching dense::solve_lower_rows, whole rows at a time (Eigen's fixed-width
// row operations, which vectorise where a plain loop over two rows of the
// same buffer was left scalar).
template <class Matrix, class Rows>
void solve_lower_transposed_rows(const Matrix& lower, int n, Rows& b) {
  static_assert(Rows::IsRowMajor && Rows::ColsAtCompileTime > 0, "row-major, fixed width");
  for (int i = n - 1; i >= 0; --i) {
    auto row = b.row(i);
    for (int k = i + 1; k < n; ++k) row -= lower(k, i) * b.row(k);
    row *= lower(i, i);
  }
}

// Augmentations sigma = 1, 10, ..., 1e11 tried for H = W + sigma AᵀA.
constexpr int kMaxSensitivityAugmentations = 12;

// W(i, j), the Hessian of the Lagrangian in unknowns i and j: the constraint
// curvature (`chain_hessian` over every chain element) and the springs.
double lagrangian_hessian(const LoopModel& model, const ChainMatrix& chain_hessian, int i, int j) {
  double h = chain_hessian(model.unknown_element(i), model.unknown_element(j));
  if (i == j) {
    const int k = model.unknown_deformation(j);
    if (k >= 0) h += model.deformation_stiffness(k);
  }
  return h;
}

// The sensitivity dx (unknowns x parameters) of a sample whose H = W +
// sigma AᵀA is positive definite for no sigma tried: W is then indefinite on
// the null space of A, the sample is no minimum (in practice a sample whose
// solve failed), and its sensitivity, still that of the KKT conditions at its
// state, comes from the whole KKT matrix [W Aᵀ; A 0] (rare: 13 of the 86,112
// samples differentiated in the default job's first 40 starts). Not inlined,
// so that its buffers take stack space only when it runs.
template <class ElementJacobian, class ParameterJacobian, class Sensitivity, size_t Parameters>
[[gnu::noinline]] void kkt_sensitivity(const LoopModel& model, const ChainMatrix& chain_hessian,
                                       const ElementJacobian& element_jacobian, const ParameterJacobian& Ap,
                                       const std::array<int, Parameters>& parameter, Sensitivity& dx) {
  constexpr int nu = Sensitivity::RowsAtCompileTime;
  constexpr int np = static_cast<int>(Parameters);
  using KktMatrix = Eigen::Matrix<double, nu + 6, nu + 6>;
  using KktRhs = Eigen::Matrix<double, nu + 6, np>;
  KktMatrix kkt = KktMatrix::Zero();
  KktRhs rhs;
  for (int c = 0; c < nu; ++c) {
    for (int r = 0; r < nu; ++r) kkt(r, c) = lagrangian_hessian(model, chain_hessian, r, c);
    const int ec = model.unknown_element(c);
    kkt.template block<6, 1>(nu, c) = element_jacobian.col(ec);
    kkt.template block<1, 6>(c, nu) = element_jacobian.col(ec).transpose();
    for (int p = 0; p < np; ++p) rhs(c, p) = -chain_hessian(ec, parameter[static_cast<size_t>(p)]);
  }
  rhs.template bottomRows<6>() = -Ap;
  const KktRhs solution = Eigen::FullPivLU<KktMatrix>(kkt).solve(rhs);
  dx = solution.template topRows<nu>();
}

// The implicit differentiation of every sample of a cycle of a loop of
// `Joints` joints with `Unknowns` unknowns (compile-time sizes: every buffer
// has a fixed size and every row a fixed width, which the compiler unrolls
// and vectorises; one instantiation per loop size and compliance): fills
// `jacobian` and, if not null, `angle_jacobian` (rows of the input joint
// left as they are).
//
// Each sample's KKT conditions are differentiated with respect to the 3n
// normalised parameters p~: [W Aᵀ; A 0] [dx; dl] = -[W_xp; A_p], W the
// Hessian of the Lagrangian in the unknowns, W_xp its mixed block with the
// parameters, A and A_p the closure Jacobians. Solved as a Newton step is,
// through H = W + sigma AᵀA = L Lᵀ (positive definite at a regular minimum;
// the right-hand side shifted by sigma Aᵀ A_p to match): with
// [B | C] = L^-1 [Aᵀ | -W_xp - sigma Aᵀ A_p], the Schur complement is
// A H^-1 Aᵀ = BᵀB, dl = (BᵀB)^-1 (BᵀC + A_p) and dx = L^-ᵀ (C - B dl).
// Buffers: fixed-size ones on the stack (about 7 kB for a 4R loop, 30 kB for
// 8 joints and full compliance); no heap allocation.
template <int Joints, int Unknowns>
void differentiate_cycle(const LoopModel& model, EquilibriumWorkspace& ws, const CycleSummary& summary,
                         Eigen::MatrixXd& jacobian, Eigen::MatrixXd* angle_jacobian) {
  constexpr int n = Joints;
  constexpr int nu = Unknowns;
  constexpr int np = 3 * Joints;  // parameters
  constexpr int width = 6 + np;   // [Aᵀ | right-hand sides]
  using Rows = Eigen::Matrix<double, nu, width, Eigen::RowMajor>;
  using ParameterRows = Eigen::Matrix<double, nu, np, Eigen::RowMajor>;
  using DualRows = Eigen::Matrix<double, 6, np, Eigen::RowMajor>;
  assert(model.joints() == Joints && model.unknown_count() == Unknowns);
  const int m = model.deformation_count();
  const int N = static_cast<int>(summary.samples.size());

  // Unknowns and parameters share chain elements, so one Hessian and one set
  // of residual derivatives over the whole chain give all four blocks.
  std::array<int, kElementsPerJoint * n> all{};
  for (int e = 0; e < kElementsPerJoint * n; ++e) all[static_cast<size_t>(e)] = e;
  std::array<int, np> parameter{};
  for (int p = 0; p < np; ++p) parameter[static_cast<size_t>(p)] = parameter_element(n, p);
  std::array<double, kMaxDeformations> weight{};  // sqrt(stiffness / N)
  for (int k = 0; k < m; ++k) weight[static_cast<size_t>(k)] = std::sqrt(model.deformation_stiffness(k) / N);
  // The normalisation D = diag(scale) - length dLᵀ (see Normalization).
  const Normalization normalization(model);
  using ParameterRow = Eigen::Matrix<double, 1, np>;
  const ParameterRow scale = normalization.scale().transpose();
  const ParameterRow length = normalization.length().transpose();
  const ParameterRow dL = normalization.dL().transpose();

  Eigen::Matrix<double, 6, kElementsPerJoint * n> element_jacobian;  // d residual / d s_e
  Eigen::Matrix<double, nu, nu> H;  // W + sigma AᵀA, then its Cholesky factor (diagonal inverted)
  Rows solved;                      // [Aᵀ | R], then [B | C]
  ParameterRows dx;                 // C - B dl, then dx
  Eigen::Matrix<double, 6, np> Ap;  // A_p
  Eigen::Matrix<double, 6, width> gram;
  DualRows dual;

  for (int j = 0; j < N; ++j) {
    const CycleSample& s = summary.samples[static_cast<size_t>(j)];
    deformed_geometry(model, s.state.deformations, ws.deformed);
    compute_chain(ws.deformed, s.state.theta, ws.chain);
    residual_hessian(ws.chain, s.state.multipliers, all, ws.chain_hessian);
    for (int e = 0; e < kElementsPerJoint * n; ++e) element_jacobian.col(e) = residual_derivative(ws.chain, e);
    for (int p = 0; p < np; ++p) Ap.col(p) = element_jacobian.col(parameter[static_cast<size_t>(p)]);
    auto a_col = [&](int u) { return element_jacobian.col(model.unknown_element(u)); };

    // H = W + sigma AᵀA (lower triangle, all the factorisation reads), sigma
    // raised until it is positive definite.
    double sigma = 1.0;
    bool factored = false;
    for (int attempt = 0; attempt < kMaxSensitivityAugmentations && !factored; ++attempt) {
      if (attempt > 0) sigma *= 10.0;
      for (int c = 0; c < nu; ++c) {
        for (int r = c; r < nu; ++r) {
          H(r, c) = lagrangian_hessian(model, ws.chain_hessian, r, c) + sigma * a_col(r).dot(a_col(c));
        }
      }
      factored = dense::cholesky_in_place(H, nu);
    }

    if (factored) {
      // [B | C] = L^-1 [Aᵀ | -W_xp - sigma Aᵀ A_p].
      for (int u = 0; u < nu; ++u) {
        const Vector6 a = a_col(u);
        const int eu = model.unknown_element(u);
        auto row = solved.row(u);
        row.template head<6>() = a.transpose();
        row.template tail<np>().noalias() = -sigma * (a.transpose() * Ap);
        for (int p = 0; p < np; ++p) row[6 + p] -= ws.chain_hessian(eu, parameter[static_cast<size_t>(p)]);
      }
      dense::solve_lower_rows(H, nu, solved);
      // Bᵀ [B | C]: the Schur complement BᵀB and BᵀC.
      gram.setZero();
      for (int u = 0; u < nu; ++u) {
        gram.noalias() += solved.row(u).template head<6>().transpose() * solved.row(u);
      }
      const Matrix6 schur = gram.template leftCols<6>();
      dual = (gram.template rightCols<np>() + Ap);
      // The Schur complement is singular only where the closure Jacobian
      // loses rank; there the sensitivity is not defined and a
      // pseudo-inverse is used: from the eigen-decomposition of the symmetric
      // BᵀB, eigenvalues within 6 eps of the largest taken as zero (the rank
      // rule of Eigen's CompleteOrthogonalDecomposition, whose solve
      // allocates for a singular matrix; the two agree to round-off).
      Matrix6 schur_factor = schur;
      if (dense::cholesky_in_place(schur_factor, 6)) {
        dense::solve_lower_rows(schur_factor, 6, dual);
        solve_lower_transposed_rows(schur_factor, 6, dual);
      } else {
        const Eigen::SelfAdjointEigenSolver<Matrix6> eigen(schur);
        const Vector6& values = eigen.eigenvalues();
        const double cutoff = 6.0 * std::numeric_limits<double>::epsilon() * values.cwiseAbs().maxCoeff();
        Vector6 inverse;
        for (int i = 0; i < 6; ++i) inverse[i] = std::abs(values[i]) > cutoff ? 1.0 / values[i] : 0.0;
        const DualRows projected = inverse.asDiagonal() * (eigen.eigenvectors().transpose() * dual);
        dual.noalias() = eigen.eigenvectors() * projected;
      }
      // dx = L^-ᵀ (C - B dl).
      for (int u = 0; u < nu; ++u) {
        auto out = dx.row(u);
        out = solved.row(u).template tail<np>();
        for (int r = 0; r < 6; ++r) out -= solved(u, r) * dual.row(r);
      }
      solve_lower_transposed_rows(H, nu, dx);
    } else {
      kkt_sensitivity(model, ws.chain_hessian, element_jacobian, Ap, parameter, dx);
    }

    for (int u = 0; u < nu; ++u) {
      // d x / d p = d x / d p~ D. Angles are dimensionless: they depend on the
      // geometry only through the normalised parameters, as the deformations do.
      auto row = dx.row(u);
      const double along = row.dot(length);
      row = row.cwiseProduct(scale) - along * dL;
      const int k = model.unknown_deformation(u);
      if (k >= 0) jacobian.row(j * m + k) = weight[static_cast<size_t>(k)] * row;
      const int joint = model.unknown_joint(u);
      if (angle_jacobian && joint >= 0) angle_jacobian->row(j * n + joint) = row;
    }
  }
}

}  // namespace

GeometryVector cycle_energy_gradient(const LoopModel& model, EquilibriumWorkspace& ws, const CycleSummary& summary,
                                     int sample) {
  const int n = model.joints();
  const int N = static_cast<int>(summary.samples.size());
  if (sample >= N)
    throw std::invalid_argument("cycle_energy_gradient: sample " + std::to_string(sample) + " of " + std::to_string(N));
  GeometryVector gradient = GeometryVector::Zero(3 * n);
  // The mean weighs every sample by 1/N; one sample's own energy, by 1.
  const double weight = sample < 0 ? 1.0 / N : 1.0;
  for (int j = sample < 0 ? 0 : sample; j < (sample < 0 ? N : sample + 1); ++j) {
    const CycleSample& s = summary.samples[static_cast<size_t>(j)];
    // Envelope theorem: dE/dp~ = lambda^T dc/dp~ at the solution (the energy
    // itself does not depend on the geometry in normalised units).
    deformed_geometry(model, s.state.deformations, ws.deformed);
    compute_chain(ws.deformed, s.state.theta, ws.chain);
    for (int k = 0; k < 3 * n; ++k) {
      gradient[k] += weight * s.state.multipliers.dot(residual_derivative(ws.chain, parameter_element(n, k)));
    }
  }
  Normalization(model).apply(gradient);  // dE/dp = Dᵀ dE/dp~
  return gradient;
}

void cycle_weighted_deformations(const LoopModel& model, const CycleSummary& summary, Eigen::VectorXd& r) {
  const int m = model.deformation_count();
  const int N = static_cast<int>(summary.samples.size());
  r.resize(N * m);
  for (int j = 0; j < N; ++j) {
    for (int k = 0; k < m; ++k) {
      r[j * m + k] =
          std::sqrt(model.deformation_stiffness(k) / N) * summary.samples[static_cast<size_t>(j)].state.deformations[k];
    }
  }
}

Eigen::VectorXd cycle_weighted_deformations(const LoopModel& model, const CycleSummary& summary) {
  Eigen::VectorXd r;
  cycle_weighted_deformations(model, summary, r);
  return r;
}

void cycle_deformation_jacobian(const LoopModel& model, EquilibriumWorkspace& ws, const CycleSummary& summary,
                                Eigen::MatrixXd& jacobian, Eigen::MatrixXd* angle_jacobian) {
  const int n = model.joints();
  const int N = static_cast<int>(summary.samples.size());
  // Every row is written: each deformation is an unknown.
  jacobian.resize(N * model.deformation_count(), 3 * n);
  if (angle_jacobian) angle_jacobian->setZero(N * n, 3 * n);  // the input angle's rows stay zero
  // One instantiation per loop size and compliance: n - 1 passive angles
  // and 2n (paper) or 3n (full) deformations.
  static_assert(kMinJoints == 4 && kMaxJoints == 8 && kMaxUnknowns == 4 * kMaxJoints - 1);
  const bool full = model.options().compliance == Compliance::full;
  switch (n) {
    case 4:
      return full ? differentiate_cycle<4, 15>(model, ws, summary, jacobian, angle_jacobian)
                  : differentiate_cycle<4, 11>(model, ws, summary, jacobian, angle_jacobian);
    case 5:
      return full ? differentiate_cycle<5, 19>(model, ws, summary, jacobian, angle_jacobian)
                  : differentiate_cycle<5, 14>(model, ws, summary, jacobian, angle_jacobian);
    case 6:
      return full ? differentiate_cycle<6, 23>(model, ws, summary, jacobian, angle_jacobian)
                  : differentiate_cycle<6, 17>(model, ws, summary, jacobian, angle_jacobian);
    case 7:
      return full ? differentiate_cycle<7, 27>(model, ws, summary, jacobian, angle_jacobian)
                  : differentiate_cycle<7, 20>(model, ws, summary, jacobian, angle_jacobian);
    case 8:
      return full ? differentiate_cycle<8, 31>(model, ws, summary, jacobian, angle_jacobian)
                  : differentiate_cycle<8, 23>(model, ws, summary, jacobian, angle_jacobian);
    default:
      throw std::logic_error("cycle_deformation_jacobian: a model of " + std::to_string(n) + " joints");
  }
}

Eigen::MatrixXd cycle_deformation_jacobian(const LoopModel& model, EquilibriumWorkspace& ws,
                                           const CycleSummary& summary, Eigen::MatrixXd* angle_jacobian) {
  Eigen::MatrixXd jacobian;
  cycle_deformation_jacobian(model, ws, summary, jacobian, angle_jacobian);
  return jacobian;
}
}  // namespace loopfarm
