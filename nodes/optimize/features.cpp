#include "nodes/optimize/features.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "runtime/angles.h"
#include "runtime/face_normals.h"
#include "runtime/parallel.h"
#include "runtime/vertex_triangles.h"

namespace meshflow {
namespace {

/// A candidate sharp edge {a, b} (a < b) and the normals of its two faces: `left` of the face
/// that runs a -> b, `right` of the one that runs b -> a.
struct FeatureCandidate {
  std::array<std::uint32_t, 2> ends;
  Eigen::Vector3f left, right;
  bool marked = false;  ///< both ends marked by the mesh's maker (a seed): never noise
  float length = 0.0f;  ///< |ends[0] - ends[1]|, metres (set where the lines are traced)
};

/// Calls f(triangle, p, q) for each directed edge p -> q of each distinct triangle around `a`
/// (VertexTriangles lists a triangle once per corner at `a`; repeats are adjacent), triangles in
/// ascending order. O(valence).
template <typename EdgeVisitor>
void for_each_edge_around(const TriangleMesh& mesh, const VertexTriangles& around, std::uint32_t a,
                          EdgeVisitor&& f) {
  std::uint32_t previous = 0xFFFFFFFFu;
  for (const std::uint32_t* it = around.begin(a); it != around.end(a); ++it) {
    if (*it == previous) continue;
    previous = *it;
    const Triangle& t = mesh.triangles[*it];
    for (int k = 0; k < 3; ++k) f(*it, t[k], t[(k + 1) % 3]);
  }
}

/// The sides of edge {a, b} (a != b) among the triangles around a: how many there are, and the
/// two lowest triangles holding one.
struct FeatureEdgeSides {
  int count = 0;
  std::uint32_t first = 0, second = 0;
};

FeatureEdgeSides feature_edge_sides(const TriangleMesh& mesh, const VertexTriangles& around,
                                    std::uint32_t a, std::uint32_t b) {
  FeatureEdgeSides s;
  for_each_edge_around(mesh, around, a,
                       [&](std::uint32_t triangle, std::uint32_t p, std::uint32_t q) {
                         if ((p == a && q == b) || (p == b && q == a)) {
                           if (s.count == 0) s.first = triangle;
                           if (s.count == 1) s.second = triangle;
                           ++s.count;
                         }
                       });
  return s;
}

/// The test of bent_vertex(): cos_half is the cosine of half the feature angle less a margin
/// for rounding (0.1 degrees), so that two normals within that of one axis are closer than the
/// angle.
struct BendTest {
  float cos_half;
  /// 1 - cos_half: the most the k normals of a vertex may fall short of k in the length of
  /// their sum, less kSumRounding x k x (k + 4), where all of them lie within half the angle.
  float spread;
};
/// Bounds the float rounding of summing k unit normals and taking the sum's length (a few k^2
/// float epsilons) in BendTest::spread's allowance.
constexpr float kSumRounding = 2e-7f;

/// A row of counted_face_normals() as one SSE register (GCC / Clang vector extension; it may
/// alias the Eigen rows it is read from).
using NormalRow = float __attribute__((vector_size(16), may_alias));

/// Whether two of v's faces (`begin`, `end`: its row of vertex_triangles()) may meet at more
/// than the feature angle: false where every face normal around v lies within half that angle
/// (test.cos_half) of their mean, so that no two of them are farther apart than the angle (no
/// edge at v is sharp). `normals`:
/// counted_face_normals() (w: 1 for a face with a normal). First without a second pass over the
/// normals: for k unit normals n_i with sum m, the sum over i of (1 - n_i . m / |m|) is k - |m|,
/// so where k - |m| <= 1 - cos_half every term is (a flat fan: most vertices); else each
/// normal's dot with the mean. A face without a normal is never sharp and counts in neither.
/// O(valence), one vector operation per face.
bool bent_vertex(const std::uint32_t* begin, const std::uint32_t* end, const NormalRow* normals,
                 const BendTest& test) {
  const std::uint32_t* t = begin;
  NormalRow sum = {0.0f, 0.0f, 0.0f, 0.0f}, odd = sum;  // two sums: half the dependent adds
  for (; t + 1 < end; t += 2) {
    sum += normals[t[0]];
    odd += normals[t[1]];
  }
  if (t != end) sum += normals[*t];
  sum += odd;
  const float k = sum[3];  // the faces with a normal
  const NormalRow squares = sum * sum;
  const float length = std::sqrt(squares[0] + squares[1] + squares[2]);
  if (k - length <= test.spread - kSumRounding * k * (k + 4.0f)) return false;  // none: k = 0
  if (!(length > 0.0f)) return true;  // opposite faces (or a non-finite sum): look
  // (n, w) . (mean, -1) + 1 is n . mean for a face with a normal (w = 1), 1 for one without.
  NormalRow axis = sum / length;
  axis[3] = -1.0f;
  for (t = begin; t != end; ++t) {
    const NormalRow d = normals[*t] * axis;
    if (!((d[0] + d[1]) + (d[2] + d[3]) + 1.0f >= test.cos_half)) return true;
  }
  return false;
}

/// One side of an edge {a, b} seen from its lower end a: the other end, the face, and whether the
/// face runs a -> b.
struct EdgeSide {
  std::uint32_t b, face;
  bool forward;
};

/// A candidate {a, b} (a < b) between the faces `first` (the lower, which runs a -> b where
/// `forward`) and `second` when their normals are apart by more than the angle (cos_limit),
/// appended to `out`.
inline void judge_edge(const std::vector<Eigen::Vector4f>& normals, std::uint32_t a,
                       std::uint32_t b, std::uint32_t first, std::uint32_t second, bool forward,
                       float cos_limit, const std::vector<std::uint8_t>* seed,
                       std::vector<FeatureCandidate>& out) {
  const Eigen::Vector4f &row0 = normals[first], &row1 = normals[second];
  if (row0.w() == 0.0f || row1.w() == 0.0f) return;  // a face without a normal: never sharp
  const Eigen::Vector3f n0 = row0.head<3>(), n1 = row1.head<3>();
  if (n0.dot(n1) < cos_limit) {
    const bool marked = seed != nullptr && (*seed)[a] != 0 && (*seed)[b] != 0;
    out.push_back({{a, b}, forward ? n0 : n1, forward ? n1 : n0, marked});
  }
}

/// candidates_at() where every face around a has three distinct corners and there are at most
/// kFanFaces of them (most vertices): each face's two edges at a (a -> next, previous -> a) with
/// b > a as keys (b, position of the face around a, forward), sorted (faces come ascending, so
/// two sides of one edge sort lower face first), each edge with exactly two sides judged.
/// Returns false (nothing appended) for another fan. O(valence^2) on a few words, no allocation.
constexpr std::size_t kFanFaces = 32;
bool candidates_at_plain_fan(const TriangleMesh& mesh, const VertexTriangles& around,
                             const std::vector<Eigen::Vector4f>& normals, std::uint32_t a,
                             float cos_limit, const std::vector<std::uint8_t>* seed,
                             std::vector<FeatureCandidate>& out) {
  const std::uint32_t* faces = around.begin(a);
  const auto k = static_cast<std::size_t>(around.end(a) - faces);
  if (k > kFanFaces) return false;
  const std::uint64_t n = mesh.vertices.size();
  std::uint64_t keys[2 * kFanFaces];
  std::size_t count = 0;
  for (std::size_t i = 0; i < k; ++i) {
    const Triangle& t = mesh.triangles[faces[i]];
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) return false;
    const int c = t[0] == a ? 0 : (t[1] == a ? 1 : 2);
    const std::uint64_t next = t[c == 2 ? 0 : c + 1], previous = t[c == 0 ? 2 : c - 1];
    keys[count] = next << 32 | i << 1 | 1;  // a -> next: forward
    count += next > a && next < n ? 1 : 0;
    keys[count] = previous << 32 | i << 1;
    count += previous > a && previous < n ? 1 : 0;
  }
  for (std::size_t i = 1; i < count; ++i)
    for (std::size_t j = i; j > 0 && keys[j] < keys[j - 1]; --j) std::swap(keys[j], keys[j - 1]);
  for (std::size_t i = 0; i < count;) {
    const std::uint64_t b = keys[i] >> 32;
    std::size_t j = i + 1;
    while (j < count && keys[j] >> 32 == b) ++j;
    if (j - i == 2) {
      const std::uint32_t lower = faces[(keys[i] & 0xFFFFFFFFu) >> 1];
      const std::uint32_t upper = faces[(keys[i + 1] & 0xFFFFFFFFu) >> 1];
      judge_edge(normals, a, static_cast<std::uint32_t>(b), lower, upper, (keys[i] & 1) != 0,
                 cos_limit, seed, out);
    }
    i = j;
  }
  return true;
}

/// The candidates whose lower end is `a` (see sharp_candidates), ascending by their other end,
/// appended to `out`; `sides` is scratch memory. Every edge {a, b} (b > a) of a's faces (each face
/// once) is judged: exactly two sides in distinct faces, their normals apart by more than the
/// angle; `left` the normal of the face that runs min -> max, read from the lower face (as the
/// lowest face holding the edge sees it). O(valence log valence).
void candidates_at(const TriangleMesh& mesh, const VertexTriangles& around,
                   const std::vector<Eigen::Vector4f>& normals, std::uint32_t a, float cos_limit,
                   const std::vector<std::uint8_t>* seed, std::vector<EdgeSide>& sides,
                   std::vector<FeatureCandidate>& out) {
  if (candidates_at_plain_fan(mesh, around, normals, a, cos_limit, seed, out)) return;
  sides.clear();
  const std::size_t n = mesh.vertices.size();
  for_each_edge_around(mesh, around, a,
                       [&](std::uint32_t triangle, std::uint32_t p, std::uint32_t q) {
                         if (p == q || (p != a && q != a)) return;
                         const std::uint32_t b = p == a ? q : p;
                         if (b > a && b < n) sides.push_back({b, triangle, p < q});
                       });
  // By other end, then face (faces come ascending: a stable sort keeps them so).
  for (std::size_t i = 1; i < sides.size(); ++i)
    for (std::size_t j = i; j > 0 && sides[j].b < sides[j - 1].b; --j)
      std::swap(sides[j], sides[j - 1]);
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i + 1;
    while (j < sides.size() && sides[j].b == sides[i].b) ++j;
    if (j - i == 2 && sides[i].face != sides[i + 1].face)
      judge_edge(normals, a, sides[i].b, sides[i].face, sides[i + 1].face, sides[i].forward,
                 cos_limit, seed, out);
    i = j;
  }
}

/// Edges with two faces meeting at a normal angle whose cosine is below cos_limit (the angle
/// `angle_deg`), sorted. Face normals once (counted_face_normals(): face_normal()'s values),
/// then one parallel pass over the vertices in fixed blocks: a vertex whose faces all lie within
/// half the angle of their mean (bent_vertex) ends no sharp edge; the others judge their edges to
/// higher vertices (candidates_at). The blocks' lists, each sorted, joined in block order:
/// sorted, the same for any thread count. O(T + bent vertices x valence log valence). `around`
/// is vertex_triangles(mesh). `seed` (optional, one byte per vertex): candidates between two
/// marked vertices are `marked`.
std::vector<FeatureCandidate> sharp_candidates(const TriangleMesh& mesh,
                                               const VertexTriangles& around, float angle_deg,
                                               float cos_limit,
                                               const std::vector<std::uint8_t>* seed = nullptr) {
  const std::vector<Eigen::Vector4f> normals = counted_face_normals(mesh);
  constexpr double kRoundingMarginDeg = 0.1;
  const double half = std::max(0.0, 0.5 * static_cast<double>(angle_deg) - kRoundingMarginDeg);
  const auto cos_half = static_cast<float>(std::cos(radians(half)));
  const BendTest test{cos_half, 1.0f - cos_half};
  const auto* rows = reinterpret_cast<const NormalRow*>(normals.data());
  const std::size_t n = mesh.vertices.size();
  const std::size_t blocks = (n + kParallelBlock - 1) / kParallelBlock;
  std::vector<std::vector<FeatureCandidate>> parts(blocks);
  tbb::enumerable_thread_specific<std::vector<EdgeSide>> scratch;
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t block) {
    // The bent vertices first, in a loop of their own (its values stay in registers).
    const BendTest fan_test = test;
    const NormalRow* const fan_normals = rows;
    const std::uint32_t *const offsets = around.offsets.data(), *const faces =
                                                                    around.triangles.data();
    const auto first = static_cast<std::uint32_t>(block * kParallelBlock);
    const auto end = static_cast<std::uint32_t>(std::min(n, (block + 1) * kParallelBlock));
    std::uint32_t bent[kParallelBlock];
    std::size_t count = 0;
    for (std::uint32_t v = first; v < end; ++v) {
      bent[count] = v;
      count += bent_vertex(faces + offsets[v], faces + offsets[v + 1], fan_normals, fan_test);
    }
    std::vector<EdgeSide>& sides = scratch.local();
    for (std::size_t i = 0; i < count; ++i)
      candidates_at(mesh, around, normals, bent[i], cos_limit, seed, sides, parts[block]);
  });
  return concatenate_parts(parts);
}

/// The candidates around every vertex (compressed rows of candidate indices).
struct FeatureIncidence {
  std::vector<std::uint32_t> offsets, edges;
  std::uint32_t degree(std::uint32_t v) const { return offsets[v + 1] - offsets[v]; }
  std::uint32_t edge(std::uint32_t v, std::uint32_t k) const { return edges[offsets[v] + k]; }
};

FeatureIncidence feature_incidence(std::size_t n, const std::vector<FeatureCandidate>& c) {
  FeatureIncidence inc;
  inc.offsets.assign(n + 1, 0);
  for (const FeatureCandidate& e : c)
    for (std::uint32_t v : e.ends) ++inc.offsets[v + 1];
  for (std::size_t v = 0; v < n; ++v) inc.offsets[v + 1] += inc.offsets[v];
  inc.edges.resize(inc.offsets[n]);
  std::vector<std::uint32_t> fill(inc.offsets.begin(), inc.offsets.end() - 1);
  for (std::size_t i = 0; i < c.size(); ++i)
    for (std::uint32_t v : c[i].ends) inc.edges[fill[v]++] = static_cast<std::uint32_t>(i);
  return inc;
}

std::uint32_t other_end(const FeatureCandidate& e, std::uint32_t v) {
  return e.ends[0] == v ? e.ends[1] : e.ends[0];
}

/// Whether the two candidates at v (v has exactly two) continue one another: the line
/// a - v - b turns by less than the feature angle (cos_limit), and the faces on either side of
/// it by less than twice that (cos_side: a bumpy side of a true edge turns too).
bool continues_line(const std::vector<Eigen::Vector3f>& points, const FeatureCandidate& in,
                    const FeatureCandidate& out, std::uint32_t v, float cos_limit, float cos_side) {
  const std::uint32_t a = other_end(in, v), b = other_end(out, v);
  const Eigen::Vector3f d_in = (points[v] - points[a]).normalized();
  const Eigen::Vector3f d_out = (points[b] - points[v]).normalized();
  if (d_in.dot(d_out) < cos_limit) return false;
  // Walking a -> v -> b, the face on the left of `in` runs a -> v.
  const Eigen::Vector3f& left_in = in.ends[0] == a ? in.left : in.right;
  const Eigen::Vector3f& right_in = in.ends[0] == a ? in.right : in.left;
  const Eigen::Vector3f& left_out = out.ends[0] == v ? out.left : out.right;
  const Eigen::Vector3f& right_out = out.ends[0] == v ? out.right : out.left;
  return left_in.dot(left_out) >= cos_side && right_in.dot(right_out) >= cos_side;
}

/// Per vertex: whether it ends, branches or breaks a line (has candidates and is no line
/// vertex), written to `breaks` (one byte per vertex) where `changed` is non-zero: the others
/// keep the candidates they had when it was written.
void line_breaks(const std::vector<Eigen::Vector3f>& points, const std::vector<FeatureCandidate>& c,
                 const FeatureIncidence& inc, float angle_deg,
                 const std::vector<std::uint8_t>& changed, std::vector<std::uint8_t>& breaks) {
  const float cos_limit = static_cast<float>(std::cos(radians(static_cast<double>(angle_deg))));
  const float cos_side =
      static_cast<float>(std::cos(radians(std::min(90.0, 2.0 * static_cast<double>(angle_deg)))));
  for (std::uint32_t v = 0; v < points.size(); ++v) {
    if (!changed[v]) continue;
    const std::uint32_t d = inc.degree(v);
    breaks[v] = d != 0 && (d != 2 || !continues_line(points, c[inc.edge(v, 0)], c[inc.edge(v, 1)],
                                                     v, cos_limit, cos_side));
  }
}

/// The lines: runs of candidates between breaks (or closed loops without one).
struct FeatureLines {
  std::vector<std::uint32_t> line_of;              ///< per candidate
  std::vector<float> length;                       ///< per line, metres
  std::vector<std::array<std::uint32_t, 2>> ends;  ///< per line; a loop: {kNoEnd, kNoEnd}
};
constexpr std::uint32_t kNoEnd = 0xFFFFFFFFu;

FeatureLines trace_lines(const std::vector<FeatureCandidate>& c, const FeatureIncidence& inc,
                         const std::vector<std::uint8_t>& breaks) {
  FeatureLines lines;
  lines.line_of.assign(c.size(), kNoEnd);
  for (std::uint32_t start = 0; start < c.size(); ++start) {
    if (lines.line_of[start] != kNoEnd) continue;
    const auto id = static_cast<std::uint32_t>(lines.length.size());
    lines.line_of[start] = id;
    float length = c[start].length;
    std::array<std::uint32_t, 2> ends{kNoEnd, kNoEnd};
    for (int side = 0; side < 2; ++side) {  // walk away from start through both of its ends
      std::uint32_t edge = start, v = c[start].ends[side];
      while (!breaks[v]) {
        edge = inc.edge(v, 0) == edge ? inc.edge(v, 1) : inc.edge(v, 0);
        if (lines.line_of[edge] == id) break;  // a closed loop
        lines.line_of[edge] = id;
        length += c[edge].length;
        v = other_end(c[edge], v);
      }
      if (breaks[v]) ends[side] = v;
    }
    lines.length.push_back(length);
    lines.ends.push_back(ends);
  }
  return lines;
}

/// Whether vertex v has at least two long lines besides `line`.
bool held_by_long_lines(const FeatureLines& lines, const FeatureIncidence& inc,
                        const std::vector<std::uint8_t>& long_line, std::uint32_t v,
                        std::uint32_t line) {
  int count = 0;
  for (std::uint32_t k = 0; k < inc.degree(v); ++k) {
    const std::uint32_t other = lines.line_of[inc.edge(v, k)];
    count += other != line && long_line[other] ? 1 : 0;
  }
  return count >= 2;
}

}  // namespace

bool MeshFeatures::has_edge(std::uint32_t a, std::uint32_t b) const {
  const std::array<std::uint32_t, 2> key{std::min(a, b), std::max(a, b)};
  return std::binary_search(edges.begin(), edges.end(), key);
}

std::size_t MeshFeatures::count(VertexKind kind) const {
  return static_cast<std::size_t>(std::count(vertex_kind.begin(), vertex_kind.end(), kind));
}

namespace {

/// The feature graph from sorted candidates (see detect_features): lines traced, short ones
/// dropped, vertex kinds.
MeshFeatures features_from_candidates(const TriangleMesh& mesh, std::vector<FeatureCandidate> c,
                                      float angle_deg, float min_line_length);

}  // namespace

MeshFeatures detect_features(const TriangleMesh& mesh, const VertexTriangles& around,
                             const std::vector<std::uint8_t>* seed, float angle_deg,
                             float min_line_length) {
  if (!(angle_deg < 180.0f)) return features_from_candidates(mesh, {}, angle_deg, min_line_length);
  if (seed != nullptr && seed->size() != mesh.vertices.size()) seed = nullptr;
  const float cos_limit = static_cast<float>(std::cos(radians(static_cast<double>(angle_deg))));
  return features_from_candidates(mesh, sharp_candidates(mesh, around, angle_deg, cos_limit, seed),
                                  angle_deg, min_line_length);
}

MeshFeatures detect_features(const TriangleMesh& mesh, float angle_deg, float min_line_length) {
  if (!(angle_deg < 180.0f)) return features_from_candidates(mesh, {}, angle_deg, min_line_length);
  return detect_features(mesh, vertex_triangles(mesh), nullptr, angle_deg, min_line_length);
}

MeshFeatures detect_features(const TriangleMesh& mesh, const std::vector<std::uint8_t>& seed,
                             float angle_deg, float min_line_length) {
  if (seed.size() != mesh.vertices.size() || !(angle_deg < 180.0f))
    return detect_features(mesh, angle_deg, min_line_length);
  return detect_features(mesh, vertex_triangles(mesh), &seed, angle_deg, min_line_length);
}

namespace {

/// The candidates (sorted) of the candidate components holding a vertex of `seeds`: a search
/// from the seeds through the candidates found around each vertex reached (each edge judged as
/// sharp_candidates() judges it, normals of its lowest two faces). O(seeds + reached vertices x
/// valence^2), serial.
std::vector<FeatureCandidate> candidates_reaching(const TriangleMesh& mesh,
                                                  const VertexTriangles& around,
                                                  const std::vector<std::uint32_t>& seeds,
                                                  float cos_limit,
                                                  const std::vector<std::uint8_t>* marks) {
  const std::size_t n = mesh.vertices.size();
  std::vector<std::uint8_t> reached(n, 0);
  std::vector<std::uint32_t> queue;
  for (std::uint32_t v : seeds)
    if (v < n && !reached[v]) reached[v] = 1, queue.push_back(v);
  std::vector<FeatureCandidate> found;
  for (std::size_t q = 0; q < queue.size(); ++q) {
    const std::uint32_t a = queue[q];
    for (const std::uint32_t* it = around.begin(a); it != around.end(a); ++it) {
      const Triangle& tri = mesh.triangles[*it];
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t p = tri[k], r = tri[(k + 1) % 3];
        if (p == r || (p != a && r != a)) continue;
        const std::uint32_t b = p == a ? r : p;
        if (b >= n) continue;
        const FeatureEdgeSides s = feature_edge_sides(mesh, around, a, b);
        // Judged once per vertex, from the side of the edge in its lowest face.
        if (s.count != 2 || s.first != *it || s.second == *it) continue;
        const Eigen::Vector3f n0 = face_normal(mesh, tri);
        const Eigen::Vector3f n1 = face_normal(mesh, mesh.triangles[s.second]);
        if (!(n0.squaredNorm() > 0.0f && n1.squaredNorm() > 0.0f && n0.dot(n1) < cos_limit))
          continue;
        const bool forward = p < r;  // the lowest face runs min -> max: its normal on the left
        const bool marked = marks != nullptr && (*marks)[a] != 0 && (*marks)[b] != 0;
        found.push_back(
            {{std::min(a, b), std::max(a, b)}, forward ? n0 : n1, forward ? n1 : n0, marked});
        if (!reached[b]) reached[b] = 1, queue.push_back(b);
      }
    }
  }
  const auto by_ends = [](const FeatureCandidate& x, const FeatureCandidate& y) {
    return x.ends < y.ends;
  };
  std::sort(found.begin(), found.end(), by_ends);  // each edge was found from both its ends
  found.erase(std::unique(found.begin(), found.end(),
                          [](const FeatureCandidate& x, const FeatureCandidate& y) {
                            return x.ends == y.ends;
                          }),
              found.end());
  return found;
}

/// Keeps the candidates whose byte in `keep` is non-zero (in order) and renumbers their vertices
/// in order (`global`, `points` and `breaks` follow, their other vertices dropped): a later round
/// costs what is left, not what the first one met. The candidates stay sorted; `changed` marks
/// the vertices left that lost a candidate. O(candidates + vertices).
void keep_candidates(std::vector<FeatureCandidate>& c, const std::vector<std::uint8_t>& keep,
                     std::vector<std::uint32_t>& global, std::vector<Eigen::Vector3f>& points,
                     std::vector<std::uint8_t>& breaks, std::vector<std::uint8_t>& changed) {
  changed.assign(global.size(), 0);
  for (std::size_t i = 0; i < c.size(); ++i)
    if (!keep[i]) changed[c[i].ends[0]] = changed[c[i].ends[1]] = 1;
  std::size_t kept = 0;
  for (std::size_t i = 0; i < c.size(); ++i)
    if (keep[i]) c[kept++] = c[i];
  c.resize(kept);
  std::vector<std::uint32_t> renumbered(global.size(), kNoEnd);
  for (const FeatureCandidate& e : c) renumbered[e.ends[0]] = renumbered[e.ends[1]] = 0;
  std::uint32_t count = 0;
  for (std::size_t v = 0; v < global.size(); ++v) {
    if (renumbered[v] == kNoEnd) continue;
    renumbered[v] = count;
    global[count] = global[v];
    points[count] = points[v];
    breaks[count] = breaks[v];
    changed[count] = changed[v];
    ++count;
  }
  global.resize(count);
  points.resize(count);
  breaks.resize(count);
  changed.resize(count);
  for (FeatureCandidate& e : c)
    for (std::uint32_t& v : e.ends) v = renumbered[v];
}

MeshFeatures features_from_candidates(const TriangleMesh& mesh, std::vector<FeatureCandidate> c,
                                      float angle_deg, float min_line_length) {
  MeshFeatures f;
  f.vertex_kind.assign(mesh.vertices.size(), MeshFeatures::VertexKind::kFree);
  if (c.empty()) return f;
  if (min_line_length == 0.0f) min_line_length = kMinFeatureLineEdges * median_edge_length(mesh);
  // The lines are traced on the candidates' own vertices only (numbered in mesh order, so the
  // candidates stay sorted), and each round on those of the candidates left: each round costs
  // O(candidates left), not O(V).
  std::vector<std::uint32_t> global, local(mesh.vertices.size(), 0);
  for (const FeatureCandidate& e : c) local[e.ends[0]] = local[e.ends[1]] = 1;
  for (std::size_t v = 0; v < local.size(); ++v)
    if (local[v] != 0) {
      local[v] = static_cast<std::uint32_t>(global.size());
      global.push_back(static_cast<std::uint32_t>(v));
    }
  for (FeatureCandidate& e : c)
    for (std::uint32_t& v : e.ends) v = local[v];
  std::vector<Eigen::Vector3f> points(global.size());
  for (std::size_t v = 0; v < global.size(); ++v) points[v] = mesh.vertices[global[v]];
  for (FeatureCandidate& e : c) e.length = (points[e.ends[0]] - points[e.ends[1]]).norm();
  FeatureIncidence inc;
  std::vector<std::uint8_t> breaks(global.size(), 0), changed(global.size(), 1);
  for (;;) {  // drop short lines until every line left is long or a bridge between long ones
    inc = feature_incidence(global.size(), c);
    line_breaks(points, c, inc, angle_deg, changed, breaks);
    if (min_line_length < 0.0f) break;
    const FeatureLines lines = trace_lines(c, inc, breaks);
    std::vector<std::uint8_t> long_line(lines.length.size());
    for (std::size_t l = 0; l < long_line.size(); ++l)
      long_line[l] = lines.length[l] >= min_line_length;
    std::vector<std::uint8_t> keep = long_line;
    for (std::size_t i = 0; i < c.size(); ++i)  // a line with a marked edge is no noise
      if (c[i].marked) keep[lines.line_of[i]] = 1;
    for (std::uint32_t l = 0; l < keep.size(); ++l) {
      const auto& [a, b] = lines.ends[l];
      if (!keep[l] && a != kNoEnd && b != kNoEnd)
        keep[l] = held_by_long_lines(lines, inc, long_line, a, l) &&
                  held_by_long_lines(lines, inc, long_line, b, l);
    }
    // Spurs first (short lines with a loose end, and short loops): a noise spur off a true
    // line cuts that line in two, which join again once the spur is gone.
    auto loose = [&](std::uint32_t l) {
      const auto& e = lines.ends[l];
      return e[0] == kNoEnd || inc.degree(e[0]) == 1 || inc.degree(e[1]) == 1;
    };
    bool spurs = false;
    for (std::uint32_t l = 0; l < keep.size(); ++l) spurs |= !keep[l] && loose(l);
    if (spurs)
      for (std::uint32_t l = 0; l < keep.size(); ++l) keep[l] |= !loose(l);
    std::vector<std::uint8_t> kept(c.size());
    bool dropped = false;
    for (std::size_t i = 0; i < c.size(); ++i) {
      kept[i] = keep[lines.line_of[i]];
      dropped |= kept[i] == 0;
    }
    if (!dropped) break;
    keep_candidates(c, kept, global, points, breaks, changed);
  }
  for (const FeatureCandidate& e : c) f.edges.push_back({global[e.ends[0]], global[e.ends[1]]});
  for (std::uint32_t v = 0; v < global.size(); ++v)
    if (inc.degree(v) > 0)
      f.vertex_kind[global[v]] =
          breaks[v] ? MeshFeatures::VertexKind::kCorner : MeshFeatures::VertexKind::kLine;
  return f;
}

}  // namespace

MeshFeatures detect_features_reaching(const TriangleMesh& mesh, const VertexTriangles& around,
                                      const std::vector<std::uint32_t>& seeds, float angle_deg,
                                      float min_line_length,
                                      const std::vector<std::uint8_t>* marks) {
  if (!(angle_deg < 180.0f) || seeds.empty())
    return features_from_candidates(mesh, {}, angle_deg, min_line_length);
  if (marks != nullptr && marks->size() != mesh.vertices.size()) marks = nullptr;
  const float cos_limit = static_cast<float>(std::cos(radians(static_cast<double>(angle_deg))));
  return features_from_candidates(mesh, candidates_reaching(mesh, around, seeds, cos_limit, marks),
                                  angle_deg, min_line_length);
}

}  // namespace meshflow
