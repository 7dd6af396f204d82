// The fit of a loop to the known families by its geometry alone (family_fit.hpp):
// the best representation of each family, and the degenerate loops whose merged
// loop fits one.
#include "family_fit.hpp"

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

namespace loopfarm::detail {
namespace {

// The loop with joints k and k + 1 merged (a_k = 0 and alpha_k snapped to 0
// or pi): joint k keeps offset d_k +- d_{k+1}, the next link's twist gains
// the snapped alpha_k. T_k T_{k+1} = Rz(theta_k +- theta_{k+1})
// Tz(d_k +- d_{k+1}) Tx(a_{k+1}) Rx(alpha_{k+1} + alpha_k) exactly when
// a_k = 0 and alpha_k is 0 (+) or pi (-).
LoopGeometry merged_loop(const LoopGeometry& g, int k) {
  const LoopGeometry w = relabelled(g, k);
  const int n = g.joints();
  const bool flipped = std::cos(w.alpha[0]) < 0.0;
  LoopGeometry r;
  r.a = w.a.tail(n - 1);
  r.alpha = w.alpha.tail(n - 1);
  r.d.resize(n - 1);
  r.d[0] = w.d[0] + (flipped ? -w.d[1] : w.d[1]);
  r.d.tail(n - 2) = w.d.tail(n - 2);
  if (flipped) r.alpha[0] = wrap_angle(r.alpha[0] + kPi);
  return r;
}

}  // namespace

FamilyCheck check_from(Family family, const Best& best) {
  FamilyCheck check;
  check.family = family;
  check.residual = best.score;
  for (size_t i = 0; i < best.conditions.values.size(); ++i) {
    check.conditions.push_back({best.conditions.names[i], best.conditions.values[i]});
  }
  return check;
}

// ---------------------------------------------------------------------------
// Families decided by the geometry alone, by joint count, for classify() and
// for the merged loop of a degenerate one.

Best best_for(Family family, const LoopGeometry& g, bool by_norm, double zero_length) {
  switch (family) {
    case Family::bennett:
      return best_over_representations<Family::bennett>(g, by_norm, zero_length);
    case Family::planar:
      return best_over_representations<Family::planar>(g, by_norm, zero_length);
    case Family::trivial:
      return best_over_representations<Family::trivial>(g, by_norm, zero_length);
    case Family::goldberg:
      return best_over_representations<Family::goldberg>(g, by_norm, zero_length);
    case Family::myard:
      return best_over_representations<Family::myard>(g, by_norm, zero_length);
    case Family::goldberg_bent:
      return best_over_representations<Family::goldberg_bent>(g, by_norm, zero_length);
    case Family::bricard_line_symmetric:
      return best_over_representations<Family::bricard_line_symmetric>(g, by_norm, zero_length);
    case Family::bricard_plane_symmetric:
      return best_over_representations<Family::bricard_plane_symmetric>(g, by_norm, zero_length);
    case Family::bricard_trihedral:
      return best_over_representations<Family::bricard_trihedral>(g, by_norm, zero_length);
    case Family::bennett_pair:
      return best_over_representations<Family::bennett_pair>(g, by_norm, zero_length);
    case Family::bennett_dyads:
      return best_over_representations<Family::bennett_dyads>(g, by_norm, zero_length);
    case Family::bennett_triads:
      return best_over_representations<Family::bennett_triads>(g, by_norm, zero_length);
    case Family::coupled_bennett_dyads:
      return best_over_representations<Family::coupled_bennett_dyads>(g, by_norm, zero_length);
    case Family::sarrus:
      return best_over_representations<Family::sarrus>(g, by_norm, zero_length);
    case Family::bricard_octahedral_plane:
      return best_over_representations<Family::bricard_octahedral_plane>(g, by_norm, zero_length);
    case Family::waldron_hybrid:
      return best_over_representations<Family::waldron_hybrid>(g, by_norm, zero_length);
    case Family::goldberg_6r:
      return best_over_representations<Family::goldberg_6r>(g, by_norm, zero_length);
    case Family::double_goldberg:
      return best_over_representations<Family::double_goldberg>(g, by_norm, zero_length);
    case Family::hooke:
      return best_over_representations<Family::hooke>(g, by_norm, zero_length);
    case Family::angle_symmetric_parallel:
      return best_over_representations<Family::angle_symmetric_parallel>(g, by_norm, zero_length);
    case Family::bricard_octahedral_collapsible:
      return best_over_representations<Family::bricard_octahedral_collapsible>(g, by_norm, zero_length);
    case Family::spherical:
    case Family::degenerate:
    case Family::cubic_321:
    case Family::unclassified:
      break;
  }
  throw std::logic_error(std::string("best_for: no representations for ") + to_string(family));
}

FamilyCheck family_check(Family family, const LoopGeometry& g, double zero_length) {
  Best best;
  if (family == Family::spherical) {
    spherical_conditions(g, true, best.conditions);
    best.score = best.conditions.max_abs();
  } else {
    best = best_for(family, g, false, zero_length);
  }
  FamilyCheck check = check_from(family, best);
  if (family == Family::bennett) {
    check.setup = best.setup_sign > 0 ? BennettSetup::asymmetric : BennettSetup::line_symmetric;
  }
  if (goldberg_type(family)) check.setup = BennettSetup::none;
  return check;
}

std::vector<Family> special_families(int n) {
  switch (n) {
    case 4:
      return {Family::bennett};
    case 5:
      return {Family::myard, Family::goldberg, Family::goldberg_bent};
    case 6:
      return {Family::bricard_trihedral,
              Family::bricard_plane_symmetric,
              Family::bricard_line_symmetric,
              Family::bennett_pair,
              Family::goldberg_6r,
              Family::double_goldberg,
              Family::bennett_triads,
              Family::coupled_bennett_dyads,
              Family::bennett_dyads,
              Family::waldron_hybrid,
              Family::sarrus,
              Family::angle_symmetric_parallel,
              Family::bricard_octahedral_plane,
              Family::bricard_octahedral_collapsible,
              Family::hooke};
    default:
      return {};
  }
}

FoldingGoldberg folding_goldberg(Family family, const Best& best, const LoopGeometry& g, double family_residual,
                                 double tolerance) {
  FoldingGoldberg out;
  if (!goldberg_type(family)) return out;
  const LoopGeometry w = written_out(best, g);
  const double L = length_scale(w);
  auto fold = [&](int loop, double& length, double& denominator) {
    const int link = loop + 1;
    const bool line_symmetric = ((best.set >> loop) & 1) != 0;
    const double half = 0.5 * (w.alpha[link] - w.alpha[0]);
    length = (w.a[link] - w.a[0]) / L;
    denominator = line_symmetric ? std::cos(half) : std::sin(half);
    return std::abs(length) <= tolerance && std::abs(denominator) <= tolerance;
  };
  for (int loop = 0; loop < 2; ++loop) {
    double length = 0.0, denominator = 0.0;
    if (!fold(loop, length, denominator)) continue;
    out.folds = true;
    out.residual = std::max({family_residual, std::abs(length), std::abs(denominator)});
    // The links of the folding loop in the 5R (representation links 1, 2 or 3, and 4,
    // which equals 1) and the joint it locks, in the loop's own labels; the
    // other Bennett loop (representation links 1 and 3 or 2, twice) is the 4R left.
    const detail::Representation& r = *best.representation;
    const int folded_link = loop == 0 ? 1 : 2;
    const int other_link = loop == 0 ? 2 : 1;
    std::vector<int> links = {r.index[0], r.index[static_cast<size_t>(folded_link)], r.index[3]};
    std::sort(links.begin(), links.end());
    const int locked_joint = r.angle_index[loop == 1 ? 4 : 0];
    const LoopGeometry moving =
        LoopGeometry{(JointVector(4) << w.a[0], w.a[other_link], w.a[0], w.a[other_link]).finished(),
                     (JointVector(4) << w.alpha[0], w.alpha[other_link], w.alpha[0], w.alpha[other_link]).finished(),
                     JointVector::Zero(4)};
    const GeometricFit fit = geometric_fit(moving, tolerance);
    double other_length = 0.0, other_denominator = 0.0;
    const bool both = fold(1 - loop, other_length, other_denominator);
    std::string names;
    for (int k : links) names += (names.empty() ? "" : ", ") + std::to_string(k + 1);
    out.detail = std::string(to_string(family)) + "'s conditions on a folding Bennett loop (links " + names +
                 " equal): moves with joint " + std::to_string(locked_joint + 1) +
                 " locked; locked 4R: " + to_string(fit.family) + (both ? " (folding too)" : "");
    out.check.family = Family::degenerate;
    out.check.residual = out.residual;
    out.check.conditions = {{std::string(to_string(family)) + " residual", family_residual},
                            {"folding loop: (link - link 1) / L", length},
                            {"folding loop: denominator of its angle relation", denominator}};
    return out;
  }
  return out;
}

GeometricFit geometric_fit(const LoopGeometry& g, double tolerance) {
  const int n = g.joints();
  GeometricFit best;
  // A fit replaces the best so far only while that one does not fit.
  const auto offer = [&](GeometricFit fit) {
    if (fit.residual < best.residual && !(best.residual <= tolerance)) best = std::move(fit);
  };
  for (Family f : {Family::planar, Family::spherical}) {
    offer({f, family_check(f, g, tolerance).residual, to_string(f)});
  }
  if (n == 5) {
    FamilyCheck degenerate;
    offer(degenerate_fit(g, tolerance, degenerate));
  }
  // The n-specific families: the first that fits and is no Goldberg-type
  // fit on a folding Bennett loop; the first folding one only after them.
  FoldingGoldberg folding;
  for (Family f : special_families(n)) {
    const Best fit = best_for(f, g, false, tolerance);
    const FamilyCheck c = check_from(f, fit);
    if (c.residual <= tolerance) {
      FoldingGoldberg fold = folding_goldberg(f, fit, g, c.residual, tolerance);
      if (fold.folds) {
        if (!folding.folds) folding = std::move(fold);
        continue;
      }
    }
    std::string detail = to_string(f);
    if (f == Family::bennett) {
      detail += std::string(" (") +
                to_string(fit.setup_sign > 0 ? BennettSetup::asymmetric : BennettSetup::line_symmetric) + " setup)";
    }
    offer({f, c.residual, detail});
  }
  if (folding.folds) offer({Family::degenerate, folding.residual, folding.detail});
  return best;
}

GeometricFit degenerate_fit(const LoopGeometry& g, double tolerance, FamilyCheck& check) {
  const int n = g.joints();
  const double L = length_scale(g);
  std::vector<std::pair<double, int>> pairs;
  for (int k = 0; k < n; ++k) pairs.push_back({std::max(g.a[k] / L, std::abs(std::sin(g.alpha[k]))), k});
  std::stable_sort(pairs.begin(), pairs.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  check = FamilyCheck{};
  check.family = Family::degenerate;
  check.residual = kInf;
  GeometricFit out;
  out.family = Family::degenerate;
  for (const auto& [pair_residual, k] : pairs) {
    if (!(pair_residual < out.residual)) break;
    const GeometricFit merged = geometric_fit(merged_loop(g, k), tolerance);
    const double residual = std::max(pair_residual, merged.residual);
    if (residual < out.residual) {
      out.residual = residual;
      const int j = (k + 1) % n;
      out.detail = "axes " + std::to_string(k + 1) + " and " + std::to_string(j + 1) + " coincide; merged " +
                   std::to_string(n - 1) + "R: " + merged.detail;
      check.residual = residual;
      check.conditions = {
          {label("a", k) + " / L", g.a[k] / L},
          {"sin(" + label("alpha", k) + ")", std::sin(g.alpha[k])},
          {"merged " + std::to_string(n - 1) + "R loop: " + to_string(merged.family) + " residual", merged.residual}};
    }
  }
  return out;
}

}  // namespace loopfarm::detail
