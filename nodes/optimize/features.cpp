#include "nodes/optimize/features.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "runtime/angles.h"

namespace meshflow {
namespace {

/// A candidate sharp edge {a, b} (a < b) and the normals of its two faces: `left` of the face
/// that runs a -> b, `right` of the one that runs b -> a.
struct FeatureCandidate {
  std::array<std::uint32_t, 2> ends;
  Eigen::Vector3f left, right;
};

/// One side of a face filed under its edge's smaller end: the larger end and the face.
struct FeatureSide {
  std::uint32_t other, face;
};

/// Every face's three sides filed under their edges' smaller ends (compressed rows, each row
/// in face order, then stably by the larger end): an edge's faces lie side by side, in face
/// order, and the rows list the edges in undirected_edge_key() order. Serial: O(V + T) and a
/// row's few entries sorted by insertion.
struct FeatureSideRows {
  std::vector<std::uint32_t> offsets;
  std::vector<FeatureSide> sides;

  explicit FeatureSideRows(const TriangleMesh& mesh) : offsets(mesh.vertices.size() + 1, 0) {
    const std::size_t n = mesh.vertices.size();
    for (const Triangle& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) ++offsets[std::min(t[k], t[(k + 1) % 3]) + 1];
    for (std::size_t v = 0; v < n; ++v) offsets[v + 1] += offsets[v];
    sides.resize(offsets[n]);
    std::vector<std::uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (std::uint32_t f = 0; f < mesh.triangles.size(); ++f) {
      const Triangle& t = mesh.triangles[f];
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = t[k], b = t[(k + 1) % 3];
        sides[fill[std::min(a, b)]++] = {std::max(a, b), f};
      }
    }
    for (std::size_t v = 0; v < n; ++v)  // stable: equal ends keep face order
      for (std::uint32_t i = offsets[v] + 1; i < offsets[v + 1]; ++i)
        for (std::uint32_t j = i; j > offsets[v] && sides[j - 1].other > sides[j].other; --j)
          std::swap(sides[j - 1], sides[j]);
  }
};

/// Edges with two faces meeting at a normal angle whose cosine is below cos_limit, sorted.
/// Face normals once per face, rows in parallel over fixed blocks joined in order: the same
/// for any thread count.
std::vector<FeatureCandidate> sharp_candidates(const TriangleMesh& mesh, float cos_limit) {
  const std::size_t n = mesh.vertices.size(), faces = mesh.triangles.size();
  std::vector<Eigen::Vector3f> normals(faces);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, faces),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t f = range.begin(); f != range.end(); ++f)
                        normals[f] = face_normal(mesh, mesh.triangles[f]);
                    });
  const FeatureSideRows rows(mesh);
  constexpr std::size_t kRowsPerBlock = 4096;
  const std::size_t blocks = (n + kRowsPerBlock - 1) / kRowsPerBlock;
  std::vector<std::vector<FeatureCandidate>> found(blocks);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t block) {
    std::vector<FeatureCandidate>& out = found[block];
    const auto end = static_cast<std::uint32_t>(std::min(n, (block + 1) * kRowsPerBlock));
    for (auto a = static_cast<std::uint32_t>(block * kRowsPerBlock); a < end; ++a) {
      const FeatureSide* row = rows.sides.data() + rows.offsets[a];
      const std::size_t size = rows.offsets[a + 1] - rows.offsets[a];
      for (std::size_t i = 0; i < size;) {
        std::size_t j = i;
        while (j < size && row[j].other == row[i].other) ++j;
        if (j - i == 2) {
          const Triangle& t0 = mesh.triangles[row[i].face];
          const Eigen::Vector3f& n0 = normals[row[i].face];
          const Eigen::Vector3f& n1 = normals[row[i + 1].face];
          if (n0.squaredNorm() > 0.0f && n1.squaredNorm() > 0.0f && n0.dot(n1) < cos_limit) {
            const std::uint32_t b = row[i].other;
            bool t0_runs_a_to_b = false;
            for (int k = 0; k < 3; ++k) t0_runs_a_to_b |= t0[k] == a && t0[(k + 1) % 3] == b;
            out.push_back({{a, b}, t0_runs_a_to_b ? n0 : n1, t0_runs_a_to_b ? n1 : n0});
          }
        }
        i = j;
      }
    }
  });
  std::vector<FeatureCandidate> out;
  for (const std::vector<FeatureCandidate>& part : found)
    out.insert(out.end(), part.begin(), part.end());
  return out;
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

/// Per vertex: whether it ends, branches or breaks a line (has candidates and is no line
/// vertex).
std::vector<std::uint8_t> line_breaks(const TriangleMesh& mesh,
                                      const std::vector<FeatureCandidate>& c,
                                      const FeatureIncidence& inc, float angle_deg) {
  const float cos_limit = static_cast<float>(std::cos(radians(static_cast<double>(angle_deg))));
  const float cos_side =
      static_cast<float>(std::cos(radians(std::min(90.0, 2.0 * static_cast<double>(angle_deg)))));
  const std::size_t n = mesh.vertices.size();
  std::vector<std::uint8_t> breaks(n, 0);
  for (std::uint32_t v = 0; v < n; ++v) {
    const std::uint32_t d = inc.degree(v);
    if (d == 0) continue;
    breaks[v] = d != 2 ||
                !continues_line(mesh, c[inc.edge(v, 0)], c[inc.edge(v, 1)], v, cos_limit, cos_side);
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
  FeatureIncidence inc;
  std::vector<std::uint8_t> breaks;
  for (;;) {  // drop short lines until every line left is long or a bridge between long ones
    inc = feature_incidence(n, c, alive);
    breaks = line_breaks(mesh, c, inc, angle_deg);
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
  for (std::uint32_t v = 0; v < n; ++v)
    if (inc.degree(v) > 0)
      f.vertex_kind[v] =
          breaks[v] ? MeshFeatures::VertexKind::kCorner : MeshFeatures::VertexKind::kLine;
  return f;
}

}  // namespace meshflow
