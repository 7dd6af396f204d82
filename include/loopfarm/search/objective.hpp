// The objective of the geometry search: the cycle energy E_mean of the
// geometry a ParameterSpace builds from free values x, with its gradient
// (envelope theorem) and, for Gauss-Newton, its residual vector r with
// E_mean = |r|^2 / 2 and the Jacobian dr/dx (implicit differentiation).
//
// Optionally steered away from the known movable families (docs/design.md,
// "Steering away from the known families"): the energy is multiplied by a factor
//
//     M(p) = prod_f (dist_f(p)^-power + shift) * prod_j (1 + (t0 / travel_j)^2)
//
// where dist_f is the distance of the geometry to family f's conditions
// (deflation, as for nonlinear equations: a zero of E on the family stops
// being a zero of M E, since E vanishes there only quadratically) and the
// second product, the non-triviality requirement, grows where a joint hardly
// turns over the cycle (travel_j below t0), the mark of a trivial motion.
// Zeros away from the steered-off sets stay zeros; M tends to a constant
// there.
//
// With ObjectiveOptions::reuse_nearby_cycle off, each evaluation is a pure
// function of x: the loop is assembled afresh from the start's initial joint
// angles. With it on (the default) each cycle is solved from the last
// successful evaluation's samples, so a value depends on the search's path
// to within the solve's tolerance (about 1e-12 relative), and each sample's
// branch is followed continuously in the geometry.
#pragma once

#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "loopfarm/core/cycle.hpp"
#include "loopfarm/search/job.hpp"

namespace loopfarm {

// The distance of a geometry to a family's condition set and, when the
// pointer is not null, its gradient with respect to (a, alpha, d).
using FamilyDistance = std::function<double(const LoopGeometry&, GeometryVector*)>;

struct DeflationTerm {
  std::string family;
  FamilyDistance distance;
};

// Which of the cycle's energies the search minimises.
enum class CycleMeasure {
  mean,  // E_mean: smooth, the default
  max,   // E_max: the paper's peak; its gradient and residuals are the worst sample's
};

struct ObjectiveOptions {
  EquilibriumOptions equilibrium;
  CycleOptions cycle;
  CycleMeasure measure = CycleMeasure::mean;
  std::vector<DeflationTerm> deflation;
  double deflation_power = 2.0;
  double deflation_shift = 1.0;
  bool nontrivial = false;
  double min_travel = 0.0872664625997164788;  // t0 [rad]
  // Start each evaluation's cycle from the last successful evaluation's
  // samples (cycle_energy_from_nearby) instead of walking it from the
  // assembly, falling back to the walk when that cannot be vouched for.
  bool reuse_nearby_cycle = true;

  // The loop settings of a job (compliance, stiffness ratio, samples, range);
  // steering is added by the caller, which knows the family distances.
  static ObjectiveOptions from_loop(const LoopSection& loop);
};

struct ObjectiveValue {
  bool ok = false;  // assembled and the cycle evaluated
  // Given up above the caller's ceiling (not ok): value, E_mean and E_max
  // are lower bounds.
  bool abandoned = false;
  double value = 0.0;  // M * E_mean (or M * E_max): what the optimiser sees
  double E_mean = 0.0;
  double E_max = 0.0;
  double steering_factor = 1.0;  // M
  int failed_samples = 0;
  int branch_jumps = 0;
};

class CycleObjective {
 public:
  // `initial_angles`: the start's joint angles at theta0 = initial_angles[0]
  // (the input joint is joint 1); the passive ones are the assembly's guess.
  CycleObjective(const ParameterSpace& space, ObjectiveOptions options, JointVector initial_angles);

  // F(x) and, when `gradient` is not null, dF/dx.
  ObjectiveValue evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient);
  // F(x) = |r|^2 / 2 and, when `jacobian` is not null, dr/dx.
  //
  // With a finite `ceiling`, a point whose F is known to exceed it before
  // its cycle is finished is given up (ObjectiveValue::abandoned; r is left
  // empty): a local search that rejects such points anyway pays only for the
  // samples that told. The deflation factor is known before the cycle and
  // the travel factor is at least 1, so the samples solved so far bound F
  // from below. A cycle with a failed sample is given up as well, at that
  // sample: its energy is wherever the solve stopped (often near zero, never
  // a zero), so a search with a ceiling does not step onto such points. An
  // abandoned evaluation counts as failed: the next one starts from the
  // cycle before it.
  ObjectiveValue evaluate_residuals(const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* jacobian,
                                    double ceiling = std::numeric_limits<double>::infinity());

  // dr/dx at the last evaluation (which must have succeeded): one implicit
  // differentiation of its cycle, no new cycle.
  void residual_jacobian(Eigen::MatrixXd& jacobian);

  // Makes `other`'s last cycle (same space and loop settings) the nearby
  // cycle of this objective's next evaluation, as if this objective had
  // evaluated it: the unsteered energy at a steered search's result follows
  // the branch the search followed. Nothing when `other`'s last evaluation
  // failed.
  void continue_from(const CycleObjective& other);

  int evaluations() const { return evaluations_; }
  // The last evaluation's x, and whether it succeeded.
  const Eigen::VectorXd& last_x() const { return last_x_; }
  bool last_ok() const { return last_ok_; }
  // The last evaluation's cycle energies and counts, unsteered (M = 1);
  // ok only when that evaluation succeeded.
  ObjectiveValue last_cycle_value() const;
  // The last evaluation's geometry, assembled start state and cycle.
  const LoopGeometry& geometry() const { return geometry_; }
  const EquilibriumState& start_state() const { return start_; }
  const CycleSummary& cycle() const { return cycle_; }
  const ParameterSpace& space() const { return space_; }
  const ObjectiveOptions& options() const { return options_; }

 private:
  // Builds the geometry, assembles and runs the cycle; false when the loop
  // cannot be assembled at theta0 or the geometry is invalid.
  // With a finite `ceiling` on F the cycle may be abandoned (cycle_.abandoned,
  // and false).
  bool run_cycle(const Eigen::VectorXd& x, double ceiling = std::numeric_limits<double>::infinity());
  bool run_cycle_at(const Eigen::VectorXd& x, double ceiling);
  // nearby_ moved to x along its sensitivities, into predicted_ (each sample
  // whose predicted change stays within a step of the walk); nearby_ itself
  // where it has none.
  const CycleSummary& predicted_nearby(const Eigen::VectorXd& x);
  // Keeps the sensitivities of cycle_ from the Jacobians just computed at it.
  void keep_sensitivity();
  // M and dM/d(a, alpha, d) (when `gradient` is not null) at the last cycle;
  // `angle_jacobian` (rows j * n + i) is needed for the travel term.
  double steering(const Eigen::MatrixXd* angle_jacobian, GeometryVector* gradient) const;
  // The deflation product of M at the last geometry and, when `log_gradient`
  // is not null, d log(product) / d(a, alpha, d) added to it.
  double deflation(GeometryVector* log_gradient) const;
  // The last cycle's energies and counts (unsteered: M = 1).
  ObjectiveValue cycle_value() const;
  // The measure of the last cycle: the sample it looks at (-1: all, the
  // mean), its energy, and the residual rows that carry it.
  int measured_sample() const;
  double measured_energy() const;
  void measured_residuals(Eigen::VectorXd& r) const;
  // Keeps only the measured sample's rows of the stacked per-sample rows
  // (scaled to weigh 1), for the max; leaves them all for the mean.
  void mask_to_measured_sample(Eigen::Ref<Eigen::MatrixXd> rows) const;
  bool steered() const { return !options_.deflation.empty() || options_.nontrivial; }

  const ParameterSpace& space_;
  ObjectiveOptions options_;
  JointVector initial_angles_;
  Eigen::MatrixXd geometry_jacobian_;  // d(a, alpha, d) / dx
  int evaluations_ = 0;
  Eigen::VectorXd last_x_;
  bool last_ok_ = false;
  LoopGeometry geometry_;
  // The deflation product at geometry_ and d log(product) / d(a, alpha, d),
  // where run_cycle_at needed it for a ceiling (NaN otherwise): steering()
  // reuses both.
  double deflation_ = std::numeric_limits<double>::quiet_NaN();
  GeometryVector deflation_log_gradient_;
  std::unique_ptr<LoopModel> model_;  // of the last evaluation
  std::unique_ptr<EquilibriumWorkspace> workspace_;
  EquilibriumState start_;
  CycleSummary cycle_;
  // The cycle of the last successful evaluation before the current one,
  // and its start state: where the next evaluation starts from.
  CycleSummary nearby_;
  EquilibriumState nearby_start_;
  bool have_nearby_ = false;
  // The sensitivities of cycle_'s sample states to (a, alpha, d), where a
  // Jacobian was computed at it (as cycle_deformation_jacobian gives them:
  // the weighted deformations' and the angles'); they travel with it to
  // nearby_. The next evaluation starts each sample from nearby's state
  // moved along them (predicted_), a first-order step in the geometry.
  Eigen::MatrixXd deformation_sensitivity_, angle_sensitivity_;
  bool have_sensitivity_ = false;
  Eigen::MatrixXd nearby_deformation_sensitivity_, nearby_angle_sensitivity_;
  Eigen::VectorXd nearby_x_;
  bool nearby_has_sensitivity_ = false;
  CycleSummary predicted_;
  // Buffers of the Jacobians, kept so that repeated evaluations reuse them.
  Eigen::VectorXd weighted_deformations_;
  Eigen::MatrixXd deformation_jacobian_;  // dr/d(a, alpha, d)
  Eigen::MatrixXd angle_jacobian_;        // d theta / d(a, alpha, d), rows j * n + i
};

// Per joint, how far its angle turns over the cycle [rad]: max - min of the
// angle unwrapped from sample to sample, with the samples where it is reached.
struct JointTravel {
  double travel = 0.0;
  int argmax = 0;
  int argmin = 0;
};
std::vector<JointTravel> joint_travel(const CycleSummary& cycle, int joints);

}  // namespace loopfarm
