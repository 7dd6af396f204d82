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

GeometricFit geometric_fit(const LoopGeometry& g, double tolerance) {
  const int n = g.joints();
  GeometricFit best;
  std::vector<Family> families = {Family::planar, Family::spherical};
  for (Family f : special_families(n)) families.push_back(f);
  for (Family f : families) {
    const FamilyCheck c = family_check(f, g, tolerance);
    if (c.residual < best.residual && !(best.residual <= tolerance)) {
      best = {f, c.residual, to_string(f)};
      if (f == Family::bennett) best.detail += std::string(" (") + to_string(c.setup) + " setup)";
    }
  }
  if (n == 5) {
    FamilyCheck degenerate;
    const GeometricFit d = degenerate_fit(g, tolerance, degenerate);
    if (d.residual < best.residual) best = d;
  }
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
