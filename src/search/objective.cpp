#include "loopfarm/search/objective.hpp"

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <utility>

#include "loopfarm/core/assembly.hpp"

namespace loopfarm {

ObjectiveOptions ObjectiveOptions::from_loop(const LoopSection& loop) {
  ObjectiveOptions s;
  s.equilibrium.compliance = loop.compliance;
  s.equilibrium.torsion_stiffness_ratio = loop.stiffness_ratio;
  s.equilibrium.closure_tolerance = loop.closure_tolerance;
  s.equilibrium.stationarity_tolerance = loop.stationarity_tolerance;
  s.measure = loop.objective == "max" ? CycleMeasure::max : CycleMeasure::mean;
  s.cycle.samples = loop.samples;
  s.cycle.range = loop.range;
  return s;
}

std::vector<JointTravel> joint_travel(const CycleSummary& cycle, int joints) {
  std::vector<JointTravel> out(static_cast<size_t>(joints));
  if (cycle.samples.empty()) return out;
  for (int i = 0; i < joints; ++i) {
    // Unwrapped along the samples, which continuation keeps close together.
    double angle = cycle.samples[0].state.theta[i];
    double lo = angle, hi = angle;
    JointTravel& t = out[static_cast<size_t>(i)];
    for (size_t j = 1; j < cycle.samples.size(); ++j) {
      angle += wrap_angle(cycle.samples[j].state.theta[i] - cycle.samples[j - 1].state.theta[i]);
      if (angle > hi) {
        hi = angle;
        t.argmax = static_cast<int>(j);
      }
      if (angle < lo) {
        lo = angle;
        t.argmin = static_cast<int>(j);
      }
    }
    t.travel = hi - lo;
  }
  return out;
}

CycleObjective::CycleObjective(const ParameterSpace& space, ObjectiveOptions options, JointVector initial_angles)
    : space_(space),
      options_(std::move(options)),
      initial_angles_(std::move(initial_angles)),
      geometry_jacobian_(space.geometry_jacobian()) {
  options_.equilibrium.validate();
  options_.cycle.validate();
  if (initial_angles_.size() != space.joints) {
    throw std::invalid_argument("CycleObjective: initial_angles has " + std::to_string(initial_angles_.size()) +
                                " values for " + std::to_string(space.joints) + " joints");
  }
}

bool CycleObjective::run_cycle(const Eigen::VectorXd& x, double ceiling) {
  last_ok_ = run_cycle_at(x, ceiling);
  return last_ok_;
}

bool CycleObjective::run_cycle_at(const Eigen::VectorXd& x, double ceiling) {
  ++evaluations_;
  // The last successful cycle is the nearby cycle of this one (after a
  // failed evaluation, the one before it still is).
  if (last_ok_) {
    std::swap(nearby_, cycle_);
    nearby_start_ = start_;
    have_nearby_ = true;
    std::swap(nearby_deformation_sensitivity_, deformation_sensitivity_);
    std::swap(nearby_angle_sensitivity_, angle_sensitivity_);
    nearby_has_sensitivity_ = have_sensitivity_;
    nearby_x_ = last_x_;
  }
  have_sensitivity_ = false;
  last_ok_ = false;
  last_x_ = x;
  cycle_.samples.clear();
  cycle_.abandoned = false;
  deflation_ = std::numeric_limits<double>::quiet_NaN();
  geometry_ = space_.geometry(x);
  if (!x.allFinite()) return false;
  try {
    validate_geometry(geometry_);
  } catch (const std::invalid_argument&) {
    return false;  // e.g. a length pushed below zero: no loop to evaluate
  }
  // F = M E >= deflation * E (the travel factor is at least 1): the energy's
  // own ceiling, widened by a relative 1e-12 against round-off in the cycle's
  // partial sums, so that no point the ceiling admits is given up. A failed
  // sample gives the cycle up too (evaluate_residuals).
  CycleCeiling energy_ceiling;
  if (ceiling < std::numeric_limits<double>::infinity()) {
    // With its gradient: the search differentiates the points it accepts,
    // and writing out the closest representation of each family once more
    // costs far less than finding it again.
    deflation_log_gradient_.setZero(3 * geometry_.joints());
    deflation_ = deflation(&deflation_log_gradient_);
    const double bound = ceiling / deflation_ * (1.0 + 1e-12);
    (options_.measure == CycleMeasure::mean ? energy_ceiling.mean : energy_ceiling.max) = bound;
    energy_ceiling.failed_sample = true;
  }
  model_ = std::make_unique<LoopModel>(geometry_, options_.equilibrium);
  workspace_ = std::make_unique<EquilibriumWorkspace>(*model_);
  if (have_nearby_ && options_.reuse_nearby_cycle &&
      cycle_energy_from_nearby(*model_, *workspace_, predicted_nearby(x), options_.cycle, cycle_, energy_ceiling)) {
    if (cycle_.abandoned) return false;
    // The start state is the sample at theta0 (the first one of a full turn).
    if (cycle_.samples.front().theta_in == initial_angles_[0]) {
      start_ = cycle_.samples.front().state;
      return std::isfinite(cycle_.E_mean);
    }
    const EquilibriumSummary anchor = solve_equilibrium(*model_, *workspace_, initial_angles_[0], nearby_start_,
                                                        {.max_iterations = options_.cycle.max_iterations_per_step});
    if (anchor.status == SolveStatus::converged) {
      start_ = anchor.state;
      return std::isfinite(cycle_.E_mean);
    }
  }
  // The start's angles first; where they do not lead to an assembly (the
  // geometry moved too far from where they fit), the deterministic guesses.
  EquilibriumSummary start = assemble_from_angles(*model_, *workspace_, initial_angles_);
  if (start.status != SolveStatus::converged) start = assemble(*model_, *workspace_, initial_angles_[0]);
  if (start.status != SolveStatus::converged) return false;
  start_ = start.state;
  cycle_energy(*model_, *workspace_, initial_angles_[0], start_, options_.cycle, cycle_, energy_ceiling);
  return !cycle_.abandoned && std::isfinite(cycle_.E_mean);
}

const CycleSummary& CycleObjective::predicted_nearby(const Eigen::VectorXd& x) {
  if (!nearby_has_sensitivity_ || nearby_x_.size() != x.size()) return nearby_;
  const int n = space_.joints;
  const int m = model_->deformation_count();
  const int N = static_cast<int>(nearby_.samples.size());
  if (nearby_angle_sensitivity_.rows() != N * n || nearby_deformation_sensitivity_.rows() != N * m) return nearby_;
  const GeometryVector dp = geometry_jacobian_ * (x - nearby_x_);
  predicted_ = nearby_;
  const double limit = options_.cycle.max_passive_step;
  for (int j = 0; j < N; ++j) {
    EquilibriumState& state = predicted_.samples[static_cast<size_t>(j)].state;
    if (state.theta.size() != n || state.deformations.size() != m) return nearby_;
    const JointVector dtheta = nearby_angle_sensitivity_.middleRows(j * n, n) * dp;
    DeformationVector ddeformation = nearby_deformation_sensitivity_.middleRows(j * m, m) * dp;
    // The Jacobian's rows are the deformations weighted by sqrt(stiffness / N).
    for (int k = 0; k < m; ++k) ddeformation[k] /= std::sqrt(model_->deformation_stiffness(k) / N);
    // A sample whose prediction would move it further than one step of the
    // walk starts from where it was: a linearisation that far out is no guide.
    if (!(std::max(dtheta.cwiseAbs().maxCoeff(), ddeformation.cwiseAbs().maxCoeff()) <= limit)) continue;
    state.theta += dtheta;
    state.deformations += ddeformation;
  }
  return predicted_;
}

void CycleObjective::keep_sensitivity() {
  deformation_sensitivity_ = deformation_jacobian_;
  angle_sensitivity_ = angle_jacobian_;
  have_sensitivity_ = deformation_sensitivity_.allFinite() && angle_sensitivity_.allFinite();
}

void CycleObjective::continue_from(const CycleObjective& other) {
  if (!other.last_ok_ || other.cycle_.samples.empty()) return;
  nearby_ = other.cycle_;
  nearby_start_ = other.start_;
  have_nearby_ = true;
  nearby_has_sensitivity_ = false;
  last_ok_ = false;  // so that the next evaluation keeps this nearby cycle
}

double CycleObjective::deflation(GeometryVector* log_gradient) const {
  const int n = geometry_.joints();
  double factor = 1.0;
  const double p = options_.deflation_power;
  for (const DeflationTerm& term : options_.deflation) {
    GeometryVector dd = GeometryVector::Zero(3 * n);
    const double dist = std::max(term.distance(geometry_, log_gradient ? &dd : nullptr), 1e-300);
    const double inverse = std::pow(dist, -p);
    const double f = inverse + options_.deflation_shift;
    factor *= f;
    // d/dp log(dist^-p + s) = -p dist^(-p-1) / (dist^-p + s) * d dist / dp
    if (log_gradient) *log_gradient += (-p * inverse / dist / f) * dd;
  }
  return factor;
}

double CycleObjective::steering(const Eigen::MatrixXd* angle_jacobian, GeometryVector* gradient) const {
  const int n = geometry_.joints();
  GeometryVector log_gradient = GeometryVector::Zero(3 * n);  // d log M / dp
  double factor = deflation_;
  if (std::isnan(deflation_)) {
    factor = deflation(gradient ? &log_gradient : nullptr);
  } else if (gradient) {
    log_gradient = deflation_log_gradient_;
  }
  if (options_.nontrivial) {
    const std::vector<JointTravel> travel = joint_travel(cycle_, n);
    const double t0 = options_.min_travel;
    for (int i = 0; i < n; ++i) {
      if (i == options_.equilibrium.input_joint) continue;  // driven: it turns by construction
      const JointTravel& t = travel[static_cast<size_t>(i)];
      const double ratio = t0 / std::max(t.travel, 1e-300);
      const double f = 1.0 + ratio * ratio;
      factor *= f;
      if (gradient && angle_jacobian) {
        // d travel / dp = d theta_i(argmax) / dp - d theta_i(argmin) / dp;
        // d log f / d travel = -2 ratio^2 / (travel f).
        const Eigen::VectorXd dtravel =
            (angle_jacobian->row(t.argmax * n + i) - angle_jacobian->row(t.argmin * n + i)).transpose();
        log_gradient += (-2.0 * ratio * ratio / (std::max(t.travel, 1e-300) * f)) * dtravel;
      }
    }
  }
  if (gradient) *gradient = factor * log_gradient;
  return factor;
}

ObjectiveValue CycleObjective::cycle_value() const {
  ObjectiveValue v;
  v.ok = true;
  v.E_mean = cycle_.E_mean;
  v.E_max = cycle_.E_max;
  v.failed_samples = cycle_.failed_samples;
  v.branch_jumps = cycle_.branch_jumps;
  return v;
}

ObjectiveValue CycleObjective::last_cycle_value() const {
  if (!last_ok_) return ObjectiveValue{};
  return cycle_value();
}

int CycleObjective::measured_sample() const {
  if (options_.measure == CycleMeasure::mean) return -1;
  int worst = 0;
  for (int j = 1; j < static_cast<int>(cycle_.samples.size()); ++j) {
    if (cycle_.samples[static_cast<size_t>(j)].energy > cycle_.samples[static_cast<size_t>(worst)].energy) worst = j;
  }
  return worst;
}

double CycleObjective::measured_energy() const {
  return options_.measure == CycleMeasure::mean ? cycle_.E_mean : cycle_.E_max;
}

void CycleObjective::measured_residuals(Eigen::VectorXd& r) const {
  cycle_weighted_deformations(*model_, cycle_, r);
  mask_to_measured_sample(r);
}

void CycleObjective::mask_to_measured_sample(Eigen::Ref<Eigen::MatrixXd> rows) const {
  const int worst = measured_sample();
  if (worst < 0) return;
  // The stacked rows weigh each sample by sqrt(1/N); the worst sample alone
  // by 1, so that |r|^2 / 2 is its energy, E_max; the others' rows vanish.
  const int m = model_->deformation_count();
  const double scale = std::sqrt(static_cast<double>(cycle_.samples.size()));
  rows.topRows(worst * m).setZero();
  rows.middleRows(worst * m, m) *= scale;
  rows.bottomRows(rows.rows() - (worst + 1) * m).setZero();
}

ObjectiveValue CycleObjective::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient) {
  ObjectiveValue v;
  if (!run_cycle(x)) {
    v.value = std::numeric_limits<double>::infinity();
    if (gradient) gradient->setZero(x.size());
    return v;
  }
  v = cycle_value();
  const int n = geometry_.joints();
  // The travel term's gradient needs the angles' sensitivities (steering()
  // reads angle_jacobian_ only then).
  if (gradient && options_.nontrivial) {
    cycle_deformation_jacobian(*model_, *workspace_, cycle_, deformation_jacobian_, &angle_jacobian_);
  }
  GeometryVector steering_gradient = GeometryVector::Zero(3 * n);
  v.steering_factor = steered() ? steering(&angle_jacobian_, gradient ? &steering_gradient : nullptr) : 1.0;
  const double energy = measured_energy();
  v.value = v.steering_factor * energy;
  if (gradient) {
    const GeometryVector energy_gradient = cycle_energy_gradient(*model_, *workspace_, cycle_, measured_sample());
    // d(M E)/dp = M dE/dp + E dM/dp, then through the ties to x.
    const Eigen::VectorXd total = v.steering_factor * energy_gradient + energy * steering_gradient;
    *gradient = geometry_jacobian_.transpose() * total;
  }
  return v;
}

ObjectiveValue CycleObjective::evaluate_residuals(const Eigen::VectorXd& x, Eigen::VectorXd& r,
                                                  Eigen::MatrixXd* jacobian, double ceiling) {
  ObjectiveValue v;
  if (!run_cycle(x, ceiling)) {
    v.value = std::numeric_limits<double>::infinity();
    if (cycle_.abandoned) {
      v.abandoned = true;
      v.E_mean = cycle_.E_mean;
      v.E_max = cycle_.E_max;
      v.steering_factor = deflation_;
      v.value = deflation_ * measured_energy();
    }
    r.resize(0);
    if (jacobian) jacobian->resize(0, x.size());
    return v;
  }
  v = cycle_value();
  v.steering_factor = steered() ? steering(nullptr, nullptr) : 1.0;
  v.value = v.steering_factor * measured_energy();
  // r' = sqrt(M) r, so that |r'|^2 / 2 = M E_mean (or M E_max).
  measured_residuals(r);
  r *= std::sqrt(v.steering_factor);
  if (jacobian) residual_jacobian(*jacobian);
  return v;
}

void CycleObjective::residual_jacobian(Eigen::MatrixXd& jacobian) {
  if (!last_ok_) throw std::logic_error("CycleObjective::residual_jacobian: the last evaluation failed");
  const int n = geometry_.joints();
  // Into the buffers of the last call: with the same sizes nothing here
  // allocates (nor do the steering's family distances).
  const bool predicting = options_.reuse_nearby_cycle;
  cycle_deformation_jacobian(*model_, *workspace_, cycle_, deformation_jacobian_,
                             options_.nontrivial || predicting ? &angle_jacobian_ : nullptr);
  if (predicting) keep_sensitivity();
  GeometryVector steering_gradient = GeometryVector::Zero(3 * n);
  const double factor = steered() ? steering(&angle_jacobian_, &steering_gradient) : 1.0;
  // dr'/dp = sqrt(M) dr/dp + r (dM/dp)ᵀ / (2 sqrt(M)), with r unsteered.
  const double root = std::sqrt(factor);
  mask_to_measured_sample(deformation_jacobian_);
  deformation_jacobian_ *= root;
  if (steered()) {
    measured_residuals(weighted_deformations_);
    deformation_jacobian_.noalias() += weighted_deformations_ * (steering_gradient.transpose() / (2.0 * root));
  }
  jacobian.noalias() = deformation_jacobian_ * geometry_jacobian_;
}

}  // namespace loopfarm
