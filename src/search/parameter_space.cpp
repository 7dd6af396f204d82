// ParameterSpace: from free values x to a geometry and initial angles, and the
// constant Jacobian of that map (job.hpp).
#include <stdexcept>
#include <string>

#include "loopfarm/search/job.hpp"

namespace loopfarm {
namespace {

bool is_geometric(int index, int joints) { return index < 3 * joints; }

}  // namespace

std::string ParameterSpace::name(int index) const {
  static const char* const kinds[] = {"a", "alpha", "d", "theta"};
  const int kind = index / joints;
  const int joint = index % joints;
  const bool angle = kind == static_cast<int>(ParameterKind::alpha) || kind == static_cast<int>(ParameterKind::theta);
  return std::string(kinds[kind]) + std::to_string(joint + 1) + (angle ? "_deg" : "");
}

std::vector<int> ParameterSpace::free_indices() const {
  std::vector<int> out;
  for (int i = 0; i < static_cast<int>(specs.size()); ++i) {
    if (is_geometric(i, joints) && specs[static_cast<size_t>(i)].mode == ParameterSpec::Mode::range) out.push_back(i);
  }
  return out;
}

int ParameterSpace::free_count() const { return static_cast<int>(free_indices().size()); }

Eigen::VectorXd ParameterSpace::lower_bounds() const {
  const std::vector<int> free = free_indices();
  Eigen::VectorXd out(static_cast<int>(free.size()));
  for (size_t k = 0; k < free.size(); ++k) out[static_cast<int>(k)] = specs[static_cast<size_t>(free[k])].lo;
  return out;
}

Eigen::VectorXd ParameterSpace::upper_bounds() const {
  const std::vector<int> free = free_indices();
  Eigen::VectorXd out(static_cast<int>(free.size()));
  for (size_t k = 0; k < free.size(); ++k) out[static_cast<int>(k)] = specs[static_cast<size_t>(free[k])].hi;
  return out;
}

LoopGeometry ParameterSpace::geometry(const Eigen::VectorXd& x) const {
  const std::vector<int> free = free_indices();
  if (x.size() != static_cast<int>(free.size())) {
    throw std::invalid_argument("ParameterSpace::geometry: " + std::to_string(x.size()) + " values for " +
                                std::to_string(free.size()) + " free parameters");
  }
  // Values of every geometric parameter: fixed and free first, then the ties
  // (whose sources are never tied themselves).
  std::vector<double> value(static_cast<size_t>(3 * joints), 0.0);
  size_t next_free = 0;
  for (int i = 0; i < 3 * joints; ++i) {
    const ParameterSpec& s = specs[static_cast<size_t>(i)];
    if (s.mode == ParameterSpec::Mode::fixed) value[static_cast<size_t>(i)] = s.value;
    if (s.mode == ParameterSpec::Mode::range) value[static_cast<size_t>(i)] = x[static_cast<int>(next_free++)];
  }
  for (int i = 0; i < 3 * joints; ++i) {
    const ParameterSpec& s = specs[static_cast<size_t>(i)];
    if (s.mode == ParameterSpec::Mode::tied)
      value[static_cast<size_t>(i)] = s.sign * value[static_cast<size_t>(s.source)];
  }
  LoopGeometry g;
  g.a.resize(joints);
  g.alpha.resize(joints);
  g.d.resize(joints);
  for (int j = 0; j < joints; ++j) {
    g.a[j] = value[static_cast<size_t>(index(ParameterKind::a, j))];
    g.alpha[j] = value[static_cast<size_t>(index(ParameterKind::alpha, j))];
    g.d[j] = value[static_cast<size_t>(index(ParameterKind::d, j))];
  }
  return g;
}

Eigen::MatrixXd ParameterSpace::geometry_jacobian() const {
  const std::vector<int> free = free_indices();
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3 * joints, static_cast<int>(free.size()));
  for (size_t k = 0; k < free.size(); ++k) J(free[k], static_cast<int>(k)) = 1.0;
  for (int i = 0; i < 3 * joints; ++i) {
    const ParameterSpec& s = specs[static_cast<size_t>(i)];
    if (s.mode == ParameterSpec::Mode::tied) J.row(i) = s.sign * J.row(s.source);
  }
  return J;
}

Eigen::VectorXd ParameterSpace::free_values(const LoopGeometry& g) const {
  const std::vector<int> free = free_indices();
  Eigen::VectorXd x(static_cast<int>(free.size()));
  for (size_t k = 0; k < free.size(); ++k) {
    const int i = free[k];
    const int joint = i % joints;
    switch (static_cast<ParameterKind>(i / joints)) {
      case ParameterKind::a:
        x[static_cast<int>(k)] = g.a[joint];
        break;
      case ParameterKind::alpha:
        x[static_cast<int>(k)] = g.alpha[joint];
        break;
      default:
        x[static_cast<int>(k)] = g.d[joint];
        break;
    }
  }
  return x;
}

int ParameterSpace::random_angle_count() const {
  int count = 0;
  for (int j = 0; j < joints; ++j) {
    count += specs[static_cast<size_t>(index(ParameterKind::theta, j))].mode == ParameterSpec::Mode::range;
  }
  return count;
}

JointVector ParameterSpace::initial_angles(const Eigen::VectorXd& draws) const {
  if (draws.size() != random_angle_count()) {
    throw std::invalid_argument("ParameterSpace::initial_angles: " + std::to_string(draws.size()) + " values for " +
                                std::to_string(random_angle_count()) + " random angles");
  }
  JointVector theta(joints);
  int next = 0;
  for (int j = 0; j < joints; ++j) {
    const ParameterSpec& s = specs[static_cast<size_t>(index(ParameterKind::theta, j))];
    if (s.mode == ParameterSpec::Mode::fixed) theta[j] = s.value;
    if (s.mode == ParameterSpec::Mode::range) theta[j] = draws[next++];
  }
  for (int j = 0; j < joints; ++j) {
    const ParameterSpec& s = specs[static_cast<size_t>(index(ParameterKind::theta, j))];
    if (s.mode == ParameterSpec::Mode::tied) theta[j] = s.sign * theta[s.source - index(ParameterKind::theta, 0)];
  }
  return theta;
}

}  // namespace loopfarm
