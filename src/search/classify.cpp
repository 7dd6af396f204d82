// Classification of a movable loop (classify.hpp): the families decided by the
// geometry (family_fit.hpp), by the pose (coincident axes) and by the motion
// (frozen and locked joints), and the choice among them.
#include "loopfarm/search/classify.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "cubic_motion_fit.hpp"
#include "family_conditions.hpp"
#include "family_fit.hpp"
#include "representation.hpp"

namespace loopfarm {

using namespace detail;

namespace {

struct AxisPair {
  int i = -1, j = -1;
  double residual = kInf;  // max(sin of the angle between them, distance / L)
};

AxisPair nearest_coincident_axes(const LoopGeometry& g, const JointVector& pose) {
  const int n = g.joints();
  const double L = length_scale(g);
  std::vector<Vector3> origin, axis;
  for (int k = 0; k < n; ++k) {
    const Eigen::Isometry3d frame = forward_transform(g, pose, k);
    origin.push_back(frame.translation());
    axis.push_back(frame.linear().col(2));
  }
  AxisPair best;
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const double angle = axis[i].cross(axis[j]).norm();
      const double distance = (origin[j] - origin[i]).cross(axis[i]).norm() / L;
      const double residual = std::max(angle, distance);
      if (residual < best.residual) best = {i, j, residual};
    }
  }
  return best;
}

// The detail line of a 5R or 6R family found, from its best representation
// (the one its check was read from).
std::string special_detail(Family family, const Best& best, const LoopGeometry& g) {
  if (family == Family::goldberg_bent) {
    // The fusion angle |psi| from the real cosine rule of the best representation:
    // cos(alpha5) = cos(alpha2) cos(alpha3) + sin(alpha2) sin(alpha3) cos(psi).
    const LoopGeometry w = written_out(best, g);
    const double cos_psi = (std::cos(w.alpha[4]) - std::cos(w.alpha[1]) * std::cos(w.alpha[2])) /
                           (std::sin(w.alpha[1]) * std::sin(w.alpha[2]));
    const double psi_deg = std::acos(std::clamp(cos_psi, -1.0, 1.0)) * 180.0 / kPi;
    const bool same = ((best.set & 1) != 0) == ((best.set & 2) != 0);
    char buffer[160];
    std::snprintf(buffer, sizeof buffer,
                  "links fused at %.4g deg (0: same side, 180: opposite sides), d1 = %sd5 = %.4g L, Bennett loops "
                  "in %s setups",
                  psi_deg, same ? "" : "-", w.d[0] / length_scale(w), same ? "the same" : "different");
    return buffer;
  }
  if (family == Family::bennett_pair) {
    const LoopGeometry w = written_out(best, g);
    char buffer[256];
    std::snprintf(buffer, sizeof buffer,
                  "two Bennett loops (links 1-3 and 4-6 of the best representation) sharing a removed link (%.4g L, "
                  "%.4g deg) between joints 1 and 4, in %s setups; two degrees of freedom",
                  w.a[1] / length_scale(w), w.alpha[1] * 180.0 / kPi,
                  ((best.set & 1) != 0) == ((best.set & 2) != 0) ? "the same" : "different");
    return buffer;
  }
  if (family == Family::bennett_dyads) {
    const LoopGeometry w = written_out(best, g);
    const double L = length_scale(w);
    char buffer[256];
    std::snprintf(buffer, sizeof buffer,
                  "Bennett dyads (links 1-2 and 4-5 of the best representation, (cos alpha + cos beta) / kappa = "
                  "%.4g L) joined by two equal links (%.4g L, %.4g deg), offsets %.4g L and %.4g L at the dyads' ends",
                  (std::cos(w.alpha[0]) + std::cos(w.alpha[1])) * w.a[0] / std::sin(w.alpha[0]) / L, w.a[2] / L,
                  w.alpha[2] * 180.0 / kPi, w.d[0] / L, w.d[3] / L);
    return buffer;
  }
  if (family == Family::bennett_triads) {
    // The two triads' shared quantities, from the best representation
    // (bennett_triads_conditions: equal for both triads in it).
    const LoopGeometry w = written_out(best, g);
    const double L = length_scale(w);
    const double k = std::sin(w.alpha[0]) / w.a[0];
    double sum = 1.0, product = 1.0;
    for (int i = 0; i < 3; ++i) {
      sum += std::cos(w.alpha[i]);
      product *= std::cos(0.5 * w.alpha[i]);
    }
    char buffer[320];
    std::snprintf(buffer, sizeof buffer,
                  "Bennett-ratio triads (links 1-3 and 4-6 of the best representation, sin alpha / a = %.4g and %.4g "
                  "/ L, no offsets inside them, d1 = -d4 = %.4g L) with the same (1 + sum of cos alpha) / k = %.4g L "
                  "and product of cos(alpha / 2) / k = %.4g L",
                  k * L, std::sin(w.alpha[3]) / w.a[3] * L, w.d[0] / L, sum / k / L, product / k / L);
    return buffer;
  }
  if (family == Family::coupled_bennett_dyads) {
    // The dyads' ratios and the three quantities they share, from the best
    // representation (coupled_bennett_dyads_conditions: equal in it).
    const LoopGeometry w = written_out(best, g);
    const double L = length_scale(w);
    const double k2 = std::sin(w.alpha[1]) / w.a[1], k5 = std::sin(w.alpha[4]) / w.a[4];
    const double tangents = std::tan(0.5 * w.alpha[1]) * std::tan(0.5 * w.alpha[2]);
    char buffer[640];
    std::snprintf(buffer, sizeof buffer,
                  "Bennett dyads (links 2-3 and 5-6 of the best representation, sin alpha / a = %.4g and %.4g / L, "
                  "d3 = d6 = 0) joined by links 1 and 4, with the same tan(alpha/2) tan(beta/2) = %.4g and (cos "
                  "alpha + cos beta) / k = %.4g L, tan(alpha/2) / a = %.4g / L on the joining links, offsets d1, d2, "
                  "d4, d5 = %.4g, %.4g, %.4g, %.4g L; the dyads' middle joints (3 and 6 there) turn together",
                  k2 * L, k5 * L, tangents, (std::cos(w.alpha[1]) + std::cos(w.alpha[2])) / k2 / L,
                  std::tan(0.5 * w.alpha[0]) / w.a[0] * L, w.d[0] / L, w.d[1] / L, w.d[3] / L, w.d[4] / L);
    return buffer;
  }
  if (family == Family::waldron_hybrid) {
    // The dyads' Bennett ratios and how far apart the two loops' feet lie on
    // the fourth axis (Waldron's slide), from the fit of the best representation.
    const LoopGeometry w = written_out(best, g);
    const WrittenOut written(w);
    const WaldronFit fit = waldron_fit(waldron_parameters(written));
    const double L = length_scale(w);
    char buffer[320];
    std::snprintf(buffer, sizeof buffer,
                  "Bennett dyads (links 1-2 and 4-5 of the best representation, |sin alpha| / a = %.4g and %.4g / L) "
                  "closed by one fourth axis, fixed in links 3 and 6 (Waldron's hybrid), the two Bennett loops' "
                  "feet on it %.4g L apart",
                  std::abs(std::sin(w.alpha[0])) / w.a[0] * L, std::abs(std::sin(w.alpha[3])) / w.a[3] * L,
                  std::abs(fit.feet));
    return buffer;
  }
  if (family == Family::double_goldberg) {
    // The one Bennett ratio of the three loops, from the best representation.
    const LoopGeometry w = written_out(best, g);
    char buffer[320];
    std::snprintf(buffer, sizeof buffer,
                  "double-Goldberg: Bennett dyads (links 1-2 and 4-5 of the best representation, |sin alpha| / a = "
                  "%.4g / L) closed by one fourth axis, fixed in links 3 and 6, on which the two Bennett loops meet "
                  "at one point; a third Bennett loop joins links 3 and 6 there (two Goldberg 5Rs merged)",
                  std::abs(std::sin(w.alpha[0])) / w.a[0] * length_scale(w));
    return buffer;
  }
  if (family == Family::goldberg_6r) {
    // Which link of the Goldberg 5R the third Bennett loop shares (P, the
    // removed joint, is the 5R's joint set / 4), the third loop's ratio and
    // the fusion angle about P, from the fit of the best representation.
    const LoopGeometry w = written_out(best, g);
    const WrittenOut written(w);
    const int k = best.set / 4, setup = best.set % 4;
    const Goldberg6RFit fit = goldberg_6r_fit(goldberg_6r_parameters(written), k, setup);
    static constexpr const char* kLinks[5] = {"BC", "CD", "DE", "EF", "FB (its fused link)"};
    char buffer[360];
    const bool same = ((setup & 1) != 0) == ((setup & 2) != 0);
    std::snprintf(buffer, sizeof buffer,
                  "a Goldberg 5R B C D E F and a third Bennett loop (links 1-2 of the best representation, |sin "
                  "alpha| / a = %.4g / L) sharing its link %s, fused at %c at %.4g deg (0 or 180: collinear), the "
                  "5R's Bennett loops in %s setups",
                  std::abs(std::sin(w.alpha[0])) / w.a[0] * length_scale(w), kLinks[k], "BCDEF"[k],
                  std::abs(fit.fusion) * 180.0 / kPi, same ? "the same" : "different");
    return buffer;
  }
  if (family == Family::hooke) {
    // How far apart the two centres are (the distance both links 3 and 6
    // hold), from the best representation.
    const LoopGeometry w = written_out(best, g);
    const double distance =
        std::sqrt(w.d[2] * w.d[2] + w.a[2] * w.a[2] + w.d[3] * w.d[3] + 2.0 * w.d[2] * w.d[3] * std::cos(w.alpha[2]));
    char buffer[256];
    std::snprintf(buffer, sizeof buffer,
                  "axes 1-3 of the best representation through one point, axes 4-6 through another, %.4g L apart in "
                  "links 3 and 6 (Hooke's double-spherical loop): link 3 turns against link 6 about the line through "
                  "them",
                  distance / length_scale(w));
    return buffer;
  }
  if (family != Family::goldberg && family != Family::myard) {
    switch (family) {
      case Family::bricard_line_symmetric:
        return "line symmetry: link i and joint i as link and joint i + 3";
      case Family::bricard_plane_symmetric:
        return "plane symmetry through joints 1 and 4 of the best representation";
      case Family::bricard_trihedral:
        return "right-angle twists, no offsets, a1^2 + a3^2 + a5^2 = a2^2 + a4^2 + a6^2";
      case Family::sarrus:
        return "two chains of three parallel axes (joints 2-4 and 5-1 of the best representation)";
      case Family::angle_symmetric_parallel:
        return best.set == 0
                   ? "three pairs of parallel axes (1-2, 4-5 and 3-6 of the best representation), opposite "
                     "joints turning by equal angles"
                   : "three pairs of parallel axes (1-2, 4-5 and 3-6 of the best representation), opposite "
                     "joints turning by equal angles; axes 4-5 the half-turned 1-2 (|alpha2| + |alpha3| = pi)";
      case Family::bricard_octahedral_plane:
        return "every a_i = 0: an octahedron with a mirror plane through two opposite vertices that maps each "
               "other vertex onto its opposite one";
      case Family::bricard_octahedral_collapsible:
        return "every a_i = 0: a doubly collapsible octahedron (Bricard's third type, two flat poses): opposite "
               "face angles at each vertex equal or supplementary, the four edges of each four-edge cycle through "
               "two opposite pairs adding up to zero with signs";
      default:
        return "";
    }
  }
  std::string d =
      (best.set & 4) ? "fused links on the same side (a5 = a2 - a3)" : "fused links on opposite sides (a5 = a2 + a3)";
  d += std::string(", Bennett loops ") + ((best.set & 1) ? "line-symmetric" : "asymmetric") + " and " +
       ((best.set & 2) ? "line-symmetric" : "asymmetric") + " in the best representation";
  return d;
}

// The cubic-motion-polynomial loop's check: the fit's thirteen residuals at
// the pose.
FamilyCheck cubic_check(const CubicMotionFit& fit) {
  FamilyCheck check;
  check.family = Family::cubic_321;
  check.residual = fit.solved ? fit.residual : kInf;
  if (fit.solved) {
    for (int i = 0; i < kCubicResiduals; ++i) {
      check.conditions.push_back({cubic_residual_name(i), fit.residuals[static_cast<size_t>(i)]});
    }
  }
  return check;
}

std::string cubic_detail(const CubicMotionFit& fit) {
  const auto& v = fit.unknowns;
  char buffer[320];
  std::snprintf(buffer, sizeof buffer,
                "a cubic motion polynomial's two factorisations: joints 1 and 4, 2 and 5, 3 and 6 share the norm "
                "factors (t - x)^2 + y^2 and turn by equal angles (up to sign); at this pose (t = infinity) x = 0, "
                "%.4g, %.4g and y = 1, %.4g, %.4g",
                v[1], v[3], v[2], v[4]);
  return buffer;
}

}  // namespace

Classification classify(const LoopGeometry& given, const JointVector& pose, std::span<const double> joint_travel,
                        const ClassifyOptions& options) {
  validate_geometry(given);
  // Offsets between parallel axes are where the search left the common
  // normal, not a property of the loop: every condition reads them with the
  // normal centred (a line-symmetric loop with parallel axes is then seen as
  // one). The axes, and so the pose, are the same.
  const LoopGeometry geometry = centred_parallel_normals(given, options.tolerance);
  const int n = geometry.joints();
  if (pose.size() != n || !pose.allFinite()) {
    throw std::invalid_argument("classify: the pose needs " + std::to_string(n) + " finite joint angles");
  }
  if (!joint_travel.empty() && static_cast<int>(joint_travel.size()) != n) {
    throw std::invalid_argument("classify: joint_travel needs one value per joint");
  }
  Classification out;

  // Bennett: the best representation; the setup as written when it fits as written.
  FamilyCheck bennett;
  bennett.family = Family::bennett;
  bennett.residual = kInf;
  if (n == 4) {
    const Best best = best_over_representations<Family::bennett>(geometry, false, options.tolerance);
    bennett = check_from(Family::bennett, best);
    bennett.setup = best.setup_sign > 0 ? BennettSetup::asymmetric : BennettSetup::line_symmetric;
    const WrittenOut as_written(geometry);
    Conditions asym, line;
    bennett_conditions(as_written, 1.0, asym);
    bennett_conditions(as_written, -1.0, line);
    const double as_written_asym = asym.max_abs();
    const double as_written_line = line.max_abs();
    if (std::min(as_written_asym, as_written_line) <= options.tolerance) {
      bennett.setup = as_written_asym <= as_written_line ? BennettSetup::asymmetric : BennettSetup::line_symmetric;
    }
  }
  FamilyCheck planar =
      check_from(Family::planar, best_over_representations<Family::planar>(geometry, false, options.tolerance));
  Best spherical_best;
  spherical_conditions(geometry, true, spherical_best.conditions);
  spherical_best.score = spherical_best.conditions.max_abs();
  FamilyCheck spherical = check_from(Family::spherical, spherical_best);
  // Trivial: coincident axes in the pose, and a frozen joint.
  FamilyCheck trivial;
  trivial.family = Family::trivial;
  const AxisPair pair = nearest_coincident_axes(geometry, pose);
  trivial.conditions.push_back({"axes " + std::to_string(pair.i + 1) + " and " + std::to_string(pair.j + 1) +
                                    " coincide (sin angle, distance / L)",
                                pair.residual});
  std::vector<int> frozen, lockable;
  double least_travel = kInf;
  // 5R: a joint that only rocks (rocking_travel) may be locked too, for the
  // locked-joint rule only (a near-miss of a locked-joint loop, ClassifyOptions).
  const double lockable_travel =
      n == 5 ? std::max(options.frozen_travel, options.rocking_travel) : options.frozen_travel;
  for (size_t k = 0; k < joint_travel.size(); ++k) {
    least_travel = std::min(least_travel, joint_travel[k]);
    if (joint_travel[k] <= options.frozen_travel) frozen.push_back(static_cast<int>(k));
    if (joint_travel[k] <= lockable_travel) lockable.push_back(static_cast<int>(k));
  }
  trivial.conditions.push_back({"least joint travel [rad]", least_travel});
  // A frozen joint passes when its travel is below frozen_travel; expressed
  // on the tolerance's scale so that one residual decides.
  const bool has_frozen = !frozen.empty();
  trivial.residual = has_frozen ? pair.residual : kInf;

  out.checks = {bennett, planar, spherical, trivial};
  // 5R and 6R: degenerate, then the joint count's own families.
  GeometricFit degenerate, locked;
  // The degenerate rules' own checks: coincident axes, a locked joint.
  FamilyCheck coaxial_check, locked_check;
  // The joint count's own families' best representations, in the order
  // tried, their checks the last of out.checks: the detail line and the fold
  // test read the one that fits.
  std::vector<Best> special_fits;
  CubicMotionFit cubic;
  if (n == 5 || n == 6) {
    degenerate = degenerate_fit(geometry, options.tolerance, coaxial_check);
    FamilyCheck check = coaxial_check;
    // A joint locked over the motion (no coincident axes: that is trivial):
    // the loop moves as the (n-1)R left by locking it, a degenerate loop too.
    // The degenerate check keeps the better of the two, unless one of them
    // decides the family (below).
    if (!lockable.empty() && !(trivial.residual <= options.tolerance)) {
      locked_check.family = Family::degenerate;
      locked =
          locked_fit(geometry, pose, lockable, joint_travel, options.tolerance, options.frozen_travel, locked_check);
      if (locked.residual < check.residual) check = locked_check;
    }
    out.checks.push_back(check);
    for (Family f : special_families(n)) {
      special_fits.push_back(best_for(f, geometry, false, options.tolerance));
      out.checks.push_back(check_from(f, special_fits.back()));
      // The "321" cubic-motion-polynomial loop after the doubly collapsible
      // octahedra, which are of its kind (docs/guide/families.md): decided at
      // the pose, not over representations (its Best stays empty, read by
      // neither the fold test nor the detail).
      if (f == Family::bricard_octahedral_collapsible) {
        cubic = cubic_321_fit(geometry, pose);
        special_fits.emplace_back();
        out.checks.push_back(cubic_check(cubic));
      }
    }
  }
  const double tol = options.tolerance;
  // The first of the 5R/6R families (after degenerate) that fits, in the order
  // tried; not a Goldberg-type loop one of whose Bennett loops only folds:
  // that one is degenerate (folding_goldberg), and its check is degenerate's.
  const FamilyCheck* special = nullptr;
  const Best* special_fit = nullptr;
  FoldingGoldberg folding;
  const size_t first_special = out.checks.size() - special_fits.size();
  for (size_t i = 0; i < special_fits.size() && !special; ++i) {
    const FamilyCheck& c = out.checks[first_special + i];
    if (!(c.residual <= tol)) continue;
    FoldingGoldberg fold = folding_goldberg(c.family, special_fits[i], geometry, c.residual, tol);
    if (!fold.folds) {
      special = &c;
      special_fit = &special_fits[i];
    } else if (!folding.folds) {
      folding = std::move(fold);
    }
  }
  if (folding.folds && !special) {
    for (FamilyCheck& c : out.checks) {
      if (c.family == Family::degenerate && folding.residual < c.residual) c = folding.check;
    }
  }
  // The degenerate rule that decides the family, if one does.
  const FamilyCheck* deciding = nullptr;
  if (trivial.residual <= tol) {
    out.family = Family::trivial;
    out.residual = trivial.residual;
    out.detail = "axes " + std::to_string(pair.i + 1) + " and " + std::to_string(pair.j + 1) + " coincide; joint";
    out.detail += frozen.size() > 1 ? "s" : "";
    for (size_t k = 0; k < frozen.size(); ++k) out.detail += (k ? ", " : " ") + std::to_string(frozen[k] + 1);
    out.detail += " frozen";
  } else if (planar.residual <= tol) {
    out.family = Family::planar;
    out.residual = planar.residual;
    out.detail = "all joint axes parallel";
  } else if (spherical.residual <= tol) {
    out.family = Family::spherical;
    out.residual = spherical.residual;
    out.detail = "all joint axes through one point";
  } else if (degenerate.residual <= tol) {
    out.family = Family::degenerate;
    out.residual = degenerate.residual;
    out.detail = degenerate.detail;
    deciding = &coaxial_check;
  } else if (special) {
    out.family = special->family;
    out.residual = special->residual;
    out.detail = special->family == Family::cubic_321 ? cubic_detail(cubic)
                                                      : special_detail(special->family, *special_fit, geometry);
    // A member whose motion found is another one (some members have several).
    if (locked.residual <= tol) out.detail += "; the motion found: " + locked.detail;
  } else if (folding.folds) {
    out.family = Family::degenerate;
    out.residual = folding.residual;
    out.detail = folding.detail;
    if (locked.residual <= tol) out.detail += "; the motion found: " + locked.detail;
    deciding = &folding.check;
  } else if (locked.residual <= tol) {
    out.family = Family::degenerate;
    out.residual = locked.residual;
    out.detail = locked.detail;
    deciding = &locked_check;
  } else if (bennett.residual <= tol) {
    out.family = Family::bennett;
    out.setup = bennett.setup;
    out.residual = bennett.residual;
    out.detail = std::string(to_string(bennett.setup)) + " setup";
  } else {
    const FamilyCheck* nearest = &out.checks.front();
    for (const FamilyCheck& c : out.checks) {
      if (c.residual < nearest->residual) nearest = &c;
    }
    out.residual = nearest->residual;
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "nearest family: %s (residual %.3g)", to_string(nearest->family),
                  nearest->residual);
    out.detail = buffer;
  }
  // The degenerate check shown is the rule that decided, so that it agrees
  // with the family's residual and detail, although another rule may read a
  // smaller residual (a coaxial pair decides before a locked joint).
  if (deciding) {
    for (FamilyCheck& c : out.checks) {
      if (c.family == Family::degenerate) c = *deciding;
    }
  }
  if (out.family != Family::unclassified) out.fitting.push_back(out.family);
  const auto add_fitting = [&](Family f, double residual) {
    if (residual <= tol && std::find(out.fitting.begin(), out.fitting.end(), f) == out.fitting.end()) {
      out.fitting.push_back(f);
    }
  };
  add_fitting(Family::trivial, trivial.residual);
  for (const FamilyCheck& c : out.checks) {
    if (c.family != Family::bennett && c.family != Family::trivial) add_fitting(c.family, c.residual);
  }
  add_fitting(Family::bennett, bennett.residual);
  return out;
}

}  // namespace loopfarm
