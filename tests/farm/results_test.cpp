// StartRecord: built from a StartSummary, and its byte format for MPI (bit-exact
// round trip, every truncation and corruption rejected).
#include "loopfarm/farm/results.hpp"

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "loopfarm/search/start.hpp"

namespace loopfarm {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

// A quiet NaN with a payload of its own and a negative sign, so that a
// round trip through a value conversion (rather than the bytes) would show.
double nan_with_payload() {
  const std::uint64_t bits = 0xFFF800000000BEEFull;
  double value;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

bool same_bits(double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; }

JointVector values(int n, double start, double step) {
  JointVector v(n);
  for (int i = 0; i < n; ++i) v[i] = start + step * i;
  return v;
}

LoopGeometry geometry(int n, double start) {
  LoopGeometry g;
  g.a = values(n, start, 0.25);
  g.alpha = values(n, -1.0, 0.3);
  g.d = values(n, 0.1, -0.05);
  return g;
}

// Every field set, with awkward values: NaN, infinities, -0, a subnormal,
// bytes that are not text.
StartRecord awkward_record(std::uint64_t index, int n) {
  StartRecord r;
  r.index = index;
  r.status = "stopval_reached";
  r.E_mean = nan_with_payload();
  r.E_max = kInf;
  r.objective = -0.0;
  r.evaluations = -7;
  r.seconds = std::numeric_limits<double>::denorm_min();
  r.zero = true;
  r.verified = index % 2 == 0;
  r.final_geometry = geometry(n, 1.0 + static_cast<double>(index));
  r.final_angles = values(n, 0.5, -kPi / 7);
  CandidateRecord& c = r.candidate;
  c.family = "bennett";
  c.setup = "line_symmetric";
  const char detail[] = "axes 1 and 3\0 coincide \xc3\xa9";
  c.detail = std::string(detail, sizeof detail - 1);
  c.families = "bennett,planar";
  c.family_residual = 1e-300;
  c.bennett_residual = -kInf;
  c.planar_residual = std::numeric_limits<double>::quiet_NaN();
  c.spherical_residual = std::numeric_limits<double>::max();
  c.trivial_residual = kInf;
  c.rigid_residual = 3e-13;
  c.full_turn = true;
  c.range_lo_deg = -180.0;
  c.range_hi_deg = 180.0;
  c.local_dimension = 3;
  c.free_parameters = 3 * n;
  c.singular_values = {2.5, 1.0, 1e-12, nan_with_payload()};
  c.canonical_key = "4R a=0.632456,1.264911 alpha=0.523599 d=0,0";
  c.canonical_geometry = geometry(n, 0.5);
  return r;
}

void expect_same_vector(const JointVector& x, const JointVector& y) {
  ASSERT_EQ(x.size(), y.size());
  for (int i = 0; i < x.size(); ++i) EXPECT_TRUE(same_bits(x[i], y[i])) << i;
}

void expect_same_geometry(const LoopGeometry& x, const LoopGeometry& y) {
  expect_same_vector(x.a, y.a);
  expect_same_vector(x.alpha, y.alpha);
  expect_same_vector(x.d, y.d);
}

void expect_same_record(const StartRecord& x, const StartRecord& y) {
  EXPECT_EQ(x.index, y.index);
  EXPECT_EQ(x.status, y.status);
  EXPECT_TRUE(same_bits(x.E_mean, y.E_mean));
  EXPECT_TRUE(same_bits(x.E_max, y.E_max));
  EXPECT_TRUE(same_bits(x.objective, y.objective));
  EXPECT_EQ(x.evaluations, y.evaluations);
  EXPECT_TRUE(same_bits(x.seconds, y.seconds));
  EXPECT_EQ(x.zero, y.zero);
  EXPECT_EQ(x.verified, y.verified);
  expect_same_geometry(x.final_geometry, y.final_geometry);
  expect_same_vector(x.final_angles, y.final_angles);
  const CandidateRecord& a = x.candidate;
  const CandidateRecord& b = y.candidate;
  EXPECT_EQ(a.family, b.family);
  EXPECT_EQ(a.setup, b.setup);
  EXPECT_EQ(a.detail, b.detail);
  EXPECT_EQ(a.families, b.families);
  for (auto [p, q] : {std::pair{a.family_residual, b.family_residual},
                      {a.bennett_residual, b.bennett_residual},
                      {a.planar_residual, b.planar_residual},
                      {a.spherical_residual, b.spherical_residual},
                      {a.trivial_residual, b.trivial_residual},
                      {a.rigid_residual, b.rigid_residual},
                      {a.range_lo_deg, b.range_lo_deg},
                      {a.range_hi_deg, b.range_hi_deg}}) {
    EXPECT_TRUE(same_bits(p, q)) << p << " " << q;
  }
  EXPECT_EQ(a.full_turn, b.full_turn);
  EXPECT_EQ(a.local_dimension, b.local_dimension);
  EXPECT_EQ(a.free_parameters, b.free_parameters);
  ASSERT_EQ(a.singular_values.size(), b.singular_values.size());
  for (size_t i = 0; i < a.singular_values.size(); ++i) {
    EXPECT_TRUE(same_bits(a.singular_values[i], b.singular_values[i])) << i;
  }
  EXPECT_EQ(a.canonical_key, b.canonical_key);
  expect_same_geometry(a.canonical_geometry, b.canonical_geometry);
}

std::vector<StartRecord> sample_records() {
  return {awkward_record(0, 4), awkward_record(1, 6), StartRecord{}, awkward_record(~0ull, 8)};
}

TEST(RecordBytes, RoundTripIsBitExact) {
  const std::vector<StartRecord> records = sample_records();
  std::string bytes;
  encode_records(records, bytes);
  const std::vector<StartRecord> back = decode_records(bytes);
  ASSERT_EQ(back.size(), records.size());
  for (size_t i = 0; i < records.size(); ++i) {
    SCOPED_TRACE(i);
    expect_same_record(records[i], back[i]);
  }
  // Encoding is a function of the records: the decoded ones give the same bytes.
  std::string again;
  encode_records(back, again);
  EXPECT_EQ(again, bytes);
}

TEST(RecordBytes, EmptyListAndDefaultRecordsRoundTrip) {
  std::string bytes = "left over";
  encode_records({}, bytes);
  EXPECT_EQ(bytes.size(), 12u);  // magic and count: the output is replaced, not appended to
  EXPECT_TRUE(decode_records(bytes).empty());
  // Records of the smallest size only: the bound on the count must let them through.
  encode_records(std::vector<StartRecord>(3), bytes);
  const std::vector<StartRecord> back = decode_records(bytes);
  ASSERT_EQ(back.size(), 3u);
  for (const StartRecord& r : back) expect_same_record(r, StartRecord{});
}

TEST(RecordBytes, EveryTruncationThrows) {
  std::string bytes;
  encode_records(sample_records(), bytes);
  for (size_t size = 0; size < bytes.size(); ++size) {
    EXPECT_THROW(decode_records(std::string_view(bytes).substr(0, size)), std::runtime_error) << size;
  }
}

TEST(RecordBytes, MalformedBuffersThrowNamingTheProblem) {
  std::string bytes;
  encode_records({awkward_record(2, 4)}, bytes);

  auto message = [](const std::string& buffer) {
    try {
      decode_records(buffer);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };

  EXPECT_NE(message(bytes + "x").find("left after the last record"), std::string::npos);

  std::string magic = bytes;
  magic[0] = 'X';
  EXPECT_NE(message(magic).find("LFR1"), std::string::npos);

  // A count that would need far more bytes than there are: refused before any allocation.
  std::string count = bytes;
  const std::uint64_t huge = std::numeric_limits<std::uint64_t>::max();
  std::memcpy(count.data() + 4, &huge, sizeof huge);
  EXPECT_NE(message(count).find("cannot fit"), std::string::npos);

  // The flags `zero` and `verified` follow index (8), status (4 + 15) and 3 doubles, an int, a double.
  const size_t zero_offset = 12 + 8 + 4 + 15 + 3 * 8 + 4 + 8;
  ASSERT_EQ(bytes[zero_offset], 1);
  std::string flag = bytes;
  flag[zero_offset] = 2;
  EXPECT_NE(message(flag).find("zero is 2"), std::string::npos);

  // The length of final_geometry.a: more joints than a loop can have.
  std::string joints = bytes;
  const std::uint32_t nine = 9;
  std::memcpy(joints.data() + zero_offset + 2, &nine, sizeof nine);
  EXPECT_NE(message(joints).find("at most 8"), std::string::npos);

  // A string length beyond the buffer.
  std::string status = bytes;
  const std::uint32_t long_status = 1u << 30;
  std::memcpy(status.data() + 12 + 8, &long_status, sizeof long_status);
  EXPECT_NE(message(status).find("truncated"), std::string::npos);
}

// A StartSummary of a verified zero, built by hand (no search).
StartSummary verified_summary() {
  StartSummary s;
  s.index = 41;
  s.status = SearchStatus::stopval_reached;
  s.E_mean = 1e-28;
  s.E_max = 4e-28;
  s.objective = 2e-28;
  s.evaluations = 37;
  s.seconds = 0.25;
  s.zero = true;
  s.final_geometry = geometry(4, 2.0);
  s.final_angles = values(4, 0.1, 0.2);
  s.candidate.geometry = geometry(4, 2.0 + 1e-9);  // polished onto the motion
  VerificationSummary& v = s.candidate.verification;
  v.assembled = v.verified = true;
  v.full_turn = false;
  v.range_lo = -kPi / 2;
  v.range_hi = kPi / 4;
  v.worst_residual = 5e-14;
  Classification& k = s.candidate.classification;
  k.family = Family::bennett;
  k.setup = BennettSetup::asymmetric;
  k.residual = 1e-15;
  k.detail = "asymmetric setup";
  k.fitting = {Family::bennett, Family::planar};
  k.checks = {{Family::bennett, BennettSetup::asymmetric, 1e-15, {}},
              {Family::planar, BennettSetup::none, 0.5, {}},
              {Family::spherical, BennettSetup::none, 0.75, {}},
              {Family::trivial, BennettSetup::none, kInf, {}}};
  s.candidate.canonical.geometry = geometry(4, 0.5);
  s.candidate.canonical.key = "4R a=... alpha=... d=...";
  s.candidate.local_dimension.parameters = 12;
  s.candidate.local_dimension.dimension = 3;
  s.candidate.local_dimension.singular_values = Eigen::Vector3d(3.0, 2.0, 1e-13);
  return s;
}

TEST(MakeStartRecord, VerifiedZeroCarriesItsAnalysis) {
  const StartSummary s = verified_summary();
  const StartRecord r = make_start_record(s);
  EXPECT_EQ(r.index, 41u);
  EXPECT_EQ(r.status, "stopval_reached");
  EXPECT_EQ(r.E_mean, 1e-28);
  EXPECT_EQ(r.E_max, 4e-28);
  EXPECT_EQ(r.objective, 2e-28);
  EXPECT_EQ(r.evaluations, 37);
  EXPECT_EQ(r.seconds, 0.25);
  EXPECT_TRUE(r.zero);
  EXPECT_TRUE(r.verified);
  // A verified zero's geometry is the one polished onto its motion.
  expect_same_geometry(r.final_geometry, s.candidate.geometry);
  expect_same_vector(r.final_angles, s.final_angles);
  const CandidateRecord& c = r.candidate;
  EXPECT_EQ(c.family, "bennett");
  EXPECT_EQ(c.setup, "asymmetric");
  EXPECT_EQ(c.detail, "asymmetric setup");
  EXPECT_EQ(c.families, "bennett,planar");
  EXPECT_EQ(c.family_residual, 1e-15);
  EXPECT_EQ(c.bennett_residual, 1e-15);
  EXPECT_EQ(c.planar_residual, 0.5);
  EXPECT_EQ(c.spherical_residual, 0.75);
  EXPECT_EQ(c.trivial_residual, kInf);
  EXPECT_EQ(c.rigid_residual, 5e-14);
  EXPECT_FALSE(c.full_turn);
  EXPECT_DOUBLE_EQ(c.range_lo_deg, -90.0);
  EXPECT_DOUBLE_EQ(c.range_hi_deg, 45.0);
  EXPECT_EQ(c.local_dimension, 3);
  EXPECT_EQ(c.free_parameters, 12);
  EXPECT_EQ(c.singular_values, (std::vector<double>{3.0, 2.0, 1e-13}));
  EXPECT_EQ(c.canonical_key, s.candidate.canonical.key);
  expect_same_geometry(c.canonical_geometry, s.candidate.canonical.geometry);
}

TEST(MakeStartRecord, ChecksAreTakenByFamilyNotPosition) {
  StartSummary s = verified_summary();
  // Only the planar check, in first place: the others do not apply (+inf).
  s.candidate.classification.checks = {{Family::planar, BennettSetup::none, 0.125, {}}};
  const StartRecord r = make_start_record(s);
  EXPECT_EQ(r.candidate.planar_residual, 0.125);
  EXPECT_EQ(r.candidate.bennett_residual, kInf);
  EXPECT_EQ(r.candidate.spherical_residual, kInf);
  EXPECT_EQ(r.candidate.trivial_residual, kInf);
}

TEST(MakeStartRecord, UnverifiedOrNonZeroStartsHaveNoCandidate) {
  StartSummary unverified = verified_summary();
  unverified.candidate.verification.verified = false;
  StartSummary not_zero = verified_summary();
  not_zero.zero = false;  // a stale analysis must not make it a candidate
  for (const StartSummary& s : {unverified, not_zero}) {
    const StartRecord r = make_start_record(s);
    EXPECT_EQ(r.zero, s.zero);
    EXPECT_FALSE(r.verified);
    EXPECT_TRUE(r.candidate.family.empty());
    EXPECT_TRUE(r.candidate.canonical_key.empty());
    EXPECT_EQ(r.candidate.canonical_geometry.joints(), 0);
    EXPECT_TRUE(r.candidate.singular_values.empty());
    expect_same_geometry(r.final_geometry, s.final_geometry);  // where the search stopped
  }
}

}  // namespace
}  // namespace loopfarm
