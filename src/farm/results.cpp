// The farm's flat record of a start (results.hpp): built from a StartSummary
// and turned into bytes and back for MPI.
//
// Byte format (native endianness, every number memcpy'd so doubles round-trip
// bit for bit, NaN payloads and infinities included):
//
//   "LFR1"  u64 record count  then per record:
//   u64 index, str status, f64 E_mean, f64 E_max, f64 objective, i32 evaluations, f64 seconds,
//   u8 zero, u8 verified, geometry final_geometry, vec final_angles,
//   str family, str setup, str detail, str families, f64 family/bennett/planar/spherical/trivial/rigid residuals,
//   u8 full_turn, f64 range_lo_deg, f64 range_hi_deg, i32 local_dimension, i32 free_parameters,
//   u32 count + f64 singular values, str canonical_key, geometry canonical_geometry
//
// where str is u32 length + bytes, vec is u32 length (<= kMaxJoints) + f64s and
// geometry is vec a, vec alpha, vec d.
#include "loopfarm/farm/results.hpp"

#include <array>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "loopfarm/search/start.hpp"

namespace loopfarm {
namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;
constexpr char kMagic[4] = {'L', 'F', 'R', '1'};
constexpr double kInfinity = std::numeric_limits<double>::infinity();

class Writer {
 public:
  explicit Writer(std::string& out) : out_(out) {}

  template <class T>
  void raw(const T& value) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    out_.append(bytes, sizeof(T));
  }
  void flag(bool value) { raw(static_cast<std::uint8_t>(value ? 1 : 0)); }
  void text(const std::string& value) {
    if (value.size() > std::numeric_limits<std::uint32_t>::max()) {
      throw std::invalid_argument("encode_records: a string longer than 4 GiB");
    }
    raw(static_cast<std::uint32_t>(value.size()));
    out_.append(value);
  }
  void vector(const JointVector& values) {
    raw(static_cast<std::uint32_t>(values.size()));
    for (int i = 0; i < values.size(); ++i) raw(values[i]);
  }
  void geometry(const LoopGeometry& g) {
    vector(g.a);
    vector(g.alpha);
    vector(g.d);
  }

 private:
  std::string& out_;
};

// Reads what Writer wrote, checking every size against the bytes that are
// left, so that a truncated or corrupt buffer throws instead of reading past
// its end or allocating what a bogus count asks for.
class Reader {
 public:
  explicit Reader(std::string_view bytes) : bytes_(bytes) {}

  size_t left() const { return bytes_.size() - offset_; }

  void need(size_t count, const char* what) const {
    if (count > left()) {
      throw std::runtime_error("decode_records: truncated buffer: " + std::string(what) + " needs " +
                               std::to_string(count) + " bytes at offset " + std::to_string(offset_) + ", " +
                               std::to_string(left()) + " left");
    }
  }

  template <class T>
  T raw(const char* what) {
    need(sizeof(T), what);
    T value;
    std::memcpy(&value, bytes_.data() + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  bool flag(const char* what) {
    const auto value = raw<std::uint8_t>(what);
    if (value > 1) {
      throw std::runtime_error("decode_records: malformed buffer: " + std::string(what) + " is " +
                               std::to_string(value) + ", not 0 or 1, at offset " + std::to_string(offset_ - 1));
    }
    return value == 1;
  }
  std::string text(const char* what) {
    const auto size = raw<std::uint32_t>(what);
    need(size, what);
    std::string value(bytes_.substr(offset_, size));
    offset_ += size;
    return value;
  }
  JointVector vector(const char* what) {
    const auto size = raw<std::uint32_t>(what);
    if (size > static_cast<std::uint32_t>(kMaxJoints)) {
      throw std::runtime_error("decode_records: malformed buffer: " + std::string(what) + " has " +
                               std::to_string(size) + " values, at most " + std::to_string(kMaxJoints));
    }
    need(size * sizeof(double), what);
    JointVector values(static_cast<int>(size));
    for (int i = 0; i < values.size(); ++i) values[i] = raw<double>(what);
    return values;
  }
  LoopGeometry geometry(const char* what) {
    LoopGeometry g;
    g.a = vector(what);
    g.alpha = vector(what);
    g.d = vector(what);
    return g;
  }

 private:
  std::string_view bytes_;
  size_t offset_ = 0;
};

// The smallest encoding of one record: every field present, every string and
// list empty. Bounds the record count a buffer can hold.
constexpr size_t kMinRecordBytes = 8 + 4 + 3 * 8 + 4 + 8 + 2 + 4 * 4    // index .. final_angles
                                   + 3 * 4 + 6 * 8 + 1 + 2 * 8 + 2 * 4  // family .. free_parameters
                                   + 4 + 4 + 3 * 4;                     // singular values .. canonical_geometry

}  // namespace

StartRecord make_start_record(const StartSummary& summary) {
  StartRecord r;
  r.index = summary.index;
  r.status = to_string(summary.status);
  r.E_mean = summary.E_mean;
  r.E_max = summary.E_max;
  r.objective = summary.objective;
  r.evaluations = summary.evaluations;
  r.seconds = summary.seconds;
  r.zero = summary.zero;
  r.verified = summary.zero && summary.candidate.verification.verified;
  // A verified zero's geometry is the one polished onto its motion (the
  // search's end moved by at most 1e-4 of L), which is what was verified.
  r.final_geometry = r.verified ? summary.candidate.geometry : summary.final_geometry;
  r.final_angles = summary.final_angles;
  // Only a verified zero becomes a candidate; anything else keeps the empty
  // default, so that records stay small and equal however they were reached.
  if (!r.verified) return r;

  const CandidateAnalysis& analysis = summary.candidate;
  CandidateRecord& c = r.candidate;
  const Classification& k = analysis.classification;
  c.family = to_string(k.family);
  c.setup = to_string(k.setup);
  c.detail = k.detail;
  for (Family f : k.fitting) {
    if (!c.families.empty()) c.families += ',';
    c.families += to_string(f);
  }
  c.family_residual = k.residual;
  c.bennett_residual = c.planar_residual = c.spherical_residual = c.trivial_residual = kInfinity;
  // By family rather than by position, so a reordering of the checks cannot
  // put a residual in the wrong column.
  for (const FamilyCheck& check : k.checks) {
    switch (check.family) {
      case Family::bennett:
        c.bennett_residual = check.residual;
        break;
      case Family::planar:
        c.planar_residual = check.residual;
        break;
      case Family::spherical:
        c.spherical_residual = check.residual;
        break;
      case Family::trivial:
        c.trivial_residual = check.residual;
        break;
      // The 5R and 6R families have no column of their own (yet): their
      // residual is family_residual when the loop is classified as one.
      case Family::goldberg:
      case Family::myard:
      case Family::bricard_line_symmetric:
      case Family::bricard_plane_symmetric:
      case Family::bricard_trihedral:
      case Family::goldberg_bent:
      case Family::bennett_pair:
      case Family::bennett_dyads:
      case Family::bennett_triads:
      case Family::coupled_bennett_dyads:
      case Family::sarrus:
      case Family::bricard_octahedral_plane:
      case Family::waldron_hybrid:
      case Family::goldberg_6r:
      case Family::double_goldberg:
      case Family::hooke:
      case Family::bricard_octahedral_collapsible:
      case Family::cubic_321:
      case Family::angle_symmetric_parallel:
      case Family::degenerate:
      case Family::unclassified:
        break;
    }
  }
  const VerificationSummary& v = analysis.verification;
  c.rigid_residual = v.worst_residual;
  c.full_turn = v.full_turn;
  c.range_lo_deg = v.range_lo * kDegreesPerRadian;
  c.range_hi_deg = v.range_hi * kDegreesPerRadian;
  const LocalDimension& ld = analysis.local_dimension;
  c.local_dimension = ld.dimension;
  c.free_parameters = ld.parameters;
  c.singular_values.assign(ld.singular_values.data(), ld.singular_values.data() + ld.singular_values.size());
  c.canonical_key = analysis.canonical.key;
  c.canonical_geometry = analysis.canonical.geometry;
  return r;
}

void encode_records(const std::vector<StartRecord>& records, std::string& out) {
  out.clear();
  Writer w(out);
  out.append(kMagic, sizeof kMagic);
  w.raw(static_cast<std::uint64_t>(records.size()));
  for (const StartRecord& r : records) {
    w.raw(r.index);
    w.text(r.status);
    w.raw(r.E_mean);
    w.raw(r.E_max);
    w.raw(r.objective);
    w.raw(static_cast<std::int32_t>(r.evaluations));
    w.raw(r.seconds);
    w.flag(r.zero);
    w.flag(r.verified);
    w.geometry(r.final_geometry);
    w.vector(r.final_angles);
    const CandidateRecord& c = r.candidate;
    w.text(c.family);
    w.text(c.setup);
    w.text(c.detail);
    w.text(c.families);
    w.raw(c.family_residual);
    w.raw(c.bennett_residual);
    w.raw(c.planar_residual);
    w.raw(c.spherical_residual);
    w.raw(c.trivial_residual);
    w.raw(c.rigid_residual);
    w.flag(c.full_turn);
    w.raw(c.range_lo_deg);
    w.raw(c.range_hi_deg);
    w.raw(static_cast<std::int32_t>(c.local_dimension));
    w.raw(static_cast<std::int32_t>(c.free_parameters));
    w.raw(static_cast<std::uint32_t>(c.singular_values.size()));
    for (double s : c.singular_values) w.raw(s);
    w.text(c.canonical_key);
    w.geometry(c.canonical_geometry);
  }
}

std::vector<StartRecord> decode_records(std::string_view bytes) {
  Reader in(bytes);
  const auto magic = in.raw<std::array<char, 4>>("the header");
  if (std::memcmp(magic.data(), kMagic, sizeof kMagic) != 0) {
    throw std::runtime_error("decode_records: malformed buffer: it does not start with \"LFR1\"");
  }
  const auto count = in.raw<std::uint64_t>("the record count");
  if (count > in.left() / kMinRecordBytes) {
    throw std::runtime_error("decode_records: malformed buffer: " + std::to_string(count) + " records cannot fit in " +
                             std::to_string(in.left()) + " bytes");
  }
  std::vector<StartRecord> records(static_cast<size_t>(count));
  for (StartRecord& r : records) {
    r.index = in.raw<std::uint64_t>("index");
    r.status = in.text("status");
    r.E_mean = in.raw<double>("E_mean");
    r.E_max = in.raw<double>("E_max");
    r.objective = in.raw<double>("objective");
    r.evaluations = in.raw<std::int32_t>("evaluations");
    r.seconds = in.raw<double>("seconds");
    r.zero = in.flag("zero");
    r.verified = in.flag("verified");
    r.final_geometry = in.geometry("final_geometry");
    r.final_angles = in.vector("final_angles");
    CandidateRecord& c = r.candidate;
    c.family = in.text("family");
    c.setup = in.text("setup");
    c.detail = in.text("detail");
    c.families = in.text("families");
    c.family_residual = in.raw<double>("family_residual");
    c.bennett_residual = in.raw<double>("bennett_residual");
    c.planar_residual = in.raw<double>("planar_residual");
    c.spherical_residual = in.raw<double>("spherical_residual");
    c.trivial_residual = in.raw<double>("trivial_residual");
    c.rigid_residual = in.raw<double>("rigid_residual");
    c.full_turn = in.flag("full_turn");
    c.range_lo_deg = in.raw<double>("range_lo_deg");
    c.range_hi_deg = in.raw<double>("range_hi_deg");
    c.local_dimension = in.raw<std::int32_t>("local_dimension");
    c.free_parameters = in.raw<std::int32_t>("free_parameters");
    const auto singular = in.raw<std::uint32_t>("singular_values");
    in.need(static_cast<size_t>(singular) * sizeof(double), "singular_values");
    c.singular_values.resize(singular);
    for (double& s : c.singular_values) s = in.raw<double>("singular_values");
    c.canonical_key = in.text("canonical_key");
    c.canonical_geometry = in.geometry("canonical_geometry");
  }
  if (in.left() != 0) {
    throw std::runtime_error("decode_records: malformed buffer: " + std::to_string(in.left()) +
                             " bytes left after the last record");
  }
  return records;
}

}  // namespace loopfarm
