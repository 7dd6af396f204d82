// De-duplication's lookup (candidate_index.hpp).
#include "candidate_index.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <functional>

#include "loopfarm/core/loop.hpp"

namespace loopfarm::store {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;
constexpr double kRadiansPerDegree = 3.14159265358979323846 / 180.0;

// splitmix64's finaliser: every input bit moves every output bit.
std::uint64_t mix(std::uint64_t x) {
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Distinct seeds, so that a key and a cell never share a hash by construction.
constexpr std::uint64_t kKeySeed = 0x6b65792d68617368ull;
constexpr std::uint64_t kCellSeed = 0x63656c6c2d686173ull;

std::uint64_t cell_hash_start(int joints) { return mix(kCellSeed ^ static_cast<std::uint64_t>(joints)); }
std::uint64_t cell_hash_step(std::uint64_t hash, long cell) {
  return mix(hash + 0x9e3779b97f4a7c15ull + static_cast<std::uint64_t>(cell));
}

}  // namespace

double canonical_distance(const CanonicalEntry& x, const CanonicalEntry& y, double tolerance) {
  const int n = x.joints;
  double distance = 0.0;
  for (int i = 0; i < 3 * n && distance <= tolerance; ++i) {
    const double difference = x.values[i] - y.values[i];
    distance = std::max(distance, std::abs(i >= n && i < 2 * n ? wrap_angle(difference) : difference));
  }
  return distance;
}

size_t CellOptions::combinations() const {
  size_t product = 1;
  for (int i = 0; i < values; ++i) product = std::min(product * count[i], kMaxCellCombinations + 1);
  return product;
}

CellOptions cell_options(const CanonicalEntry& c, double tolerance) {
  const int n = c.joints;
  constexpr double kTwoPi = 2.0 * 3.14159265358979323846;
  CellOptions options;
  options.values = 3 * n;
  for (int i = 0; i < 3 * n; ++i) {
    const bool twist = i >= n && i < 2 * n;
    const double width = twist ? kTwoPi / kTwistCells : kGridCell;
    const double u = twist ? (c.values[i] + kTwoPi / 2) / width : c.values[i] / width;
    const double cell = std::floor(u);
    const double offset = (u - cell) * width;  // distance above the cell's lower edge
    auto wrap = [twist](long k) { return twist ? ((k % kTwistCells) + kTwistCells) % kTwistCells : k; };
    const long k = static_cast<long>(cell);
    std::array<long, 3>& o = options.cells[i];
    std::uint8_t& count = options.count[i];
    o[count++] = wrap(k);
    if (offset <= tolerance) o[count++] = wrap(k - 1);
    if (width - offset <= tolerance) o[count++] = wrap(k + 1);
  }
  return options;
}

bool next_choice(const CellOptions& options, CellChoice& choice) {
  for (int i = 0; i < options.values; ++i) {
    if (++choice[i] < options.count[i]) return true;
    choice[i] = 0;
  }
  return false;
}

std::string cell_name(const CellOptions& options, const CellChoice& choice) {
  char buffer[3 * kMaxJoints * 22];
  char* end = buffer;
  for (int i = 0; i < options.values; ++i) {
    if (i > 0) *end++ = ',';
    end = std::to_chars(end, buffer + sizeof buffer, options.cells[i][choice[i]]).ptr;
  }
  return std::string(buffer, end);
}

std::string grid_cell(const CanonicalEntry& c) { return cell_name(cell_options(c, 0.0), CellChoice{}); }

double stored_twist(double radians) { return radians * kDegreesPerRadian; }
double twist_from_stored(double degrees) { return degrees * kRadiansPerDegree; }

CanonicalEntry canonical_entry(const StartRecord& r, std::int64_t run_id) {
  const LoopGeometry& g = r.candidate.canonical_geometry;
  const int n = g.joints();
  CanonicalEntry c;
  c.key = r.candidate.canonical_key;
  c.joints = n;
  for (int i = 0; i < n; ++i) {
    c.values[i] = g.a[i];
    c.values[n + i] = twist_from_stored(stored_twist(g.alpha[i]));
    c.values[2 * n + i] = g.d[i];
  }
  c.first_run = run_id;
  c.first_start = static_cast<std::int64_t>(r.index);
  return c;
}

std::uint64_t key_hash(int joints, std::string_view key) {
  return mix(kKeySeed ^ std::hash<std::string_view>{}(key) ^ (static_cast<std::uint64_t>(joints) << 56));
}

std::uint64_t cell_hash(int joints, const CellOptions& options, const CellChoice& choice) {
  std::uint64_t hash = cell_hash_start(joints);
  for (int i = 0; i < options.values; ++i) hash = cell_hash_step(hash, options.cells[i][choice[i]]);
  return hash;
}

bool cell_hash_of_name(int joints, std::string_view text, std::uint64_t& hash) {
  hash = cell_hash_start(joints);
  const char* at = text.data();
  const char* const end = text.data() + text.size();
  for (int i = 0; i < 3 * joints; ++i) {
    if (i > 0) {
      if (at == end || *at != ',') return false;
      ++at;
    }
    long cell = 0;
    const auto [next, error] = std::from_chars(at, end, cell);
    if (error != std::errc()) return false;
    hash = cell_hash_step(hash, cell);
    at = next;
  }
  return at == end;
}

void CandidateIndex::clear() {
  slots_.clear();
  entries_ = 0;
  highest_id_ = 0;
  data_version_ = 0;
  loaded_ = false;
}

void CandidateIndex::add(std::uint64_t hash, std::int64_t id) {
  if (2 * (entries_ + 1) > slots_.size()) grow();
  const std::uint64_t h = hash == 0 ? 1 : hash;
  const size_t mask = slots_.size() - 1;
  size_t i = h & mask;
  while (slots_[i].hash != 0) i = (i + 1) & mask;
  slots_[i] = {h, id};
  ++entries_;
  highest_id_ = std::max(highest_id_, id);
}

void CandidateIndex::grow() {
  std::vector<Slot> old;
  old.swap(slots_);
  slots_.assign(std::max<size_t>(1024, 2 * old.size()), Slot{});
  const size_t mask = slots_.size() - 1;
  for (const Slot& s : old) {
    if (s.hash == 0) continue;
    size_t i = s.hash & mask;
    while (slots_[i].hash != 0) i = (i + 1) & mask;
    slots_[i] = s;
  }
}

}  // namespace loopfarm::store
