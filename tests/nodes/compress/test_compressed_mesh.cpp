#include "nodes/compress/compressed_mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <string>

#include "graph/pipeline.h"
#include "nodes/compress/coordinate_snap.h"
#include "nodes/compress/edgebreaker_replay.h"
#include "nodes/compress/parallelogram_ring.h"
#include "nodes/compress/progressive_mesh.h"
#include "nodes/compress/range_coder.h"
#include "nodes/io/byte_buffer.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/synthetic/scan_simulator.h"
#include "runtime/error.h"
#include "runtime/threads.h"
#include "test_support.h"

namespace meshflow {
namespace {

using compress::CompressConfig;
using compress::CompressReport;
using test::grid_mesh;
using test::messy_mesh;
using test::tetrahedron;

// A torus (genus 1) of n x m quads, radii 1 and 0.3, closed, counter-clockwise from outside.
TriangleMesh torus(std::uint32_t n, std::uint32_t m) {
  TriangleMesh t;
  for (std::uint32_t i = 0; i < n; ++i)
    for (std::uint32_t j = 0; j < m; ++j) {
      const double u = 2 * M_PI * i / n, v = 2 * M_PI * j / m;
      t.vertices.emplace_back(static_cast<float>((1 + 0.3 * std::cos(v)) * std::cos(u)),
                              static_cast<float>((1 + 0.3 * std::cos(v)) * std::sin(u)),
                              static_cast<float>(0.3 * std::sin(v)));
    }
  const auto id = [&](std::uint32_t i, std::uint32_t j) { return (i % n) * m + (j % m); };
  for (std::uint32_t i = 0; i < n; ++i)
    for (std::uint32_t j = 0; j < m; ++j) {
      t.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      t.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return t;
}

// A UV sphere of radius 1 (two poles), closed.
TriangleMesh sphere(std::uint32_t rings, std::uint32_t sectors) {
  TriangleMesh s;
  s.vertices.emplace_back(0.0f, 0.0f, 1.0f);
  for (std::uint32_t r = 1; r < rings; ++r)
    for (std::uint32_t k = 0; k < sectors; ++k) {
      const double theta = M_PI * r / rings, phi = 2 * M_PI * k / sectors;
      s.vertices.emplace_back(static_cast<float>(std::sin(theta) * std::cos(phi)),
                              static_cast<float>(std::sin(theta) * std::sin(phi)),
                              static_cast<float>(std::cos(theta)));
    }
  s.vertices.emplace_back(0.0f, 0.0f, -1.0f);
  const auto ring = [&](std::uint32_t r, std::uint32_t k) {
    return 1 + (r - 1) * sectors + k % sectors;
  };
  const auto south = static_cast<std::uint32_t>(s.vertices.size() - 1);
  for (std::uint32_t k = 0; k < sectors; ++k) {
    s.triangles.push_back({0, ring(1, k), ring(1, k + 1)});
    s.triangles.push_back({south, ring(rings - 1, k + 1), ring(rings - 1, k)});
  }
  for (std::uint32_t r = 1; r + 1 < rings; ++r)
    for (std::uint32_t k = 0; k < sectors; ++k) {
      s.triangles.push_back({ring(r, k), ring(r + 1, k), ring(r + 1, k + 1)});
      s.triangles.push_back({ring(r, k), ring(r + 1, k + 1), ring(r, k + 1)});
    }
  return s;
}

// a's triangles followed by b's (two components).
TriangleMesh joined(const TriangleMesh& a, const TriangleMesh& b) {
  TriangleMesh out = a;
  const auto offset = static_cast<std::uint32_t>(a.vertices.size());
  out.vertices.insert(out.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (Triangle t : b.triangles)
    out.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return out;
}

// Random triangles over few vertices: every kind of cut, non-manifold edge and vertex.
TriangleMesh soup(std::uint32_t vertices, std::uint32_t triangles, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> coordinate(-1.0f, 1.0f);
  std::uniform_int_distribution<std::uint32_t> vertex(0, vertices - 1);
  TriangleMesh m;
  for (std::uint32_t i = 0; i < vertices; ++i)
    m.vertices.emplace_back(coordinate(rng), coordinate(rng), coordinate(rng));
  for (std::uint32_t i = 0; i < triangles; ++i)
    m.triangles.push_back({vertex(rng), vertex(rng), vertex(rng)});
  return m;
}

// `t` rotated to start at its smallest corner (orientation kept).
Triangle canonical(Triangle t) {
  while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
  return t;
}

// Decoded equals the input through the report's orders: same triangles (each possibly rotated,
// never flipped), positions within half a step per axis, normals within 0.26 degrees, colours
// exact.
void expect_same_mesh(const TriangleMesh& input, const TriangleMesh& decoded,
                      const CompressReport& report) {
  ASSERT_EQ(decoded.vertices.size(), input.vertices.size());
  ASSERT_EQ(decoded.triangles.size(), input.triangles.size());
  ASSERT_EQ(report.vertex_order.size(), input.vertices.size());
  ASSERT_EQ(report.triangle_order.size(), input.triangles.size());
  std::vector<std::uint32_t> seen(input.triangles.size(), 0);
  for (std::size_t k = 0; k < decoded.triangles.size(); ++k) {
    const Triangle& d = decoded.triangles[k];
    const Triangle mapped{report.vertex_order[d[0]], report.vertex_order[d[1]],
                          report.vertex_order[d[2]]};
    const std::uint32_t source = report.triangle_order[k];
    ASSERT_LT(source, input.triangles.size());
    ++seen[source];
    // Triangles with a repeated corner have no rotation to normalise; compare as given.
    EXPECT_EQ(canonical(mapped), canonical(input.triangles[source])) << "triangle " << k;
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](std::uint32_t c) { return c == 1; }));
  const double bound = report.quantizer.step / 2 * (1 + 1e-6) + 1e-6;
  for (std::size_t k = 0; k < decoded.vertices.size(); ++k) {
    const Eigen::Vector3f& want = input.vertices[report.vertex_order[k]];
    EXPECT_LE((decoded.vertices[k] - want).cwiseAbs().maxCoeff(), bound) << "vertex " << k;
    if (!input.normals.empty()) {
      const Eigen::Vector3f& n = input.normals[report.vertex_order[k]];
      EXPECT_GT(decoded.normals[k].dot(n.normalized()), std::cos(0.26 * M_PI / 180)) << k;
    }
    if (!input.colors.empty()) {
      const Rgb8 a = decoded.colors[k], b = input.colors[report.vertex_order[k]];
      EXPECT_TRUE(a.r == b.r && a.g == b.g && a.b == b.b) << "vertex " << k;
    }
  }
}

// Compresses, decodes and compares; returns the compression's report.
CompressReport round_trip(const TriangleMesh& mesh, const CompressConfig& config = {}) {
  CompressReport report;
  const std::vector<unsigned char> bytes = compress::compress_mesh(mesh, config, &report);
  EXPECT_EQ(report.total_bytes, bytes.size());
  expect_same_mesh(mesh, compress::decompress_mesh(bytes, "memory"), report);
  return report;
}

TEST(RangeCoder, IntegersAndSymbolsRoundTrip) {
  std::mt19937 rng(7);
  std::vector<std::int32_t> values = {0, 1, -1, 2147483647, -2147483647 - 1, 12345, -77};
  for (int i = 0; i < 5000; ++i) values.push_back(static_cast<std::int32_t>(rng()) >> (rng() % 32));
  compress::RangeEncoder enc;
  compress::IntegerModel model;
  compress::FrequencyModel<8> symbols;
  for (std::size_t i = 0; i < values.size(); ++i) {
    model.encode(enc, values[i]);
    symbols.encode(enc, static_cast<unsigned>(i % 6));
    enc.encode_direct(static_cast<std::uint32_t>(i) & 0x1FFFu, 13);
  }
  const std::vector<unsigned char> bytes = enc.finish();
  compress::RangeDecoder dec(bytes.data(), bytes.size(), "memory", "test");
  compress::IntegerModel model2;
  compress::FrequencyModel<8> symbols2;
  for (std::size_t i = 0; i < values.size(); ++i) {
    ASSERT_EQ(model2.decode(dec), values[i]) << i;
    ASSERT_EQ(symbols2.decode(dec), i % 6) << i;
    ASSERT_EQ(dec.decode_direct(13), static_cast<std::uint32_t>(i) & 0x1FFFu) << i;
  }
  EXPECT_NO_THROW(dec.check());
}

// IntegerModel::cost() predicts what encode() spends: summed over a stream of skewed values,
// the estimates match the coded size within 1 % (the coder's overhead is a few bytes).
TEST(RangeCoder, IntegerCostMatchesCodedSize) {
  std::mt19937 rng(11);
  std::geometric_distribution<std::int32_t> magnitude(0.2);
  compress::RangeEncoder enc;
  compress::IntegerModel model;
  std::uint64_t sixteenths = 0;
  for (int i = 0; i < 20000; ++i) {
    const std::int32_t v = (rng() & 1u) != 0 ? magnitude(rng) : -magnitude(rng);
    sixteenths += model.cost(v);
    model.encode(enc, v);
  }
  const double estimated = static_cast<double>(sixteenths) / 128.0;  // bytes
  const auto coded = static_cast<double>(enc.finish().size());
  EXPECT_NEAR(estimated, coded, 0.01 * coded) << estimated << " estimated, " << coded << " coded";
}

// A FrequencyModel codes a stationary source of 32 symbols within 1 % (plus the coder's few
// bytes) of its entropy, and every symbol round-trips; the cost estimates add up to the coded
// size within 1 %. The distribution: geometric (p = 0.3), with symbol 31 never drawn.
TEST(RangeCoder, FrequencyModelCodesNearTheEntropy) {
  std::mt19937 rng(5);
  std::geometric_distribution<unsigned> draw(0.3);
  std::vector<unsigned> symbols;
  std::array<double, 32> histogram{};
  while (symbols.size() < 40000) {
    const unsigned s = draw(rng);
    if (s >= 31) continue;
    symbols.push_back(s);
    histogram[s] += 1.0;
  }
  double entropy_bits = 0.0;
  for (double h : histogram)
    if (h > 0.0) entropy_bits -= h * std::log2(h / static_cast<double>(symbols.size()));
  compress::RangeEncoder enc;
  compress::FrequencyModel<32> model;
  std::uint64_t sixteenths = 0;
  for (unsigned s : symbols) {
    sixteenths += model.cost(s);
    model.encode(enc, s);
  }
  const std::vector<unsigned char> bytes = enc.finish();
  const double entropy_bytes = entropy_bits / 8.0;
  EXPECT_LT(static_cast<double>(bytes.size()), 1.01 * entropy_bytes + 16.0)
      << bytes.size() << " bytes, entropy " << entropy_bytes;
  EXPECT_NEAR(static_cast<double>(sixteenths) / 128.0, static_cast<double>(bytes.size()),
              0.01 * static_cast<double>(bytes.size()));
  compress::RangeDecoder dec(bytes.data(), bytes.size(), "memory", "test");
  compress::FrequencyModel<32> model2;
  for (std::size_t i = 0; i < symbols.size(); ++i) ASSERT_EQ(model2.decode(dec), symbols[i]) << i;
  EXPECT_NO_THROW(dec.check());
}

TEST(Edgebreaker, ClosedSurfacesRoundTripExactly) {
  round_trip(tetrahedron());
  round_trip(sphere(24, 32));
  CompressReport report;
  const TriangleMesh t = torus(40, 24);
  compress::compress_mesh(t, {}, &report);
  EXPECT_GE(report.body.handles, 1u) << "a genus-1 surface has a handle";
  EXPECT_EQ(report.body.holes, 0u);
  round_trip(t);
}

// The symbols are coded last first in the context of the rebuilt triangles at the gate's
// vertices: on a mesh whose vertices all have six triangles, that context nearly decides each
// symbol (0.14 bits per triangle here; coded first to last with the two symbols before as
// context it took 0.27).
TEST(Edgebreaker, ValenceContextsMakeRegularConnectivityCheap) {
  const TriangleMesh t = torus(100, 60);
  CompressReport report;
  round_trip(t);
  compress::compress_mesh(t, {}, &report);
  EXPECT_LT(8.0 * static_cast<double>(report.body.connectivity_bytes) /
                static_cast<double>(t.triangles.size()),
            0.2);
}

// The replay's edge diamonds name every edge of the decoded surface once with its two third
// vertices, and the parallelogram ring offers vertex k exactly the parallelograms a brute-force
// search of the decoded triangles finds (x, y, w all before k; at most four, as the ring caps):
// a sphere, a torus (an M symbol), a bordered grid (a hole vertex) and two components.
TEST(ParallelogramRing, OffersWhatABruteForceSearchFinds) {
  for (const TriangleMesh& mesh :
       {sphere(9, 13), torus(17, 11), grid_mesh(9), joined(sphere(5, 7), torus(9, 6))}) {
    const compress::ClosedSurface surface = compress::build_closed_surface(mesh.triangles);
    const compress::Traversal walk = compress::edgebreaker_traverse(surface);
    const compress::Connectivity& c = walk.connectivity;
    const std::size_t vertices = walk.surface_vertex.size();
    compress::ReverseReplay replay(c.components, c.ops.size(), vertices, c.handles, "test");
    while (replay.next() != compress::ReverseReplay::Step::kDone) {
      if (replay.next() == compress::ReverseReplay::Step::kSymbol)
        replay.apply(c.ops[replay.symbols_left() - 1]);
      else
        replay.answer(replay.symbols_left() == walk.component_first_symbol[replay.component()]);
    }
    const compress::ReplayedSurface r = replay.finish();
    // Brute force: each edge's third vertices from the triangles.
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> thirds;
    for (const Triangle& t : r.triangles)
      for (std::size_t j = 0; j < 3; ++j) {
        const std::uint32_t x = t[(j + 1) % 3], y = t[(j + 2) % 3];
        thirds[{std::min(x, y), std::max(x, y)}].push_back(t[j]);
      }
    ASSERT_EQ(r.diamonds.size(), thirds.size());
    for (const compress::EdgeDiamond& d : r.diamonds) {
      const auto it = thirds.find({std::min(d.x, d.y), std::max(d.x, d.y)});
      ASSERT_NE(it, thirds.end());
      ASSERT_EQ(it->second.size(), 2u);
      EXPECT_EQ(std::minmax(d.left, d.right), std::minmax(it->second[0], it->second[1]));
    }
    // Arbitrary integer positions, distinct per vertex.
    std::vector<std::array<std::int32_t, 3>> grid(vertices);
    for (std::uint32_t v = 0; v < vertices; ++v)
      grid[v] = {static_cast<std::int32_t>(v), static_cast<std::int32_t>(3 * v * v % 1009),
                 static_cast<std::int32_t>(v % 7)};
    const std::vector<char> hole(vertices, 0);
    const compress::ParallelogramRing ring(r.diamonds, hole, vertices);
    std::size_t offered = 0;
    for (std::uint32_t k = 0; k < vertices; ++k) {
      std::vector<std::array<std::int64_t, 3>> expected;
      for (const auto& [edge, third] : thirds) {
        const std::uint32_t hi = std::max(third[0], third[1]), lo = std::min(third[0], third[1]);
        if (hi != k || edge.second >= k) continue;
        std::array<std::int64_t, 3> p{};
        for (std::size_t a = 0; a < 3; ++a)
          p[a] = std::int64_t{grid[edge.first][a]} + grid[edge.second][a] - grid[lo][a];
        expected.push_back(p);
      }
      compress::ParallelogramRing::Parallelograms got{};
      const unsigned n = ring.gather(k, grid, got);
      ASSERT_EQ(n, std::min<std::size_t>(expected.size(), 4)) << "vertex " << k;
      for (unsigned i = 0; i < n; ++i)
        EXPECT_NE(std::find(expected.begin(), expected.end(), got[i]), expected.end())
            << "vertex " << k << " parallelogram " << i;
      offered += n;
    }
    EXPECT_GT(offered, vertices / 2);
  }
}

TEST(Edgebreaker, BordersComponentsAndLooseVerticesRoundTrip) {
  round_trip(grid_mesh(30));  // one border loop
  TriangleMesh two = joined(sphere(10, 12), joined(grid_mesh(8), torus(12, 8)));
  two.vertices.emplace_back(5.0f, 5.0f, 5.0f);  // on no triangle
  CompressReport report;
  compress::compress_mesh(two, {}, &report);
  EXPECT_EQ(report.body.holes, 1u);
  round_trip(two);
  TriangleMesh holed = grid_mesh(20);  // several holes: drop a few separated triangles
  for (std::size_t k : {300u, 120u, 44u})
    holed.triangles.erase(holed.triangles.begin() + static_cast<std::ptrdiff_t>(k));
  round_trip(holed);
}

TEST(Edgebreaker, NonManifoldInputRoundTripsThroughCutsAndMergedFans) {
  for (std::uint32_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE(seed);
    const TriangleMesh messy = messy_mesh(12, seed);
    CompressReport report;
    compress::compress_mesh(messy, {}, &report);
    EXPECT_GT(report.body.merged_fans, 0u);
    round_trip(messy);
    round_trip(soup(40, 200, seed));
  }
}

TEST(Edgebreaker, NormalsAndColoursRoundTrip) {
  TriangleMesh s = sphere(16, 20);
  for (const Eigen::Vector3f& p : s.vertices) {
    s.normals.push_back(p.normalized());
    s.colors.push_back(Rgb8{static_cast<std::uint8_t>(128 + 127 * p.x()),
                            static_cast<std::uint8_t>(128 + 127 * p.y()), 40});
  }
  round_trip(s);
  CompressConfig bare;
  bare.normals = bare.colors = false;
  const TriangleMesh decoded = compress::decompress_mesh(compress::compress_mesh(s, bare), "m");
  EXPECT_TRUE(decoded.normals.empty());
  EXPECT_TRUE(decoded.colors.empty());
}

TEST(Edgebreaker, QuantisationFollowsTheStepOrTheBits) {
  const TriangleMesh s = sphere(30, 40);
  CompressReport report;
  compress::compress_mesh(s, {}, &report);
  // Default: 1/64 of the median edge.
  EXPECT_NEAR(report.quantizer.step, median_edge_length(s) / 64.0, median_edge_length(s) / 640.0);
  CompressConfig bits;
  bits.position_bits = 11;
  compress::compress_mesh(s, bits, &report);
  EXPECT_EQ(report.quantizer.bits, 11u);
  EXPECT_NEAR(report.quantizer.step, 2.0 / 2047.0, 1e-6);
  round_trip(s, bits);
  // A regular closed mesh's connectivity costs about 2 bits per triangle or less.
  compress::compress_mesh(s, {}, &report);
  EXPECT_LT(8.0 * static_cast<double>(report.body.connectivity_bytes) /
                static_cast<double>(s.triangles.size()),
            2.0);
}

TEST(Edgebreaker, EmptyMeshesAndBadInputs) {
  round_trip(TriangleMesh{});
  TriangleMesh points;
  points.vertices = {Eigen::Vector3f(1, 2, 3), Eigen::Vector3f(4, 5, 6)};
  round_trip(points);
  TriangleMesh out_of_range = tetrahedron();
  out_of_range.triangles.push_back({0, 1, 9});
  EXPECT_THROW(compress::compress_mesh(out_of_range), Error);
  TriangleMesh nan = tetrahedron();
  nan.vertices[2].x() = std::nanf("");
  EXPECT_THROW(compress::compress_mesh(nan), Error);
}

// Every error names the data and a field; nothing else escapes.
void expect_clean_error(const std::vector<unsigned char>& bytes) {
  try {
    compress::decompress_mesh(bytes, "bad.mfc");
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.mfc"), std::string::npos) << e.what();
  }
}

TEST(CompressedMeshFile, TruncatedFlippedAndWrongVersionFilesFailClearly) {
  const TriangleMesh t = torus(16, 10);
  for (const bool progressive : {false, true}) {
    SCOPED_TRACE(progressive);
    const std::vector<unsigned char> good =
        progressive ? compress::compress_progressive(t) : compress::compress_mesh(t);
    for (std::size_t cut = 0; cut < good.size(); cut += 1 + cut / 8) {
      std::vector<unsigned char> shorter(good.begin(),
                                         good.begin() + static_cast<std::ptrdiff_t>(cut));
      EXPECT_THROW(compress::decompress_mesh(shorter, "bad.mfc"), Error) << cut;
    }
    std::vector<unsigned char> flipped = good;
    flipped[good.size() / 2] ^= 0x10;
    try {
      compress::decompress_mesh(flipped, "bad.mfc");
      ADD_FAILURE() << "a flipped bit passed the checksum";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("checksum"), std::string::npos) << e.what();
    }
    std::vector<unsigned char> version = good;
    version[8] = 12;
    compress::reseal_compressed_mesh(version);
    try {
      compress::decompress_mesh(version, "bad.mfc");
      ADD_FAILURE() << "version 12 was read";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("version"), std::string::npos) << e.what();
    }
    // Flipped bits behind a valid checksum: errors (or a mesh), never a crash.
    std::uint32_t state = 99;
    for (int trial = 0; trial < 300; ++trial) {
      std::vector<unsigned char> bad = good;
      state = state * 1664525u + 1013904223u;
      const std::size_t at = 60 + state % (bad.size() - 68);
      bad[at] ^= static_cast<unsigned char>(1u << (state >> 29));
      compress::reseal_compressed_mesh(bad);
      expect_clean_error(bad);
    }
  }
}

TEST(ProgressiveMesh, FullLevelIsTheInputAndEveryLevelIsManifold) {
  for (const TriangleMesh& mesh : {torus(40, 24), sphere(24, 32), grid_mesh(30)}) {
    CompressReport report;
    CompressConfig config;
    config.splits_per_packet = 100;
    const std::vector<unsigned char> bytes = compress::compress_progressive(mesh, config, &report);
    EXPECT_GT(report.splits, mesh.vertices.size() / 2);
    EXPECT_LT(report.base_triangles, mesh.triangles.size() / 10);
    expect_same_mesh(mesh, compress::decompress_mesh(bytes, "memory"), report);
    std::size_t previous = 0;
    for (std::size_t splits = 0; splits <= report.splits; splits += 1 + splits / 3) {
      compress::ProgressiveLevel level;
      level.splits = splits;
      const TriangleMesh m = compress::decompress_progressive_level(bytes, "memory", level);
      EXPECT_EQ(m.vertices.size(), mesh.vertices.size() - report.splits + splits);
      EXPECT_GE(m.triangles.size(), previous);
      previous = m.triangles.size();
      const EdgeStatistics e = edge_statistics(m);
      EXPECT_EQ(e.non_manifold_edges, 0u) << splits;
      EXPECT_EQ(e.inconsistent_edges, 0u) << splits;
      EXPECT_EQ(e.boundary_edges == 0, edge_statistics(mesh).boundary_edges == 0) << splits;
    }
    compress::ProgressiveLevel by_triangles;
    by_triangles.triangles = mesh.triangles.size() / 2;
    const TriangleMesh half = compress::decompress_progressive_level(bytes, "memory", by_triangles);
    EXPECT_GE(half.triangles.size(), mesh.triangles.size() / 2);
    EXPECT_LE(half.triangles.size(), mesh.triangles.size() / 2 + 4);
  }
}

TEST(ProgressiveMesh, AttributesAndMessyInputRoundTrip) {
  TriangleMesh s = sphere(16, 20);
  for (const Eigen::Vector3f& p : s.vertices) {
    s.normals.push_back(p.normalized());
    s.colors.push_back(Rgb8{static_cast<std::uint8_t>(128 + 127 * p.z()), 9, 200});
  }
  for (const TriangleMesh& mesh : {s, messy_mesh(12, 3), joined(grid_mesh(6), torus(12, 8))}) {
    CompressReport report;
    const std::vector<unsigned char> bytes = compress::compress_progressive(mesh, {}, &report);
    expect_same_mesh(mesh, compress::decompress_mesh(bytes, "memory"), report);
  }
}

// The largest angle between n and its decoded octahedral code, degrees.
double octahedral_error_deg(const Eigen::Vector3f& n, unsigned bits) {
  const Eigen::Vector3f d =
      compress::octahedral_decode(compress::octahedral_encode(n, bits), bits).cast<float>();
  return std::acos(std::min(1.0, static_cast<double>(d.dot(n)))) * 180 / M_PI;
}

// The octahedral grid at b bits keeps every direction within 125 / (2^(b-1) - 1) degrees (plus
// float rounding): 0.26 at the default 10 bits, Draco's default grid (2^10 - 2 steps across
// [-1, 1], whose worst case is the same).
TEST(NormalCoding, OctahedralGridBoundHolds) {
  std::mt19937 rng(5);
  std::normal_distribution<float> g;
  for (const unsigned bits : {6u, 8u, 10u, 12u}) {
    const double bound = 125.0 / ((1 << (bits - 1)) - 1) + 0.02;
    double worst = 0;
    for (int i = 0; i < 200000; ++i) {
      const Eigen::Vector3f n = Eigen::Vector3f(g(rng), g(rng), g(rng)).normalized();
      worst = std::max(worst, octahedral_error_deg(n, bits));
    }
    EXPECT_LT(worst, bound) << bits;
    EXPECT_GT(worst, bound / 2) << bits;  // the bound is not loose
  }
  EXPECT_LT(125.0 / 511 + 0.02, 0.265);
}

// The angle between two vectors in degrees, in double precision (a float dot product near 1
// resolves only about 0.02 degrees).
double angle_degrees(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  const Eigen::Vector3d x = a.cast<double>(), y = b.cast<double>();
  return std::atan2(x.cross(y).norm(), x.dot(y)) * 180 / M_PI;
}

// A mesh whose normals are its area-weighted face normals (as the extractors write them).
TriangleMesh with_face_normals(TriangleMesh m) {
  compute_vertex_normals(m);
  return m;
}

// Normals predicted from the decoded one ring cost a few bits each where the normals follow
// the surface (version 2 coded each from a neighbour's code at 12 bits: 18.7 bits per normal on
// kurt3d scan000 at 5 cm, issue 57; version 3 there: 6.6 at 10 bits).
TEST(NormalCoding, GeometricPredictionMakesSurfaceNormalsCheap) {
  const TriangleMesh mesh = with_face_normals(sphere(80, 120));
  for (const unsigned bits : {8u, 10u, 12u}) {
    CompressConfig config;
    config.normal_bits = bits;
    CompressReport report;
    const std::vector<unsigned char> bytes = compress::compress_mesh(mesh, config, &report);
    const double per_normal =
        8.0 * static_cast<double>(report.body.attribute_bytes) / mesh.vertices.size();
    RecordProperty("bits_per_normal_" + std::to_string(bits), std::to_string(per_normal));
    EXPECT_LT(per_normal, bits <= 10 ? 4.5 : 8.5) << bits;  // measured 3.54 at 10, 7.14 at 12
    const TriangleMesh decoded = compress::decompress_mesh(bytes, "memory");
    const double bound = compress::normal_error_degrees(bits);
    for (std::size_t k = 0; k < decoded.vertices.size(); ++k) {
      const Eigen::Vector3f& n = mesh.normals[report.vertex_order[k]];
      EXPECT_LE(angle_degrees(decoded.normals[k], n), bound) << k;
    }
  }
}

// The stated angle holds for normals in any direction from their prediction (random ones, and
// each exactly opposite the surface's: the residual grid's far side), at any normal_error; an
// angle out of range is refused.
TEST(NormalCoding, StatedAngleHoldsForAnyDirection) {
  TriangleMesh mesh = with_face_normals(torus(40, 24));
  std::mt19937 rng(5);
  std::normal_distribution<float> g;
  for (std::size_t i = 0; i < mesh.normals.size(); ++i)
    mesh.normals[i] = i % 3 == 0 ? Eigen::Vector3f(-mesh.normals[i])
                                 : Eigen::Vector3f(g(rng), g(rng), g(rng)).normalized();
  for (const double error : {0.05, 0.7, 5.0}) {
    CompressConfig config;
    config.normal_error = error;
    CompressReport report;
    const TriangleMesh decoded =
        compress::decompress_mesh(compress::compress_mesh(mesh, config, &report), "memory");
    ASSERT_EQ(decoded.normals.size(), mesh.normals.size());
    double worst = 0;
    for (std::size_t k = 0; k < decoded.normals.size(); ++k)
      worst =
          std::max(worst, angle_degrees(decoded.normals[k], mesh.normals[report.vertex_order[k]]));
    EXPECT_LE(worst, error) << error;
    EXPECT_GT(worst, error / 4) << error;  // the bound is used, not far finer
  }
  CompressConfig bad;
  bad.normal_error = 45;
  EXPECT_THROW(compress::compress_mesh(mesh, bad), Error);
}

// Normals of any direction (not the surface's) still round-trip within the bound; normal_bits 0
// leaves them out and the decoder recomputes the surface's.
TEST(NormalCoding, ArbitraryNormalsAndRecomputedNormals) {
  TriangleMesh mesh = torus(40, 24);
  std::mt19937 rng(3);
  std::normal_distribution<float> g;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    mesh.normals.push_back(Eigen::Vector3f(g(rng), g(rng), g(rng)).normalized());
  round_trip(mesh);
  const TriangleMesh surface = with_face_normals(torus(40, 24));
  CompressConfig config;
  config.normal_bits = 0;
  CompressReport report;
  const std::vector<unsigned char> bytes = compress::compress_mesh(surface, config, &report);
  EXPECT_LT(report.body.attribute_bytes, 8u);  // no normals stored
  const compress::CompressedMeshInfo info = compress::compressed_mesh_info(bytes, "memory");
  EXPECT_FALSE(info.normals);
  EXPECT_TRUE(info.recomputed_normals);
  const TriangleMesh decoded = compress::decompress_mesh(bytes, "memory");
  ASSERT_EQ(decoded.normals.size(), surface.normals.size());
  // Recomputed from positions within step / 2 (1/64 of an edge): within 1 degree here.
  for (std::size_t k = 0; k < decoded.vertices.size(); ++k)
    EXPECT_GT(decoded.normals[k].dot(surface.normals[report.vertex_order[k]]),
              std::cos(1.0 * M_PI / 180))
        << k;
  config.normal_bits = 3;
  EXPECT_THROW(compress::compress_mesh(surface, config), Error);
}

// Colours predicted from decoded neighbours and coded channel after channel: exact, and a smooth
// gradient costs under half of 24 bits per vertex (measured 8.3; version 8's coder 11.0).
TEST(ColorCoding, SmoothAndNoisyColoursRoundTripExactly) {
  TriangleMesh smooth = sphere(60, 80), noisy = smooth;
  std::mt19937 rng(11);
  for (const Eigen::Vector3f& p : smooth.vertices) {
    const auto c = [](float x) { return static_cast<std::uint8_t>(std::lround(127.5f + 127 * x)); };
    smooth.colors.push_back(Rgb8{c(p.x()), c(p.y()), c(p.z())});
    noisy.colors.push_back(Rgb8{static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()),
                                static_cast<std::uint8_t>(rng())});
  }
  for (const bool is_smooth : {true, false}) {
    const TriangleMesh& mesh = is_smooth ? smooth : noisy;
    CompressReport report;
    const std::vector<unsigned char> bytes = compress::compress_mesh(mesh, {}, &report);
    expect_same_mesh(mesh, compress::decompress_mesh(bytes, "memory"), report);
    const double per_vertex =
        8.0 * static_cast<double>(report.body.attribute_bytes) / mesh.vertices.size();
    RecordProperty(is_smooth ? "smooth_bits_per_colour" : "noisy_bits_per_colour",
                   std::to_string(per_vertex));
    if (is_smooth) {
      EXPECT_LT(per_vertex, 12.0);
    }
  }
}

// The decoder's second thread (the output triangles and the colours' neighbourhood beside the
// positions and the normals) changes nothing: the same mesh at 1 and 2 threads, and the same
// error for a cut file.
TEST(ColorCoding, DecodingIsTheSameOnOneAndTwoThreads) {
  TriangleMesh mesh = sphere(60, 80);
  for (const Eigen::Vector3f& p : mesh.vertices)
    mesh.colors.push_back(Rgb8{static_cast<std::uint8_t>(128 + 127 * p.x()), 40,
                               static_cast<std::uint8_t>(128 + 100 * p.z())});
  const std::vector<unsigned char> bytes = compress::compress_mesh(mesh, {});
  std::vector<unsigned char> cut(bytes.begin(), bytes.end() - 100);
  TriangleMesh decoded[2];
  std::string error[2];
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    decoded[threads - 1] = compress::decompress_mesh(bytes, "memory");
    try {
      compress::decompress_mesh(cut, "memory");
    } catch (const Error& e) {
      error[threads - 1] = e.what();
    }
  }
  EXPECT_EQ(decoded[0].vertices, decoded[1].vertices);
  EXPECT_EQ(decoded[0].triangles, decoded[1].triangles);
  EXPECT_EQ(decoded[0].normals, decoded[1].normals);
  ASSERT_EQ(decoded[0].colors.size(), mesh.vertices.size());
  for (std::size_t k = 0; k < mesh.vertices.size(); ++k) {
    const Rgb8 a = decoded[0].colors[k], b = decoded[1].colors[k];
    EXPECT_TRUE(a.r == b.r && a.g == b.g && a.b == b.b) << k;
  }
  EXPECT_FALSE(error[0].empty());
  EXPECT_EQ(error[0], error[1]);
}

// Channels that move together (a sensor whose red and green are one, Kinect's): the coder codes
// green from red and blue from both, so noise in red and green and a constant blue cost about
// one channel's residual (the difference of two uniform bytes, ~8.4 bits): measured 9.0 bits
// per vertex; version 8's YCoCg residuals cost all three (22.0).
TEST(ColorCoding, ChannelsThatMoveTogetherCostAboutOneChannel) {
  TriangleMesh mesh = sphere(60, 80);
  std::mt19937 rng(5);
  for (std::size_t k = 0; k < mesh.vertices.size(); ++k) {
    const auto v = static_cast<std::uint8_t>(rng());
    mesh.colors.push_back(Rgb8{v, v, 77});
  }
  CompressConfig config;
  config.normals = false;
  CompressReport report;
  const std::vector<unsigned char> bytes = compress::compress_mesh(mesh, config, &report);
  expect_same_mesh(mesh, compress::decompress_mesh(bytes, "memory"), report);
  const double per_vertex =
      8.0 * static_cast<double>(report.body.attribute_bytes) / mesh.vertices.size();
  RecordProperty("bits_per_colour", std::to_string(per_vertex));
  EXPECT_LT(per_vertex, 10.0);
}

// The end offsets of a progressive file's parts: the base prefix, then each packet.
std::vector<std::size_t> packet_boundaries(const std::vector<unsigned char>& bytes) {
  io::ByteReader in = compress::detail::body_reader(bytes, "memory");
  const compress::CompressedMeshInfo info = compress::detail::read_header(in, bytes);
  compress::decode_body(in, info.quantizer, {info.normals, info.colors}, "memory");
  in.u64("split count");
  const std::uint32_t packets = in.u32("packet count");
  std::vector<std::size_t> ends{in.position()};
  for (std::uint32_t p = 0; p < packets; ++p) {
    in.u32("splits");
    in.bytes(static_cast<std::size_t>(in.u64("size")), "packet");
    ends.push_back(in.position());
  }
  return ends;
}

// Every prefix cut at a part boundary decodes to the levels it holds; a prefix cut elsewhere,
// and a flipped byte anywhere in a prefix or the whole file, is reported.
TEST(ProgressiveMesh, EveryPacketPrefixDecodesAndEveryFlippedByteIsReported) {
  TriangleMesh mesh = with_face_normals(sphere(20, 28));
  for (const Eigen::Vector3f& p : mesh.vertices)
    mesh.colors.push_back(Rgb8{static_cast<std::uint8_t>(128 + 120 * p.z()), 40, 90});
  CompressConfig config;
  config.splits_per_packet = 40;
  CompressReport report;
  const std::vector<unsigned char> bytes = compress::compress_progressive(mesh, config, &report);
  const std::vector<std::size_t> ends = packet_boundaries(bytes);
  ASSERT_GT(ends.size(), 5u);
  const std::size_t base_vertices = mesh.vertices.size() - report.splits;
  for (std::size_t i = 0; i < ends.size(); ++i) {
    const std::vector<unsigned char> prefix(bytes.begin(),
                                            bytes.begin() + static_cast<std::ptrdiff_t>(ends[i]));
    const compress::PrefixDecode d = compress::decompress_progressive_prefix(prefix, "stream");
    EXPECT_EQ(d.packets, i);
    EXPECT_EQ(d.packets_stated, ends.size() - 1);
    EXPECT_EQ(d.mesh.vertices.size(),
              std::min(mesh.vertices.size(), base_vertices + i * config.splits_per_packet));
    EXPECT_EQ(d.mesh.normals.size(), d.mesh.vertices.size());
    EXPECT_EQ(d.mesh.colors.size(), d.mesh.vertices.size());
    compress::ProgressiveLevel level;
    level.splits = d.mesh.vertices.size() - base_vertices;
    const TriangleMesh same = compress::decompress_progressive_level(bytes, "memory", level);
    EXPECT_EQ(same.triangles, d.mesh.triangles) << i;
    // A flipped byte anywhere in this prefix (every 7th, and the last) is reported.
    for (std::size_t at = 0; at < prefix.size(); at += (at + 7 < prefix.size() ? 7 : 1)) {
      std::vector<unsigned char> bad = prefix;
      bad[at] ^= 0x04;
      EXPECT_THROW(compress::decompress_progressive_prefix(bad, "stream"), Error) << i << " " << at;
      if (at + 1 == prefix.size()) break;
    }
    // Cut inside the next part: not a boundary.
    if (ends[i] + 3 < bytes.size()) {
      const std::vector<unsigned char> cut(
          bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(ends[i] + 3));
      EXPECT_THROW(compress::decompress_progressive_prefix(cut, "stream"), Error) << i;
    }
  }
  const compress::PrefixDecode whole = compress::decompress_progressive_prefix(bytes, "file");
  EXPECT_TRUE(whole.complete);
  expect_same_mesh(mesh, whole.mesh, report);
  for (std::size_t at = 0; at < bytes.size(); at += 5) {
    std::vector<unsigned char> bad = bytes;
    bad[at] ^= 0x40;
    EXPECT_THROW(compress::decompress_progressive_prefix(bad, "file"), Error) << at;
  }
}

// The fuzzer's helper: reseal_progressive_mesh() rewrites the prefix checksum, every packet's and
// the file's (all zeroed here) to the encoder's, so a mutated stream reaches the decoder.
TEST(ProgressiveMesh, ResealingRewritesEveryChecksum) {
  CompressConfig config;
  config.splits_per_packet = 40;
  const std::vector<unsigned char> bytes =
      compress::compress_progressive(with_face_normals(sphere(14, 18)), config);
  const std::vector<std::size_t> ends = packet_boundaries(bytes);
  ASSERT_GT(ends.size(), 3u);
  std::vector<unsigned char> zeroed = bytes;
  const auto zero = [&](std::size_t at) { std::fill_n(zeroed.begin() + at, 8, 0); };
  zero(compress::detail::kPrefixChecksumOffset);
  for (std::size_t i = 1; i < ends.size(); ++i) zero(ends[i] - 8);
  zero(bytes.size() - 8);
  ASSERT_NE(zeroed, bytes);
  compress::reseal_progressive_mesh(zeroed);
  EXPECT_EQ(zeroed, bytes);
  // A flipped byte in the last packet's stream: refused by its checksum, then (resealed) no
  // checksum complains.
  std::vector<unsigned char> flipped = bytes;
  flipped[ends[ends.size() - 2] + 13] ^= 0x10;
  const auto error = [](const std::vector<unsigned char>& b) {
    try {
      compress::decompress_progressive_prefix(b, "stream");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error(flipped).find("checksum"), std::string::npos) << error(flipped);
  compress::reseal_progressive_mesh(flipped);
  EXPECT_EQ(error(flipped).find("checksum"), std::string::npos) << error(flipped);
  // Single-rate files: the file checksum only.
  std::vector<unsigned char> single = compress::compress_mesh(torus(8, 6));
  const std::vector<unsigned char> good = single;
  std::fill_n(single.end() - 8, 8, 0);
  compress::reseal_progressive_mesh(single);
  EXPECT_EQ(single, good);
}

// Files of older versions (2: before the prefix checksums and the new attribute coders; 7:
// before the coordinate snap symbols; 8: before the colour coder's distance-weighted prediction
// and channel decorrelation; 9: snap candidates from the parallelograms' far corners too; 10:
// snap symbols axis by axis) are refused with the versions named.
TEST(CompressedMeshFile, OldVersionsAreRefusedByName) {
  for (const unsigned char old : {2, 7, 8, 9, 10}) {
    std::vector<unsigned char> bytes = compress::compress_mesh(torus(8, 6));
    bytes[8] = old;
    compress::reseal_compressed_mesh(bytes);
    try {
      compress::decompress_mesh(bytes, "old.mfc");
      ADD_FAILURE() << "version " << int{old} << " was read";
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("is " + std::to_string(old) + "; this build reads version 11"),
                std::string::npos)
          << what;
      EXPECT_NE(what.find("old.mfc"), std::string::npos) << what;
    }
  }
}

// Meshes as meshflow writes them (reconstructed, with normals, and colours where the cloud has
// them) round-trip with positions within half a step, normals within the 10-bit bound and
// colours exact, through both position modes (the coder picks one per mesh).
TriangleMesh reconstructed(PointCloud cloud, float voxel) {
  ReconstructionConfig config;
  if (voxel > 0) config.voxelize.voxel_size = voxel;  // else the default
  const FramePtr frame = ReconstructionPipeline(config, 1).reconstruct(std::move(cloud), "test");
  EXPECT_TRUE(frame->ok()) << frame->error;
  return frame->mesh;
}

void round_trip_written_mesh(const TriangleMesh& mesh, bool colors) {
  ASSERT_FALSE(mesh.triangles.empty());
  ASSERT_EQ(mesh.normals.size(), mesh.vertices.size());
  ASSERT_EQ(mesh.colors.size(), colors ? mesh.vertices.size() : 0u);
  CompressConfig config;
  config.position_bits = 14;
  round_trip(mesh, config);
}

TEST(RealMeshes, DemoRoomRoundTripsWithNormals) {
  const TriangleMesh mesh =
      reconstructed(synthetic::simulate_scan(synthetic::demo_room_scene(), {}), 0.05f);
  round_trip_written_mesh(mesh, false);
  // Normals within 0.5 degrees, quantised around their ring prediction, cost under a bit each
  // (measured 0.49 with 14-bit positions); the octahedral coder of version 6 spent 3.1 bits at
  // 9 bits (the same bound) and 2.0 at 8 (twice it).
  CompressConfig config;
  config.position_bits = 14;
  config.normal_error = 0.5;
  CompressReport report;
  const TriangleMesh decoded =
      compress::decompress_mesh(compress::compress_mesh(mesh, config, &report), "memory");
  EXPECT_LT(8.0 * static_cast<double>(report.body.attribute_bytes) / mesh.vertices.size(), 1.0);
  double sum = 0;
  for (std::size_t k = 0; k < decoded.normals.size(); ++k) {
    const double angle = angle_degrees(decoded.normals[k], mesh.normals[report.vertex_order[k]]);
    EXPECT_LE(angle, 0.5) << k;
    sum += angle;
  }
  // A zero residual keeps the prediction's own error: the mean is well under the bound.
  EXPECT_LT(sum / static_cast<double>(decoded.normals.size()), 0.25);
}

TEST(RealMeshes, Kurt3dScan000RoundTripsWithNormals) {
  MESHFLOW_REQUIRE_DATA("kurt3d/scan000.3d");
  const TriangleMesh mesh =
      reconstructed(io::read_point_cloud(test::data_path("kurt3d/scan000.3d")), 0.05f);
  round_trip_written_mesh(mesh, false);
  // Bytes per normal: the coder before issue 57 spent 18.7 bits per normal here (146 kB for
  // 62 k normals, measured with `meshflow compress` at e337a85^); version 3 and later 6.6 at the
  // default 10 bits.
  CompressReport report;
  compress::compress_mesh(mesh, {}, &report);
  EXPECT_LT(8.0 * static_cast<double>(report.body.attribute_bytes) / mesh.vertices.size(), 8.0);
}

TEST(RealMeshes, ColouredKinectCloudRoundTripsWithNormalsAndColours) {
  MESHFLOW_REQUIRE_DATA("kinect_pcl/table_scene_mug_stereo_textured.pcd");
  round_trip_written_mesh(
      reconstructed(
          io::read_point_cloud(test::data_path("kinect_pcl/table_scene_mug_stereo_textured.pcd")),
          0.0f),
      true);
}

// On a smooth surface nearly every vertex is predicted from trusted parallelograms (one or a
// mean of several), not from the gate's midpoint.
TEST(PositionCoding, ConstrainedPredictionTrustsParallelogramsOnSmoothSurfaces) {
  const TriangleMesh mesh = sphere(200, 300);
  CompressConfig config;
  config.position_bits = 16;
  config.normals = config.colors = false;
  const CompressReport report = round_trip(mesh, config);
  EXPECT_GT(report.body.trusted_parallelograms, mesh.vertices.size() * 9 / 10);
}

// A grid folded into a zigzag (a sharp crease every 4 columns) and tilted along y (so that no
// neighbour shares a vertex's z and z is always coded as a residual, not a snap): a
// parallelogram across a crease predicts off the surface by a grid step, one within a face
// exactly; the encoder refuses the former, trusts the latter, and codes the mesh's positions in
// well under a bit per vertex.
TEST(PositionCoding, ConstrainedPredictionRefusesParallelogramsAcrossCreases) {
  TriangleMesh mesh = grid_mesh(120);
  for (Eigen::Vector3f& v : mesh.vertices) {
    const int phase = static_cast<int>(v.x()) % 8;
    v.z() = static_cast<float>(phase < 4 ? phase : 8 - phase) + 0.75f * v.y();
  }
  CompressConfig config;
  config.step = 0.25;
  config.normals = config.colors = false;
  const CompressReport report = round_trip(mesh, config);
  const std::size_t offered = report.body.offered_parallelograms;
  EXPECT_LT(report.body.trusted_parallelograms, offered * 95 / 100);
  EXPECT_GT(report.body.trusted_parallelograms, offered / 2);
  EXPECT_LT(8.0 * static_cast<double>(report.body.position_bytes) / mesh.vertices.size(), 1.0);
}

// A snap's candidates are the distinct neighbour values on the axis nearest the prediction (the
// smaller first on a tie), at most kSnapCandidates: against sorting every distinct value. Each
// offered value's symbol is 1 + its rank; any other value's is 0.
TEST(PositionCoding, SnapCandidatesAreTheNearestDistinctNeighbourValues) {
  std::uint32_t state = 7;
  const auto next = [&state](std::uint32_t n) {
    state = state * 1664525u + 1013904223u;
    return (state >> 8) % n;
  };
  for (int trial = 0; trial < 2000; ++trial) {
    compress::SnapNeighbours nb;
    nb.count = next(compress::SnapNeighbours::kMax + 1);
    const std::size_t axis = next(3);
    for (unsigned i = 0; i < nb.count; ++i)
      for (auto& coordinate : nb.coordinate) coordinate[i] = static_cast<std::int32_t>(next(9)) - 4;
    const auto predicted = static_cast<std::int32_t>(next(11)) - 5;
    std::vector<std::int32_t> values(nb.coordinate[axis].begin(),
                                     nb.coordinate[axis].begin() + nb.count);
    std::sort(values.begin(), values.end(), [predicted](std::int32_t a, std::int32_t b) {
      const std::int32_t da = std::abs(a - predicted), db = std::abs(b - predicted);
      return da != db ? da < db : a < b;
    });
    values.erase(std::unique(values.begin(), values.end()), values.end());
    const std::vector<std::int32_t> all = values;
    values.resize(std::min<std::size_t>(values.size(), compress::kSnapCandidates));
    const compress::SnapCandidates c = compress::snap_candidates(nb, axis, predicted);
    ASSERT_EQ(c.n, values.size()) << trial;
    ASSERT_EQ(c.distinct, all.size()) << trial;
    if (c.n > 0) {
      EXPECT_EQ(c.nearest, values[0]) << trial;
    }
    for (unsigned j = 0; j < c.n; ++j) EXPECT_EQ(c.ranked(j), values[j]) << trial << " " << j;
    for (std::int32_t v = -6; v <= 6; ++v) {
      const auto at = std::find(values.begin(), values.end(), v);
      const unsigned symbol =
          at == values.end() ? 0u : static_cast<unsigned>(at - values.begin()) + 1u;
      EXPECT_EQ(c.symbol_of(v), symbol) << trial << " " << v;
      EXPECT_EQ(compress::shares_value(nb, axis, v),
                std::find(all.begin(), all.end(), v) != all.end())
          << trial << " " << v;
    }
  }
}

// The demo room as `meshflow demo` writes it (2 mm range noise) lies on a voxel lattice: most
// coordinates equal a decoded neighbour's and are coded as a snap symbol. Its positions (14 bits)
// cost under 12 bits per vertex (measured 10.6); version 7, which coded a residual for every
// coordinate, spent 14.1 (6.1 without noise, now 4.8).
TEST(PositionCoding, LatticeCoordinatesSnapToTheirNeighbours) {
  synthetic::ScanConfig scan;
  scan.noise_sigma = 0.002f;
  TriangleMesh mesh =
      reconstructed(synthetic::simulate_scan(synthetic::demo_room_scene(), scan), 0.05f);
  mesh.normals.clear();
  CompressConfig config;
  config.position_bits = 14;
  config.normals = config.colors = false;
  const CompressReport report = round_trip(mesh, config);
  const double bits = 8.0 * static_cast<double>(report.body.position_bytes) / mesh.vertices.size();
  RecordProperty("position_bits_per_vertex", std::to_string(bits));
  EXPECT_LT(bits, 12.0);
  EXPECT_GT(report.body.snapped_coordinates, mesh.vertices.size());  // over a third
}

}  // namespace
}  // namespace meshflow
