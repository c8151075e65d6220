#include "nodes/optimize/features.h"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "runtime/angles.h"

namespace meshflow {
namespace {

/// A candidate sharp edge {a, b} (a < b) and the normals of its two faces: `left` of the face
/// that runs a -> b, `right` of the one that runs b -> a.
struct FeatureCandidate {
  std::array<std::uint32_t, 2> ends;
  Eigen::Vector3f left, right;
};

/// One side of a face: its edge's undirected key and the face. The empty default constructor
/// leaves a vector of them unwritten (no serial zeroing of 16 bytes per side).
struct FaceSide {
  std::uint64_t key;
  std::uint32_t face;
  FaceSide() {}  // not `= default`, which would zero a vector of them
  FaceSide(std::uint64_t k, std::uint32_t f) : key(k), face(f) {}
  bool operator<(const FaceSide& o) const { return key != o.key ? key < o.key : face < o.face; }
};

/// Edges with two faces meeting at a normal angle whose cosine is below cos_limit, sorted.
/// Parallel: the sort and the face normals; the scan over the sorted sides is linear.
std::vector<FeatureCandidate> sharp_candidates(const TriangleMesh& mesh, float cos_limit) {
  // Every face's edges as (undirected key, face), sorted: an edge's faces are neighbours. The
  // pairs are unique, so the parallel sort's order is the only one.
  const std::size_t faces = mesh.triangles.size();
  std::vector<FaceSide> sides(3 * faces);  // left uninitialised: the parallel loop writes all
  std::vector<Eigen::Vector3f> normal(faces);
  tbb::parallel_for(std::size_t{0}, faces, [&](std::size_t t) {
    const Triangle& tri = mesh.triangles[t];
    for (std::size_t k = 0; k < 3; ++k)
      sides[3 * t + k] =
          FaceSide(undirected_edge_key(tri[k], tri[(k + 1) % 3]), static_cast<std::uint32_t>(t));
    normal[t] = face_normal(mesh, tri);
  });
  tbb::parallel_sort(sides.begin(), sides.end());
  std::vector<FeatureCandidate> out;
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i;
    while (j < sides.size() && sides[j].key == sides[i].key) ++j;
    if (j - i == 2) {
      const Triangle& t0 = mesh.triangles[sides[i].face];
      const Eigen::Vector3f& n0 = normal[sides[i].face];
      const Eigen::Vector3f& n1 = normal[sides[i + 1].face];
      if (n0.squaredNorm() > 0.0f && n1.squaredNorm() > 0.0f && n0.dot(n1) < cos_limit) {
        const auto a = static_cast<std::uint32_t>(sides[i].key >> 32);
        const auto b = static_cast<std::uint32_t>(sides[i].key & 0xFFFFFFFFu);
        bool t0_runs_a_to_b = false;
        for (int k = 0; k < 3; ++k) t0_runs_a_to_b |= t0[k] == a && t0[(k + 1) % 3] == b;
        out.push_back({{a, b}, t0_runs_a_to_b ? n0 : n1, t0_runs_a_to_b ? n1 : n0});
      }
    }
    i = j;
  }
  return out;
}

constexpr std::uint32_t kNoRow = 0xFFFFFFFFu;

/// The vertices that candidates touch, ascending, and each mesh vertex's row among them
/// (kNoRow for the others): the rounds of detect_features() visit only these.
struct TouchedVertices {
  std::vector<std::uint32_t> vertices;
  std::vector<std::uint32_t> row;
};

TouchedVertices touched_vertices(std::size_t n, const std::vector<FeatureCandidate>& c) {
  TouchedVertices t;
  t.row.assign(n, kNoRow);
  for (const FeatureCandidate& e : c)
    for (std::uint32_t v : e.ends) t.row[v] = 0;
  for (std::uint32_t v = 0; v < n; ++v)
    if (t.row[v] != kNoRow) {
      t.row[v] = static_cast<std::uint32_t>(t.vertices.size());
      t.vertices.push_back(v);
    }
  return t;
}

/// The live candidates around every touched vertex (compressed rows of candidate indices).
struct FeatureIncidence {
  const TouchedVertices* touched = nullptr;
  std::vector<std::uint32_t> offsets, edges;
  std::uint32_t degree(std::uint32_t v) const {
    const std::uint32_t r = touched->row[v];
    return r == kNoRow ? 0 : offsets[r + 1] - offsets[r];
  }
  std::uint32_t edge(std::uint32_t v, std::uint32_t k) const {
    return edges[offsets[touched->row[v]] + k];
  }
};

/// O(candidates + touched vertices).
FeatureIncidence feature_incidence(const TouchedVertices& touched,
                                   const std::vector<FeatureCandidate>& c,
                                   const std::vector<std::uint8_t>& alive) {
  FeatureIncidence inc;
  inc.touched = &touched;
  const std::size_t m = touched.vertices.size();
  inc.offsets.assign(m + 1, 0);
  for (std::size_t i = 0; i < c.size(); ++i)
    if (alive[i])
      for (std::uint32_t v : c[i].ends) ++inc.offsets[touched.row[v] + 1];
  for (std::size_t r = 0; r < m; ++r) inc.offsets[r + 1] += inc.offsets[r];
  inc.edges.resize(inc.offsets[m]);
  std::vector<std::uint32_t> fill(inc.offsets.begin(), inc.offsets.end() - 1);
  for (std::size_t i = 0; i < c.size(); ++i)
    if (alive[i])
      for (std::uint32_t v : c[i].ends)
        inc.edges[fill[touched.row[v]]++] = static_cast<std::uint32_t>(i);
  return inc;
}

std::uint32_t other_end(const FeatureCandidate& e, std::uint32_t v) {
  return e.ends[0] == v ? e.ends[1] : e.ends[0];
}

/// Whether the two candidates at v (v has exactly two) continue one another: the line
/// a - v - b turns by less than the feature angle (cos_limit), and the faces on either side of
/// it by less than twice that (cos_side: a bumpy side of a true edge turns too).
bool continues_line(const TriangleMesh& mesh, const FeatureCandidate& in,
                    const FeatureCandidate& out, std::uint32_t v, float cos_limit, float cos_side) {
  const std::uint32_t a = other_end(in, v), b = other_end(out, v);
  const Eigen::Vector3f d_in = (mesh.vertices[v] - mesh.vertices[a]).normalized();
  const Eigen::Vector3f d_out = (mesh.vertices[b] - mesh.vertices[v]).normalized();
  if (d_in.dot(d_out) < cos_limit) return false;
  // Walking a -> v -> b, the face on the left of `in` runs a -> v.
  const Eigen::Vector3f& left_in = in.ends[0] == a ? in.left : in.right;
  const Eigen::Vector3f& right_in = in.ends[0] == a ? in.right : in.left;
  const Eigen::Vector3f& left_out = out.ends[0] == v ? out.left : out.right;
  const Eigen::Vector3f& right_out = out.ends[0] == v ? out.right : out.left;
  return left_in.dot(left_out) >= cos_side && right_in.dot(right_out) >= cos_side;
}

/// Per vertex (entries of touched vertices rewritten, the others left 0): whether it ends,
/// branches or breaks a line (has candidates and is no line vertex). O(touched vertices).
void line_breaks(const TriangleMesh& mesh, const std::vector<FeatureCandidate>& c,
                 const FeatureIncidence& inc, float angle_deg, std::vector<std::uint8_t>& breaks) {
  const float cos_limit = static_cast<float>(std::cos(radians(static_cast<double>(angle_deg))));
  const float cos_side =
      static_cast<float>(std::cos(radians(std::min(90.0, 2.0 * static_cast<double>(angle_deg)))));
  for (std::uint32_t v : inc.touched->vertices) {
    const std::uint32_t d = inc.degree(v);
    breaks[v] = d != 0 && (d != 2 || !continues_line(mesh, c[inc.edge(v, 0)], c[inc.edge(v, 1)], v,
                                                     cos_limit, cos_side));
  }
}

/// The lines: runs of candidates between breaks (or closed loops without one).
struct FeatureLines {
  std::vector<std::uint32_t> line_of;              ///< per candidate (alive ones only)
  std::vector<float> length;                       ///< per line, metres
  std::vector<std::array<std::uint32_t, 2>> ends;  ///< per line; a loop: {kNoEnd, kNoEnd}
};
constexpr std::uint32_t kNoEnd = 0xFFFFFFFFu;

FeatureLines trace_lines(const TriangleMesh& mesh, const std::vector<FeatureCandidate>& c,
                         const std::vector<std::uint8_t>& alive, const FeatureIncidence& inc,
                         const std::vector<std::uint8_t>& breaks) {
  FeatureLines lines;
  lines.line_of.assign(c.size(), kNoEnd);
  for (std::uint32_t start = 0; start < c.size(); ++start) {
    if (!alive[start] || lines.line_of[start] != kNoEnd) continue;
    const auto id = static_cast<std::uint32_t>(lines.length.size());
    lines.line_of[start] = id;
    float length = (mesh.vertices[c[start].ends[0]] - mesh.vertices[c[start].ends[1]]).norm();
    std::array<std::uint32_t, 2> ends{kNoEnd, kNoEnd};
    for (int side = 0; side < 2; ++side) {  // walk away from start through both of its ends
      std::uint32_t edge = start, v = c[start].ends[side];
      while (!breaks[v]) {
        edge = inc.edge(v, 0) == edge ? inc.edge(v, 1) : inc.edge(v, 0);
        if (lines.line_of[edge] == id) break;  // a closed loop
        lines.line_of[edge] = id;
        length += (mesh.vertices[c[edge].ends[0]] - mesh.vertices[c[edge].ends[1]]).norm();
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

MeshFeatures detect_features(const TriangleMesh& mesh, float angle_deg, float min_line_length) {
  MeshFeatures f;
  const std::size_t n = mesh.vertices.size();
  f.vertex_kind.assign(n, MeshFeatures::VertexKind::kFree);
  if (!(angle_deg < 180.0f)) return f;
  const float cos_limit = static_cast<float>(std::cos(radians(static_cast<double>(angle_deg))));
  const std::vector<FeatureCandidate> c = sharp_candidates(mesh, cos_limit);
  if (min_line_length == 0.0f) min_line_length = kMinFeatureLineEdges * median_edge_length(mesh);
  std::vector<std::uint8_t> alive(c.size(), 1);
  const TouchedVertices touched = touched_vertices(n, c);
  FeatureIncidence inc;
  std::vector<std::uint8_t> breaks(n, 0);
  for (;;) {  // drop short lines until every line left is long or a bridge between long ones
    inc = feature_incidence(touched, c, alive);
    line_breaks(mesh, c, inc, angle_deg, breaks);
    if (min_line_length < 0.0f) break;
    const FeatureLines lines = trace_lines(mesh, c, alive, inc, breaks);
    std::vector<std::uint8_t> long_line(lines.length.size());
    for (std::size_t l = 0; l < long_line.size(); ++l)
      long_line[l] = lines.length[l] >= min_line_length;
    std::vector<std::uint8_t> keep = long_line;
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
    if (alive[i]) f.edges.push_back(c[i].ends);
  for (std::uint32_t v : touched.vertices)
    if (inc.degree(v) > 0)
      f.vertex_kind[v] =
          breaks[v] ? MeshFeatures::VertexKind::kCorner : MeshFeatures::VertexKind::kLine;
  return f;
}

}  // namespace meshflow
