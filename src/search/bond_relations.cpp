// Polynomial relations between pairs of joint angles along a circuit, and
// the fingerprint of their bidegrees (bond_relations.hpp).
#include "loopfarm/search/bond_relations.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/SVD>

namespace loopfarm {
namespace {

constexpr int kLargestDegree = 8;
constexpr int kLargestRows = 100000;

std::string number(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

// Every candidate bidegree with 1 <= p, q <= max_degree, in the order they
// are tried: by p + q, then by max(p, q), then by p.
std::vector<std::pair<int, int>> candidate_bidegrees(int max_degree) {
  std::vector<std::pair<int, int>> out;
  for (int p = 1; p <= max_degree; ++p) {
    for (int q = 1; q <= max_degree; ++q) out.emplace_back(p, q);
  }
  std::sort(out.begin(), out.end(), [](const std::pair<int, int>& x, const std::pair<int, int>& y) {
    const int sx = x.first + x.second, sy = y.first + y.second;
    if (sx != sy) return sx < sy;
    const int mx = std::max(x.first, x.second), my = std::max(y.first, y.second);
    if (mx != my) return mx < my;
    return x.first < y.first;
  });
  return out;
}

// Indices of `count` poses spread evenly along the arclength of the
// sequence (the Euclidean norm of each step's wrapped joint differences),
// increasing and distinct: for each of `count` equal pieces of the
// arclength, the first pose at or past its middle.
std::vector<int> spread_by_arclength(std::span<const JointVector> poses, int count) {
  const int total = static_cast<int>(poses.size());
  std::vector<int> picked;
  if (count >= total) {
    for (int k = 0; k < total; ++k) picked.push_back(k);
    return picked;
  }
  std::vector<double> arclength(static_cast<size_t>(total), 0.0);
  for (int k = 1; k < total; ++k) {
    double step = 0.0;
    for (int joint = 0; joint < poses[0].size(); ++joint) {
      const double d = wrap_angle(poses[static_cast<size_t>(k)][joint] - poses[static_cast<size_t>(k - 1)][joint]);
      step += d * d;
    }
    arclength[static_cast<size_t>(k)] = arclength[static_cast<size_t>(k - 1)] + std::sqrt(step);
  }
  const double length = arclength.back();
  int previous = -1;
  for (int r = 0; r < count; ++r) {
    int k = r * total / count;  // no arclength at all (every pose the same): evenly by index
    if (length > 0.0) {
      const double target = length * (r + 0.5) / count;
      k = static_cast<int>(std::lower_bound(arclength.begin(), arclength.end(), target) - arclength.begin());
    }
    // Distinct and increasing, leaving room for the rows still to come.
    k = std::max(k, previous + 1);
    k = std::min(k, total - count + r);
    picked.push_back(k);
    previous = k;
  }
  return picked;
}

// Powers s^e and c^e of one joint's half-angle at every row, e = 0..degree.
struct HalfAnglePowers {
  Eigen::MatrixXd s;  // rows x (degree + 1)
  Eigen::MatrixXd c;
};

HalfAnglePowers half_angle_powers(const Eigen::VectorXd& theta, int degree) {
  const Eigen::Index rows = theta.size();
  HalfAnglePowers out{Eigen::MatrixXd::Ones(rows, degree + 1), Eigen::MatrixXd::Ones(rows, degree + 1)};
  for (Eigen::Index r = 0; r < rows; ++r) {
    const double s = std::sin(0.5 * theta[r]), c = std::cos(0.5 * theta[r]);
    for (int e = 1; e <= degree; ++e) {
      out.s(r, e) = out.s(r, e - 1) * s;
      out.c(r, e) = out.c(r, e - 1) * c;
    }
  }
  return out;
}

// The monomials of bidegree (p, q) at every row: column a (q + 1) + b is
// s_i^a c_i^(p-a) s_j^b c_j^(q-b).
Eigen::MatrixXd monomials(const HalfAnglePowers& i, const HalfAnglePowers& j, int p, int q) {
  const Eigen::Index rows = i.s.rows();
  Eigen::MatrixXd out(rows, (p + 1) * (q + 1));
  for (int a = 0; a <= p; ++a) {
    for (int b = 0; b <= q; ++b) {
      out.col(a * (q + 1) + b) =
          i.s.col(a).cwiseProduct(i.c.col(p - a)).cwiseProduct(j.s.col(b)).cwiseProduct(j.c.col(q - b));
    }
  }
  return out;
}

// The smallest and next singular values over the largest.
struct Ratios {
  double smallest = 0.0;
  double next = 0.0;
};

Ratios singular_ratios(const Eigen::VectorXd& values) {
  const Eigen::Index k = values.size();
  const double largest = values[0];
  if (!(largest > 0.0)) return {1.0, 1.0};  // cannot happen on the unit circle: s^2 + c^2 = 1
  return {values[k - 1] / largest, k >= 2 ? values[k - 2] / largest : 1.0};
}

// The pair's relation: the first candidate whose ratio is within the
// tolerance, with its null vector.
BondPair fit_pair(int i, int j, const HalfAnglePowers& pi, const HalfAnglePowers& pj,
                  const std::vector<std::pair<int, int>>& candidates, double tolerance) {
  BondPair out;
  out.i = i;
  out.j = j;
  double closest = std::numeric_limits<double>::infinity();
  for (const auto& [p, q] : candidates) {
    const Eigen::MatrixXd m = monomials(pi, pj, p, q);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(m);  // values only; at most 8 x 81 ... 100000 x 81
    const Ratios r = singular_ratios(svd.singularValues());
    if (r.smallest <= tolerance) {
      out.status = r.next <= tolerance ? BondStatus::ambiguous : BondStatus::related;
      out.p = p;
      out.q = q;
      out.ratio = r.smallest;
      out.gap = r.next;
      out.closest_rejected = std::isinf(closest) ? std::numeric_limits<double>::quiet_NaN() : closest;
      // The relation: the right singular vector of the smallest value,
      // its largest component made positive.
      const Eigen::JacobiSVD<Eigen::MatrixXd> full(m, Eigen::ComputeThinV);
      Eigen::VectorXd v = full.matrixV().col(full.matrixV().cols() - 1);
      Eigen::Index largest = 0;
      v.cwiseAbs().maxCoeff(&largest);
      if (v[largest] < 0.0) v = -v;
      v /= v.norm();
      out.coefficients.assign(v.data(), v.data() + v.size());
      return out;
    }
    closest = std::min(closest, r.smallest);
    // The last candidate is (max_degree, max_degree): kept for `none`.
    out.ratio = r.smallest;
    out.gap = r.next;
  }
  out.status = BondStatus::none;
  out.closest_rejected = closest;
  return out;
}

std::string entry(const BondPair& pair, bool swapped) {
  switch (pair.status) {
    case BondStatus::frozen:
      return "f";
    case BondStatus::none:
      return "-";
    case BondStatus::related:
    case BondStatus::ambiguous:
      break;
  }
  const int first = swapped ? pair.q : pair.p, second = swapped ? pair.p : pair.q;
  return std::to_string(first) + std::to_string(second) + (pair.status == BondStatus::ambiguous ? "?" : "");
}

}  // namespace

const char* to_string(BondStatus status) {
  switch (status) {
    case BondStatus::related:
      return "related";
    case BondStatus::ambiguous:
      return "ambiguous";
    case BondStatus::none:
      return "none";
    case BondStatus::frozen:
      return "frozen";
  }
  return "?";
}

int BondOptions::minimum_rows() const { return 3 * (max_degree + 1) * (max_degree + 1); }

int BondOptions::wanted_rows() const { return rows > 0 ? rows : 5 * (max_degree + 1) * (max_degree + 1); }

void BondOptions::validate() const {
  if (max_degree < 1 || max_degree > kLargestDegree) {
    throw std::invalid_argument("BondOptions: max_degree is " + std::to_string(max_degree) + "; must be in [1, " +
                                std::to_string(kLargestDegree) + "]");
  }
  if (!(tolerance > 0.0 && tolerance < 1.0)) {
    throw std::invalid_argument("BondOptions: tolerance is " + number(tolerance) + "; must be in (0, 1)");
  }
  if (!(frozen_travel >= 0.0 && std::isfinite(frozen_travel))) {
    throw std::invalid_argument("BondOptions: frozen_travel is " + number(frozen_travel) +
                                " rad; must be finite and >= 0");
  }
  if (rows != 0 && (rows < minimum_rows() || rows > kLargestRows)) {
    throw std::invalid_argument("BondOptions: rows is " + std::to_string(rows) + "; must be 0 (automatic) or in [" +
                                std::to_string(minimum_rows()) + ", " + std::to_string(kLargestRows) +
                                "] for max_degree " + std::to_string(max_degree) +
                                " (3 (max_degree + 1)^2: three rows per column of the largest candidate)");
  }
}

const BondPair& BondSummary::pair(int i, int j) const {
  if (i > j) std::swap(i, j);
  for (const BondPair& p : pairs) {
    if (p.i == i && p.j == j) return p;
  }
  throw std::out_of_range("BondSummary: no pair (" + std::to_string(i) + ", " + std::to_string(j) + ")");
}

std::string bond_fingerprint(int joints, int max_degree, std::span<const BondPair> pairs) {
  const int n = joints;
  if (n < 2 || static_cast<int>(pairs.size()) != n * (n - 1) / 2) {
    throw std::invalid_argument("bond_fingerprint: " + std::to_string(pairs.size()) + " pairs for " +
                                std::to_string(n) + " joints; expected n (n - 1) / 2");
  }
  // Where pair (i, j) sits in `pairs`.
  std::vector<int> slot(static_cast<size_t>(n * n), -1);
  for (int k = 0; k < static_cast<int>(pairs.size()); ++k) {
    const BondPair& p = pairs[static_cast<size_t>(k)];
    if (p.i < 0 || p.j >= n || p.i >= p.j) throw std::invalid_argument("bond_fingerprint: a pair is not i < j < n");
    slot[static_cast<size_t>(p.i * n + p.j)] = k;
  }
  const std::string head = std::to_string(n) + "R/" + std::to_string(max_degree);
  std::string least;
  // New joint k is old joint (shift + k) mod n, or (shift - k) mod n reversed.
  for (int reversed = 0; reversed < 2; ++reversed) {
    for (int shift = 0; shift < n; ++shift) {
      auto old_joint = [&](int k) { return ((reversed ? shift - k : shift + k) % n + n) % n; };
      std::string text = head;
      for (int i = 0; i < n; ++i) {
        for (int j = i + 1; j < n; ++j) {
          const int oi = old_joint(i), oj = old_joint(j);
          const int k = slot[static_cast<size_t>(std::min(oi, oj) * n + std::max(oi, oj))];
          if (k < 0) throw std::invalid_argument("bond_fingerprint: a pair is missing");
          text += ' ' + entry(pairs[static_cast<size_t>(k)], oi > oj);
        }
      }
      if (least.empty() || text < least) least = std::move(text);
    }
  }
  return least;
}

BondSummary bond_relations(const LoopGeometry& geometry, std::span<const JointVector> poses,
                           const BondOptions& options) {
  const auto started = std::chrono::steady_clock::now();
  validate_geometry(geometry);
  options.validate();
  const int n = geometry.joints();
  for (size_t k = 0; k < poses.size(); ++k) {
    if (poses[k].size() != n) {
      throw std::invalid_argument("bond_relations: pose " + std::to_string(k) + " has " +
                                  std::to_string(poses[k].size()) + " angles for " + std::to_string(n) + " joints");
    }
    if (!poses[k].allFinite()) {
      throw std::invalid_argument("bond_relations: pose " + std::to_string(k) + " has an angle that is not finite");
    }
  }
  if (static_cast<int>(poses.size()) < options.minimum_rows()) {
    throw std::invalid_argument("bond_relations: " + std::to_string(poses.size()) + " poses; at least " +
                                std::to_string(options.minimum_rows()) + " are needed for max_degree " +
                                std::to_string(options.max_degree) +
                                " (3 (max_degree + 1)^2: three rows per column of the largest candidate)");
  }

  BondSummary out;
  out.joints = n;
  out.max_degree = options.max_degree;
  out.tolerance = options.tolerance;
  out.poses = static_cast<int>(poses.size());

  // Each joint's travel over every pose (unwrapped along the sequence, so
  // that a crank read in (-pi, pi] is not taken for one that jumps).
  for (int joint = 0; joint < n; ++joint) {
    double angle = poses[0][joint], lo = angle, hi = angle;
    for (size_t k = 1; k < poses.size(); ++k) {
      angle += wrap_angle(poses[k][joint] - poses[k - 1][joint]);
      lo = std::min(lo, angle);
      hi = std::max(hi, angle);
    }
    out.travel.push_back(hi - lo);
    out.frozen.push_back(hi - lo < options.frozen_travel);
  }

  // The rows: poses spread by arclength, and how well they close.
  const std::vector<int> rows = spread_by_arclength(poses, options.wanted_rows());
  out.rows = static_cast<int>(rows.size());
  const LoopGeometry unit = scaled(geometry, length_scale(geometry));
  for (const int k : rows) {
    out.worst_closure =
        std::max(out.worst_closure, closure_residual(unit, poses[static_cast<size_t>(k)]).lpNorm<Eigen::Infinity>());
  }
  std::vector<HalfAnglePowers> powers;
  for (int joint = 0; joint < n; ++joint) {
    Eigen::VectorXd theta(out.rows);
    for (int r = 0; r < out.rows; ++r) theta[r] = poses[static_cast<size_t>(rows[static_cast<size_t>(r)])][joint];
    powers.push_back(half_angle_powers(theta, options.max_degree));
  }

  const std::vector<std::pair<int, int>> candidates = candidate_bidegrees(options.max_degree);
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (out.frozen[static_cast<size_t>(i)] || out.frozen[static_cast<size_t>(j)]) {
        BondPair frozen;
        frozen.i = i;
        frozen.j = j;
        frozen.status = BondStatus::frozen;
        frozen.ratio = frozen.gap = frozen.closest_rejected = std::numeric_limits<double>::quiet_NaN();
        out.pairs.push_back(frozen);
        continue;
      }
      out.pairs.push_back(fit_pair(i, j, powers[static_cast<size_t>(i)], powers[static_cast<size_t>(j)], candidates,
                                   options.tolerance));
    }
  }
  out.fingerprint = bond_fingerprint(n, options.max_degree, out.pairs);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return out;
}

}  // namespace loopfarm
