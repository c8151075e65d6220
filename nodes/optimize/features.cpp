#include "nodes/optimize/features.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "runtime/angles.h"
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
};

/// The sides of edge {a, b} (a != b) among the triangles around a: how many there are, and the
/// two lowest triangles holding one.
struct FeatureEdgeSides {
  int count = 0;
  std::uint32_t first = 0, second = 0;
};

FeatureEdgeSides feature_edge_sides(const TriangleMesh& mesh, const VertexTriangles& around,
                                    std::uint32_t a, std::uint32_t b) {
  FeatureEdgeSides s;
  std::uint32_t previous = 0xFFFFFFFFu;
  for (const std::uint32_t* it = around.begin(a); it != around.end(a); ++it) {
    if (*it == previous) continue;  // a triangle repeating a is listed once per repetition
    previous = *it;
    const Triangle& t = mesh.triangles[*it];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t p = t[k], q = t[(k + 1) % 3];
      if ((p == a && q == b) || (p == b && q == a)) {
        if (s.count == 0) s.first = *it;
        if (s.count == 1) s.second = *it;
        ++s.count;
      }
    }
  }
  return s;
}

/// Whether two of v's faces may meet at more than the feature angle: false where every face
/// normal around v lies within half that angle (less a margin for rounding: `cos_half`) of
/// their mean, so that no two of them are farther apart than the angle (no edge at v is sharp).
/// O(valence).
bool bent_vertex(const VertexTriangles& around, const std::vector<Eigen::Vector3f>& normals,
                 std::uint32_t v, float cos_half) {
  Eigen::Vector3f mean = Eigen::Vector3f::Zero();
  for (const std::uint32_t* t = around.begin(v); t != around.end(v); ++t) mean += normals[*t];
  if (!(mean.squaredNorm() > 0.0f))  // opposite faces, or none with area: look
    return around.end(v) - around.begin(v) > 1;
  mean.normalize();
  for (const std::uint32_t* t = around.begin(v); t != around.end(v); ++t)
    if (normals[*t].squaredNorm() > 0.0f && !(normals[*t].dot(mean) >= cos_half)) return true;
  return false;
}

/// One side of an edge {a, b} seen from its lower end a: the other end, the face, and whether the
/// face runs a -> b.
struct EdgeSide {
  std::uint32_t b, face;
  bool forward;
};

/// The candidates whose lower end is `a` (see sharp_candidates), ascending by their other end,
/// appended to `out`; `sides` is scratch memory. Every edge {a, b} (b > a) of a's faces (each face
/// once) is judged: exactly two sides in distinct faces, their normals apart by more than the
/// angle; `left` the normal of the face that runs min -> max, read from the lower face (as the
/// lowest face holding the edge sees it). O(valence log valence).
void candidates_at(const TriangleMesh& mesh, const VertexTriangles& around,
                   const std::vector<Eigen::Vector3f>& normals, std::uint32_t a, float cos_limit,
                   const std::vector<std::uint8_t>* seed, std::vector<EdgeSide>& sides,
                   std::vector<FeatureCandidate>& out) {
  sides.clear();
  std::uint32_t previous = 0xFFFFFFFFu;
  const std::size_t n = mesh.vertices.size();
  for (const std::uint32_t* it = around.begin(a); it != around.end(a); ++it) {
    if (*it == previous) continue;  // a triangle repeating a is listed once per repetition
    previous = *it;
    const Triangle& t = mesh.triangles[*it];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t p = t[k], q = t[(k + 1) % 3];
      if (p == q || (p != a && q != a)) continue;
      const std::uint32_t b = p == a ? q : p;
      if (b > a && b < n) sides.push_back({b, *it, p < q});
    }
  }
  // By other end, then face (faces come ascending: a stable sort keeps them so).
  for (std::size_t i = 1; i < sides.size(); ++i)
    for (std::size_t j = i; j > 0 && sides[j].b < sides[j - 1].b; --j)
      std::swap(sides[j], sides[j - 1]);
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i + 1;
    while (j < sides.size() && sides[j].b == sides[i].b) ++j;
    if (j - i == 2 && sides[i].face != sides[i + 1].face) {
      const Eigen::Vector3f& n0 = normals[sides[i].face];
      const Eigen::Vector3f& n1 = normals[sides[i + 1].face];
      if (n0.squaredNorm() > 0.0f && n1.squaredNorm() > 0.0f && n0.dot(n1) < cos_limit) {
        const std::uint32_t b = sides[i].b;
        const bool marked = seed != nullptr && (*seed)[a] != 0 && (*seed)[b] != 0;
        const bool forward = sides[i].forward;
        out.push_back({{a, b}, forward ? n0 : n1, forward ? n1 : n0, marked});
      }
    }
    i = j;
  }
}

/// Edges with two faces meeting at a normal angle whose cosine is below cos_limit (the angle
/// `angle_deg`), sorted. Face normals once, then one parallel pass over the vertices in fixed
/// blocks: a vertex whose faces all lie within half the angle of their mean (bent_vertex) ends
/// no sharp edge; the others judge their edges to higher vertices (candidates_at). The blocks'
/// lists, each sorted, joined in block order: sorted, the same for any thread count.
/// O(T + bent vertices x valence log valence). `around` is vertex_triangles(mesh).
/// `seed` (optional, one byte per vertex): candidates between two marked vertices are `marked`.
std::vector<FeatureCandidate> sharp_candidates(const TriangleMesh& mesh,
                                               const VertexTriangles& around, float angle_deg,
                                               float cos_limit,
                                               const std::vector<std::uint8_t>* seed = nullptr) {
  const std::size_t t_count = mesh.triangles.size();
  std::vector<Eigen::Vector3f> normals(t_count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, t_count), [&](const auto& range) {
    for (std::size_t t = range.begin(); t != range.end(); ++t)
      normals[t] = face_normal(mesh, mesh.triangles[t]);
  });
  constexpr double kRoundingMarginDeg = 0.1;
  const double half = std::max(0.0, 0.5 * static_cast<double>(angle_deg) - kRoundingMarginDeg);
  const auto cos_half = static_cast<float>(std::cos(radians(half)));
  const std::size_t n = mesh.vertices.size();
  const std::size_t blocks = (n + kParallelBlock - 1) / kParallelBlock;
  std::vector<std::vector<FeatureCandidate>> parts(blocks);
  tbb::enumerable_thread_specific<std::vector<EdgeSide>> scratch;
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t block) {
    std::vector<EdgeSide>& sides = scratch.local();
    const std::size_t end = std::min(n, (block + 1) * kParallelBlock);
    for (std::size_t v = block * kParallelBlock; v < end; ++v) {
      const auto a = static_cast<std::uint32_t>(v);
      if (bent_vertex(around, normals, a, cos_half))
        candidates_at(mesh, around, normals, a, cos_limit, seed, sides, parts[block]);
    }
  });
  return concatenate_parts(parts);
}

/// The live candidates around every vertex (compressed rows of candidate indices).
struct FeatureIncidence {
  std::vector<std::uint32_t> offsets, edges;
  std::uint32_t degree(std::uint32_t v) const { return offsets[v + 1] - offsets[v]; }
  std::uint32_t edge(std::uint32_t v, std::uint32_t k) const { return edges[offsets[v] + k]; }
};

FeatureIncidence feature_incidence(std::size_t n, const std::vector<FeatureCandidate>& c,
                                   const std::vector<std::uint8_t>& alive) {
  FeatureIncidence inc;
  inc.offsets.assign(n + 1, 0);
  for (std::size_t i = 0; i < c.size(); ++i)
    if (alive[i])
      for (std::uint32_t v : c[i].ends) ++inc.offsets[v + 1];
  for (std::size_t v = 0; v < n; ++v) inc.offsets[v + 1] += inc.offsets[v];
  inc.edges.resize(inc.offsets[n]);
  std::vector<std::uint32_t> fill(inc.offsets.begin(), inc.offsets.end() - 1);
  for (std::size_t i = 0; i < c.size(); ++i)
    if (alive[i])
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
/// vertex).
std::vector<std::uint8_t> line_breaks(const std::vector<Eigen::Vector3f>& points,
                                      const std::vector<FeatureCandidate>& c,
                                      const FeatureIncidence& inc, float angle_deg) {
  const float cos_limit = static_cast<float>(std::cos(radians(static_cast<double>(angle_deg))));
  const float cos_side =
      static_cast<float>(std::cos(radians(std::min(90.0, 2.0 * static_cast<double>(angle_deg)))));
  const std::size_t n = points.size();
  std::vector<std::uint8_t> breaks(n, 0);
  for (std::uint32_t v = 0; v < n; ++v) {
    const std::uint32_t d = inc.degree(v);
    if (d == 0) continue;
    breaks[v] = d != 2 || !continues_line(points, c[inc.edge(v, 0)], c[inc.edge(v, 1)], v,
                                          cos_limit, cos_side);
  }
  return breaks;
}

/// The lines: runs of candidates between breaks (or closed loops without one).
struct FeatureLines {
  std::vector<std::uint32_t> line_of;              ///< per candidate (alive ones only)
  std::vector<float> length;                       ///< per line, metres
  std::vector<std::array<std::uint32_t, 2>> ends;  ///< per line; a loop: {kNoEnd, kNoEnd}
};
constexpr std::uint32_t kNoEnd = 0xFFFFFFFFu;

FeatureLines trace_lines(const std::vector<Eigen::Vector3f>& points,
                         const std::vector<FeatureCandidate>& c,
                         const std::vector<std::uint8_t>& alive, const FeatureIncidence& inc,
                         const std::vector<std::uint8_t>& breaks) {
  FeatureLines lines;
  lines.line_of.assign(c.size(), kNoEnd);
  for (std::uint32_t start = 0; start < c.size(); ++start) {
    if (!alive[start] || lines.line_of[start] != kNoEnd) continue;
    const auto id = static_cast<std::uint32_t>(lines.length.size());
    lines.line_of[start] = id;
    float length = (points[c[start].ends[0]] - points[c[start].ends[1]]).norm();
    std::array<std::uint32_t, 2> ends{kNoEnd, kNoEnd};
    for (int side = 0; side < 2; ++side) {  // walk away from start through both of its ends
      std::uint32_t edge = start, v = c[start].ends[side];
      while (!breaks[v]) {
        edge = inc.edge(v, 0) == edge ? inc.edge(v, 1) : inc.edge(v, 0);
        if (lines.line_of[edge] == id) break;  // a closed loop
        lines.line_of[edge] = id;
        length += (points[c[edge].ends[0]] - points[c[edge].ends[1]]).norm();
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

MeshFeatures features_from_candidates(const TriangleMesh& mesh, std::vector<FeatureCandidate> c,
                                      float angle_deg, float min_line_length) {
  MeshFeatures f;
  f.vertex_kind.assign(mesh.vertices.size(), MeshFeatures::VertexKind::kFree);
  if (c.empty()) return f;
  if (min_line_length == 0.0f) min_line_length = kMinFeatureLineEdges * median_edge_length(mesh);
  // The lines are traced on the candidates' own vertices only (numbered in mesh order, so the
  // candidates stay sorted): each round costs O(candidates), not O(V).
  std::vector<std::uint32_t> global;
  global.reserve(2 * c.size());
  for (const FeatureCandidate& e : c) global.insert(global.end(), e.ends.begin(), e.ends.end());
  std::sort(global.begin(), global.end());
  global.erase(std::unique(global.begin(), global.end()), global.end());
  for (FeatureCandidate& e : c)
    for (std::uint32_t& v : e.ends)
      v = static_cast<std::uint32_t>(std::lower_bound(global.begin(), global.end(), v) -
                                     global.begin());
  const std::size_t n = global.size();
  std::vector<Eigen::Vector3f> points(n);
  for (std::size_t v = 0; v < n; ++v) points[v] = mesh.vertices[global[v]];
  std::vector<std::uint8_t> alive(c.size(), 1);
  FeatureIncidence inc;
  std::vector<std::uint8_t> breaks;
  for (;;) {  // drop short lines until every line left is long or a bridge between long ones
    inc = feature_incidence(n, c, alive);
    breaks = line_breaks(points, c, inc, angle_deg);
    if (min_line_length < 0.0f) break;
    const FeatureLines lines = trace_lines(points, c, alive, inc, breaks);
    std::vector<std::uint8_t> long_line(lines.length.size());
    for (std::size_t l = 0; l < long_line.size(); ++l)
      long_line[l] = lines.length[l] >= min_line_length;
    std::vector<std::uint8_t> keep = long_line;
    for (std::size_t i = 0; i < c.size(); ++i)  // a line with a marked edge is no noise
      if (alive[i] && c[i].marked) keep[lines.line_of[i]] = 1;
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
    bool dropped = false;
    for (std::size_t i = 0; i < c.size(); ++i)
      if (alive[i] && !keep[lines.line_of[i]]) alive[i] = 0, dropped = true;
    if (!dropped) break;
  }
  for (std::size_t i = 0; i < c.size(); ++i)
    if (alive[i]) f.edges.push_back({global[c[i].ends[0]], global[c[i].ends[1]]});
  for (std::uint32_t v = 0; v < n; ++v)
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
