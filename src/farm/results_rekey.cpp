// Schema versions 5 to 6 and 6 to 7: the candidates whose canonical geometry
// has a zero-length link or parallel axes keyed again (results_rekey.hpp,
// results_database_impl.hpp; docs/guide/database.md, "Schema versions" and
// "De-duplication").
//
// The canonical key takes the twist at a link whose length it writes as 0
// (a_k / L quantised to 0) with either sign (version 6), and reads the
// offsets between parallel axes with their common normal centred (version
// 7). A key written before it did so may differ for a loop with such a link,
// and a run that finds the linkage again under the new key adds a second
// row; two starts of one such loop may even have stored two rows. The
// upgrade, inside the transaction of the first write that needs it, therefore
//   - recomputes, for every candidate whose stored canonical geometry has
//     such a link, its canonical_key, canonical geometry (a*, alpha*_deg, d*)
//     and grid_cell from that geometry, with the functions a run uses for a
//     new verified start, and writes those whose key changes (the rest, every
//     candidate without such a link among them, is not written);
//   - looks each row it re-keyed up among the other candidates, in the order
//     of their representatives, exactly as a run looks up a new start (by key,
//     else the nearest within the de-duplication's tolerance: find_candidate),
//     and merges a match into one row: the lower candidate_id (the one
//     committed first) stays, with the columns of the earlier representative
//     (first_run, first_start), the hits added; the starts of the other row
//     name it, and the other row goes.
// The stored canonical geometry is the only geometry of a candidate the file
// always holds, so it is what is keyed again; it is the representation the
// run's canonical_form gave, scaled to L = 1, and any representation of a loop
// gives the same key (but for a value within round-off of a quantisation
// boundary, which the numeric comparison catches).
#include "results_rekey.hpp"

#include <algorithm>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "loopfarm/farm/results.hpp"
#include "loopfarm/search/canonical.hpp"
#include "results_database_impl.hpp"
#include "results_schema.hpp"
#include "sqlite_support.hpp"

namespace loopfarm {
namespace store {

std::optional<RekeyedCandidate> rekey_candidate(const CanonicalEntry& stored) {
  const int n = stored.joints;
  if (n < kMinJoints || n > kMaxJoints) return std::nullopt;
  LoopGeometry g;
  g.a.resize(n);
  g.alpha.resize(n);
  g.d.resize(n);
  for (int i = 0; i < n; ++i) {
    g.a[i] = stored.values[i];
    g.alpha[i] = stored.values[n + i];
    g.d[i] = stored.values[2 * n + i];
  }
  try {
    if (!has_zero_length_link(g) && !has_parallel_link(g)) return std::nullopt;
    // As a run: the start's canonical form (analyse_candidate), its record
    // (make_start_record), the entry and grid cell the store computes of it
    // (place_candidate).
    StartRecord r;
    r.index = static_cast<std::uint64_t>(stored.first_start);
    const CanonicalForm form = canonical_form(g);
    r.candidate.canonical_key = form.key;
    r.candidate.canonical_geometry = form.geometry;
    if (r.candidate.canonical_key == stored.key) return std::nullopt;
    RekeyedCandidate out;
    out.entry = canonical_entry(r, stored.first_run);
    out.entry.id = stored.id;
    out.geometry = r.candidate.canonical_geometry;
    out.grid_cell = grid_cell(out.entry);
    return out;
  } catch (const std::invalid_argument&) {
    return std::nullopt;  // no loop (a negative length, too few joints...): left as it is
  }
}

}  // namespace store

using namespace store;

void ResultsDatabase::Impl::rekey_candidates() {
  // Every candidate whose key changes, with its new values.
  std::vector<RekeyedCandidate> rekeyed;
  {
    Statement all;
    all.prepare(path, db(),
                "SELECT candidate_id, canonical_key, first_run, first_start, joints, " + geometry_columns("", "") +
                    " FROM candidates ORDER BY candidate_id");
    constexpr int kGeometry = 5;
    while (all.step("cannot read the candidates")) {
      CanonicalEntry c;
      c.id = all.integer(0);
      c.key = all.text(1);
      c.first_run = all.integer(2);
      c.first_start = all.integer(3);
      c.joints = static_cast<int>(all.integer(4));
      if (c.joints < kMinJoints || c.joints > kMaxJoints) continue;
      // A row without its geometry is no loop to key.
      if (!read_canonical_values(all, kGeometry, c.joints, c)) continue;
      if (std::optional<RekeyedCandidate> r = rekey_candidate(c)) rekeyed.push_back(std::move(*r));
    }
  }
  if (rekeyed.empty()) return;

  static const std::string update_sql = [] {
    // canonical_key, then the 24 geometry columns, as candidate_columns() lists them.
    const std::vector<std::string> columns = candidate_columns();
    std::string sql = "UPDATE candidates SET canonical_key = ?1";
    for (int i = 0; i < 3 * kMaxJoints; ++i) sql += ", " + columns[5 + i] + " = ?" + std::to_string(2 + i);
    return sql + ", grid_cell = ?26 WHERE candidate_id = ?27";
  }();
  Statement update;
  update.prepare(path, db(), update_sql);
  for (const RekeyedCandidate& r : rekeyed) {
    update.reset();
    const LoopGeometry& g = r.geometry;
    const int n = g.joints();
    update.bind(1, r.entry.key);
    int p = 2;
    for (const JointVector* list : {&g.a, &g.alpha, &g.d}) {
      for (int i = 0; i < kMaxJoints; ++i, ++p) {
        if (i < n) {
          // Twists in degrees, as a run stores them (bind_candidate).
          update.bind(p, list == &g.alpha ? stored_twist((*list)[i]) : (*list)[i]);
        } else {
          update.bind_null(p);
        }
      }
    }
    update.bind(26, r.grid_cell);
    update.bind(27, r.entry.id);
    update.run("cannot re-key a candidate");
  }

  // Each re-keyed row looked up among the others, in the order of the
  // representatives, as a run looks up a new start: merged into its match.
  std::sort(rekeyed.begin(), rekeyed.end(), [](const RekeyedCandidate& x, const RekeyedCandidate& y) {
    return std::tie(x.entry.first_run, x.entry.first_start, x.entry.id) <
           std::tie(y.entry.first_run, y.entry.first_start, y.entry.id);
  });
  candidate_index.clear();  // loaded again from the table, new keys and cells
  refresh_candidate_index();
  // Every other row under the same key is merged (one linkage, however many
  // keys the build before gave it); failing that, the nearest within the
  // tolerance, once, as a run counts a start as a hit of one candidate.
  for (const RekeyedCandidate& r : rekeyed) {
    std::int64_t id = r.entry.id;
    while (true) {
      const std::optional<StoredCandidate> current = read_candidate(id);
      if (!current) break;  // merged into another row already
      const std::optional<CanonicalEntry> match = find_candidate(current->entry, kDefaultDedupTolerance, id);
      if (!match) break;
      const bool by_key = match->key == current->entry.key;
      merge_candidate_rows(std::min(id, match->id), std::max(id, match->id));
      id = std::min(id, match->id);
      if (!by_key) break;
    }
  }
  // The index holds what the transaction wrote; should it roll back, the next
  // lookup must read the table again.
  candidate_index.clear();
}

void ResultsDatabase::Impl::merge_candidate_rows(std::int64_t survivor, std::int64_t other) {
  const std::optional<StoredCandidate> kept = read_candidate(survivor);
  const std::optional<StoredCandidate> gone = read_candidate(other);
  if (!kept || !gone)
    fail(path, "cannot merge candidates " + std::to_string(survivor) + " and " + std::to_string(other));
  static const std::vector<std::string> columns = candidate_columns();
  static const std::string list = [] {
    std::string out;
    for (const std::string& c : columns) out += (out.empty() ? "" : ", ") + c;
    return out;
  }();
  // The earliest (run, start) represents the linkage, as place_candidate keeps it.
  if (std::pair(gone->entry.first_run, gone->entry.first_start) <
      std::pair(kept->entry.first_run, kept->entry.first_start)) {
    Statement take;
    take.prepare(path, db(),
                 "UPDATE candidates SET (" + list + ") = (SELECT " + list +
                     " FROM candidates WHERE candidate_id = ?1) WHERE candidate_id = ?2");
    take.bind(1, other);
    take.bind(2, survivor);
    take.run("cannot merge candidates");
  }
  Statement hits;
  hits.prepare(path, db(),
               "UPDATE candidates SET hits = hits + (SELECT hits FROM candidates WHERE candidate_id = ?1) "
               "WHERE candidate_id = ?2");
  hits.bind(1, other);
  hits.bind(2, survivor);
  hits.run("cannot merge candidates");
  Statement starts;
  starts.prepare(path, db(), "UPDATE starts SET candidate_id = ?1 WHERE candidate_id = ?2");
  starts.bind(1, survivor);
  starts.bind(2, other);
  starts.run("cannot re-point the starts of a merged candidate");
  Statement remove;
  remove.prepare(path, db(), "DELETE FROM candidates WHERE candidate_id = ?1");
  remove.bind(1, other);
  remove.run("cannot remove a merged candidate");
  // The survivor's key and cell may be the other row's now: the index must name them.
  if (const std::optional<StoredCandidate> now = read_candidate(survivor)) {
    candidate_index.add(key_hash(now->entry.joints, now->entry.key), survivor);
    std::uint64_t cell = 0;
    if (cell_hash_of_name(now->entry.joints, now->grid_cell, cell)) candidate_index.add(cell, survivor);
  }
}

}  // namespace loopfarm
