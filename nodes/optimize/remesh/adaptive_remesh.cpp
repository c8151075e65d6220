#include "nodes/optimize/remesh/adaptive_remesh.h"

#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>

#include "nodes/optimize/feature_snap.h"
#include "nodes/search/closest_point.h"
#include "nodes/search/mesh_distance_index.h"
#include "runtime/half_edge_mesh.h"

namespace meshflow {
namespace {

using Vec3 = Eigen::Vector3f;
constexpr std::uint32_t kNone = HalfEdgeMesh::kNone;
constexpr float kSplitAbove = 4.0f / 3.0f;  // Botsch & Kobbelt's thresholds around the target
constexpr float kCollapseBelow = 4.0f / 5.0f;
constexpr float kSmallestMove = 0.05f;  // relaxation leaves vertices this close (x target) alone
// snap_feature_vertices() moves a feature vertex by up to 2 median edges, onto sides flat to
// within 0.05 of one (a noisy scan's sides are not: its feature vertices stay).
constexpr float kSnapMoveEdges = 2.0f;
constexpr float kSnapFlatnessEdges = 0.05f;
// The default tolerance: this many times the input's roughness, within [this share, a quarter]
// of its median edge. (A scan's extraction is smoothed by its voxels: its roughness understates
// its noise; kurt3d at 5 cm: roughness 2.0 mm, the quarter edge 12.6 mm.)
constexpr float kToleranceRoughness = 6.0f;
constexpr float kLeastToleranceEdges = 0.01f;

/// The remesher's state: the mesh and what each vertex carries alongside it.
struct Remesher {
  const TriangleMesh& input;  // the surface new and moved vertices are projected onto
  const MeshDistanceIndex& surface;
  HalfEdgeMesh mesh;
  std::vector<float> target;     // edge length wanted around each vertex (metres)
  std::vector<float> curvature;  // largest absolute principal curvature (1/metres)
  std::vector<Rgb8> colors;      // empty when the input has none
  float tolerance = 0.0f;
  float min_turn_cos = 0.0f;
  float max_border_turn_sin = 0.0f;
  /// Feature graph: kind of every vertex (MeshFeatures::VertexKind) and the sharp edges as
  /// undirected_edge_key()s, kept current through splits and collapses.
  std::vector<MeshFeatures::VertexKind> kind;
  std::unordered_set<std::uint64_t> sharp;

  bool is_free(std::uint32_t v) const { return kind[v] == MeshFeatures::VertexKind::kFree; }
  bool is_sharp(std::uint32_t a, std::uint32_t b) const {
    return !sharp.empty() && sharp.count(undirected_edge_key(a, b)) != 0;
  }
};

bool removed(const HalfEdgeMesh& h, std::uint32_t v) { return h.outgoing(v) == kNone; }

/// The vertices around v, in ring order (on a border, the last one closes the open fan).
std::vector<std::uint32_t> neighbour_vertices(const HalfEdgeMesh& h, std::uint32_t v) {
  const std::vector<std::uint32_t> ring = h.ring(v);
  std::vector<std::uint32_t> out;
  out.reserve(ring.size() + 1);
  for (std::uint32_t e : ring) out.push_back(h.to(e));
  if (!ring.empty() && h.is_border_vertex(v)) out.push_back(h.to(HalfEdgeMesh::next(ring.back())));
  return out;
}

/// Face f's vertices in its winding order (the first half-edge runs from the first to the second).
Triangle corners(const HalfEdgeMesh& h, std::uint32_t f) {
  return {h.to(3 * f + 2), h.to(3 * f), h.to(3 * f + 1)};
}

Vec3 face_cross(const HalfEdgeMesh& h, std::uint32_t f) {
  const Triangle t = corners(h, f);
  const Vec3& a = h.position(t[0]);
  return (h.position(t[1]) - a).cross(h.position(t[2]) - a);
}

bool face_has_area(const HalfEdgeMesh& h, std::uint32_t f) {
  const Triangle t = corners(h, f);
  return has_area(h.position(t[0]), h.position(t[1]), h.position(t[2]));
}

/// Whether the face area vector `after` is within the turn whose cosine is `min_cos` of `before`.
bool within_turn(const Vec3& before, const Vec3& after, float min_cos) {
  return before.dot(after) >= min_cos * before.norm() * after.norm();
}

/// Area-weighted unit normal at v (zero without area).
Vec3 vertex_normal(const HalfEdgeMesh& h, std::uint32_t v) {
  Vec3 n = Vec3::Zero();
  for (std::uint32_t e : h.ring(v)) n += face_cross(h, HalfEdgeMesh::face(e));
  return n.squaredNorm() > 0.0f ? Vec3(n.normalized()) : n;
}

/// Every vertex's neighbours in compressed rows: a snapshot of the mesh's connectivity for the
/// passes that read it many times without changing it. Parallel over vertices; O(V x valence).
struct Adjacency {
  std::vector<std::uint32_t> offsets;  // vertex_count + 1
  std::vector<std::uint32_t> vertices;
  const std::uint32_t* begin(std::uint32_t v) const { return vertices.data() + offsets[v]; }
  const std::uint32_t* end(std::uint32_t v) const { return vertices.data() + offsets[v + 1]; }
};

Adjacency adjacency(const HalfEdgeMesh& h) {
  const std::size_t n = h.vertex_count();
  Adjacency a;
  a.offsets.assign(n + 1, 0);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t v) {
    a.offsets[v + 1] =
        static_cast<std::uint32_t>(neighbour_vertices(h, static_cast<std::uint32_t>(v)).size());
  });
  for (std::size_t v = 0; v < n; ++v) a.offsets[v + 1] += a.offsets[v];
  a.vertices.resize(a.offsets[n]);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t v) {
    const std::vector<std::uint32_t> around = neighbour_vertices(h, static_cast<std::uint32_t>(v));
    std::copy(around.begin(), around.end(), a.vertices.begin() + a.offsets[v]);
  });
  return a;
}

/// The vertices within `rings` edges of v, v excluded, not reaching past a vertex that is not
/// free (`kind`; empty: no features): a sharp edge's vertices lie on both of its sides.
std::vector<std::uint32_t> neighbourhood(const Adjacency& adj, std::uint32_t v, int rings,
                                         const std::vector<MeshFeatures::VertexKind>& kind) {
  std::vector<std::uint32_t> found{v};
  std::size_t begin = 0;
  for (int r = 0; r < rings; ++r) {
    const std::size_t end = found.size();
    for (std::size_t i = begin; i < end; ++i) {
      if (i > 0 && !kind.empty() && kind[found[i]] != MeshFeatures::VertexKind::kFree) continue;
      for (const std::uint32_t* w = adj.begin(found[i]); w != adj.end(found[i]); ++w)
        if (std::find(found.begin(), found.end(), *w) == found.end()) found.push_back(*w);
    }
    begin = end;
  }
  found.erase(found.begin());
  return found;
}

/// Largest absolute principal curvature at v from the least-squares height field
/// z = a x^2 + b xy + c y^2 + d x + e y + f over its neighbourhood, in the frame of v's normal
/// (the constant and linear terms absorb noise and a tilted normal). 0 with fewer than six
/// neighbours or without a normal.
float fitted_curvature(const HalfEdgeMesh& h, const Adjacency& adj, std::uint32_t v, int rings,
                       const std::vector<MeshFeatures::VertexKind>& kind) {
  const Vec3 n = vertex_normal(h, v);
  const std::vector<std::uint32_t> near = neighbourhood(adj, v, rings, kind);
  if (n.squaredNorm() == 0.0f || near.size() < 6) return 0.0f;
  const Vec3 t1 = n.unitOrthogonal(), t2 = n.cross(t1);
  const Vec3& p = h.position(v);
  double scale = 0.0;
  for (std::uint32_t w : near) scale += (h.position(w) - p).norm();
  scale = scale > 0.0 ? static_cast<double>(near.size()) / scale : 1.0;  // unit mean distance
  Eigen::Matrix<double, 6, 6> normal_matrix = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> rhs = Eigen::Matrix<double, 6, 1>::Zero();
  auto add = [&](const Vec3& d) {
    const double x = scale * d.dot(t1), y = scale * d.dot(t2), z = scale * d.dot(n);
    Eigen::Matrix<double, 6, 1> row;
    row << x * x, x * y, y * y, x, y, 1.0;
    normal_matrix += row * row.transpose();
    rhs += z * row;
  };
  add(Vec3::Zero());
  for (std::uint32_t w : near) add(h.position(w) - p);
  const Eigen::Matrix<double, 6, 1> q = normal_matrix.ldlt().solve(rhs);
  if (!q.allFinite()) return 0.0f;
  Eigen::Matrix2d hessian;
  hessian << 2.0 * q[0], q[1], q[1], 2.0 * q[2];
  const Eigen::Vector2d k = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(hessian).eigenvalues();
  return static_cast<float>(std::max(std::abs(k[0]), std::abs(k[1])) * scale);
}

/// The input's roughness (metres): 1.4826 x the median, over the interior free vertices, of the
/// distance along the vertex normal from the vertex to the mean of its neighbours. Noise of
/// standard deviation s gives about s; a smooth surface only curvature x edge^2 / 4 (a clean
/// extraction's flat faces: nothing). Parallel over vertices; O(V x valence).
float surface_roughness(const HalfEdgeMesh& h, const Adjacency& adj,
                        const std::vector<MeshFeatures::VertexKind>& kind) {
  const std::size_t n = h.vertex_count();
  std::vector<float> d(n, -1.0f);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    const auto v = static_cast<std::uint32_t>(i);
    if (removed(h, v) || h.is_border_vertex(v) || kind[v] != MeshFeatures::VertexKind::kFree ||
        adj.end(v) - adj.begin(v) < 3)
      return;
    Vec3 mean = Vec3::Zero();
    for (const std::uint32_t* w = adj.begin(v); w != adj.end(v); ++w) mean += h.position(*w);
    mean /= static_cast<float>(adj.end(v) - adj.begin(v));
    d[i] = std::abs(vertex_normal(h, v).dot(h.position(v) - mean));
  });
  d.erase(std::remove(d.begin(), d.end(), -1.0f), d.end());
  if (d.empty()) return 0.0f;
  const auto middle = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
  std::nth_element(d.begin(), middle, d.end());
  return 1.4826f * *middle;
}

/// Target lengths from curvatures, clamped, then limited so that they grow by at most
/// `gradation` per metre from any vertex (Jacobi sweeps until stable).
std::vector<float> target_lengths(const HalfEdgeMesh& h, const Adjacency& adj,
                                  const std::vector<float>& curvature, float tolerance,
                                  float min_edge, float max_edge, float gradation) {
  const std::size_t n = h.vertex_count();
  std::vector<float> target(n);
  for (std::size_t v = 0; v < n; ++v) {
    // The longest edge kept, 4/3 of the target, spans a chord within the tolerance.
    const float wanted =
        curvature[v] > 0.0f ? std::sqrt(8.0f * tolerance / curvature[v]) / kSplitAbove : max_edge;
    target[v] = std::clamp(wanted, min_edge, max_edge);
  }
  std::vector<float> next(n);
  for (int sweep = 0; sweep < 64; ++sweep) {
    std::vector<std::uint8_t> changed(n, 0);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t v) {
      float t = target[v];
      for (const std::uint32_t* w = adj.begin(static_cast<std::uint32_t>(v));
           w != adj.end(static_cast<std::uint32_t>(v)); ++w)
        t = std::min(t, target[*w] + gradation * (h.position(*w) - h.position(v)).norm());
      next[v] = t;
      changed[v] = t < target[v] ? 1 : 0;
    });
    target.swap(next);
    if (std::find(changed.begin(), changed.end(), 1) == changed.end()) break;
  }
  return target;
}

/// The point of the input surface nearest to p when the input faces the way `normal` does
/// there (a thin part's other side is not taken); otherwise p itself.
Vec3 onto_input(const Remesher& r, const Vec3& p, const Vec3& normal) {
  const MeshDistanceIndex::Hit hit = r.surface.closest(p);
  if (!std::isfinite(hit.distance)) return p;
  const Vec3 facing = face_normal(r.input, r.input.triangles[hit.triangle]);
  return facing.dot(normal) > 0.5f ? hit.point : p;
}

float edge_target(const Remesher& r, std::uint32_t a, std::uint32_t b) {
  return std::min(r.target[a], r.target[b]);
}

/// One half-edge per undirected edge of the live faces, in half-edge order.
std::vector<std::uint32_t> edges(const HalfEdgeMesh& h) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t e = 0; e < h.half_edge_count(); ++e)
    if (h.face_alive(HalfEdgeMesh::face(e)) && (h.is_border(e) || e < h.twin(e))) out.push_back(e);
  return out;
}

float edge_length(const HalfEdgeMesh& h, std::uint32_t e) {
  return (h.position(h.to(e)) - h.position(h.from(e))).norm();
}

/// Longer than the other two edges of each of its faces (ties included): splitting only such
/// edges never makes an edge longer, so split rounds end.
bool longest_in_faces(const HalfEdgeMesh& h, std::uint32_t e) {
  const float length = edge_length(h, e);
  for (std::uint32_t side : {e, h.twin(e)}) {
    if (side == kNone) continue;
    if (edge_length(h, HalfEdgeMesh::next(side)) > length ||
        edge_length(h, HalfEdgeMesh::prev(side)) > length)
      return false;
  }
  return true;
}

/// Whether splitting the edge of e at p leaves every new face with area.
bool split_keeps_area(const HalfEdgeMesh& h, std::uint32_t e, const Vec3& p) {
  for (std::uint32_t side : {e, h.twin(e)}) {
    if (side == kNone) continue;
    const Vec3& c = h.position(h.to(HalfEdgeMesh::next(side)));
    if (!has_area(h.position(h.from(side)), p, c) || !has_area(p, h.position(h.to(side)), c))
      return false;
  }
  return true;
}

std::size_t split_long_edges(Remesher& r) {
  HalfEdgeMesh& h = r.mesh;
  std::size_t splits = 0;
  for (std::uint32_t e : edges(h)) {
    const std::uint32_t a = h.from(e), b = h.to(e);
    if (edge_length(h, e) <= kSplitAbove * edge_target(r, a, b) || !longest_in_faces(h, e))
      continue;
    Vec3 normal = face_cross(h, HalfEdgeMesh::face(e));
    if (!h.is_border(e)) normal += face_cross(h, HalfEdgeMesh::face(h.twin(e)));
    const bool sharp = r.is_sharp(a, b);  // split on the line itself, not projected off it
    const Vec3 middle = 0.5f * (h.position(a) + h.position(b));
    const Vec3 at = sharp ? middle : onto_input(r, middle, normal.normalized());
    if (!split_keeps_area(h, e, at)) continue;
    h.split(e, at);  // the new vertex is the last one
    const auto m = static_cast<std::uint32_t>(h.vertex_count() - 1);
    r.kind.push_back(sharp ? MeshFeatures::VertexKind::kLine : MeshFeatures::VertexKind::kFree);
    if (sharp) {
      r.sharp.erase(undirected_edge_key(a, b));
      r.sharp.insert(undirected_edge_key(a, m));
      r.sharp.insert(undirected_edge_key(m, b));
    }
    r.target.push_back(0.5f * (r.target[a] + r.target[b]));
    r.curvature.push_back(0.5f * (r.curvature[a] + r.curvature[b]));
    if (!r.colors.empty()) r.colors.push_back(midpoint_color(r.colors[a], r.colors[b]));
    ++splits;
  }
  return splits;
}

/// The sine of the turn between v's two border edges (prev -> v -> next).
float border_turn_sin(const HalfEdgeMesh& h, std::uint32_t v) {
  const std::uint32_t out = h.outgoing(v);  // the border half-edge leaving v
  std::uint32_t in = kNone;                 // the border half-edge arriving at v
  for (std::uint32_t e : h.ring(v)) in = HalfEdgeMesh::prev(e);
  if (in == kNone) return 1.0f;
  const Vec3 d1 = (h.position(v) - h.position(h.from(in))).normalized();
  const Vec3 d2 = (h.position(h.to(out)) - h.position(v)).normalized();
  return d1.dot(d2) <= 0.0f ? 1.0f : d1.cross(d2).norm();
}

/// The other end of u's second sharp edge, for u on a feature line and (u, v) one of its
/// sharp edges; kNone if there is none.
std::uint32_t line_neighbour(const Remesher& r, std::uint32_t u, std::uint32_t v) {
  for (std::uint32_t w : neighbour_vertices(r.mesh, u))
    if (w != v && r.is_sharp(u, w)) return w;
  return kNone;
}

/// Whether u -> v keeps the feature graph: corners stay; a vertex on a feature line moves only
/// onto a line neighbour, where the line w - u - v turns by less than the border limit, and
/// not when w and v are already joined by a sharp edge (a line of three would close).
bool keeps_features(const Remesher& r, std::uint32_t u, std::uint32_t v) {
  if (r.is_free(u)) return true;
  if (r.kind[u] != MeshFeatures::VertexKind::kLine || !r.is_sharp(u, v)) return false;
  const HalfEdgeMesh& h = r.mesh;
  if (h.is_border_vertex(u)) return false;
  const std::uint32_t w = line_neighbour(r, u, v);
  if (w == kNone || r.is_sharp(w, v)) return false;
  const Vec3 d1 = (h.position(u) - h.position(w)).normalized();
  const Vec3 d2 = (h.position(v) - h.position(u)).normalized();
  return d1.dot(d2) > 0.0f && d1.cross(d2).norm() <= r.max_border_turn_sin;
}

/// Whether removing u by collapsing u -> v keeps the mesh within the remesher's limits: every
/// edge v gains is short enough, every face that moves with u keeps its orientation within
/// the allowed turn, u lies within the tolerance of the faces that replace its own, and a
/// border vertex only slides along a nearly straight border; keeps_features() holds. The topology
/// is HalfEdgeMesh's.
bool collapse_allowed(const Remesher& r, std::uint32_t e) {
  const HalfEdgeMesh& h = r.mesh;
  const std::uint32_t u = h.from(e), v = h.to(e);
  if (!keeps_features(r, u, v)) return false;
  if (h.is_border_vertex(u)) {
    const bool along_border = h.is_border(e) || h.is_border(h.twin(e));
    if (!along_border || border_turn_sin(h, u) > r.max_border_turn_sin) return false;
  }
  const Vec3& pu = h.position(u);
  const Vec3& pv = h.position(v);
  for (std::uint32_t w : neighbour_vertices(h, u))
    if (w != v && (h.position(w) - pv).norm() > kSplitAbove * edge_target(r, v, w)) return false;
  float nearest = std::numeric_limits<float>::max();
  for (std::uint32_t out : h.ring(u)) {
    const std::uint32_t f = HalfEdgeMesh::face(out);
    const std::uint32_t b = h.to(out), c = h.to(HalfEdgeMesh::next(out));
    if (b == v || c == v) continue;  // disappears with the edge
    const Vec3 before = face_cross(h, f);
    const Vec3 after = (h.position(b) - pv).cross(h.position(c) - pv);
    if (!has_area(pv, h.position(b), h.position(c)) || !within_turn(before, after, r.min_turn_cos))
      return false;
    nearest = std::min(
        nearest, (closest_point_on_triangle(pu, pv, h.position(b), h.position(c)) - pu).norm());
  }
  return nearest <= r.tolerance || nearest == std::numeric_limits<float>::max();
}

std::size_t collapse_short_edges(Remesher& r) {
  HalfEdgeMesh& h = r.mesh;
  std::size_t collapses = 0;
  for (std::uint32_t e : edges(h)) {
    if (!h.face_alive(HalfEdgeMesh::face(e))) continue;  // gone with an earlier collapse
    const std::uint32_t a = h.from(e), b = h.to(e);
    if (edge_length(h, e) >= kCollapseBelow * edge_target(r, a, b)) continue;
    // Remove the flatter end first; the other direction when that one is not allowed.
    std::uint32_t first = e, second = h.twin(e);
    if (r.curvature[b] < r.curvature[a] || (r.curvature[b] == r.curvature[a] && b < a))
      std::swap(first, second);
    for (std::uint32_t c : {first, second}) {  // a border edge has one direction only
      if (c == kNone || !collapse_allowed(r, c)) continue;
      const std::uint32_t u = h.from(c), v = h.to(c);
      const std::uint32_t w = r.is_free(u) ? kNone : line_neighbour(r, u, v);
      if (!h.collapse(c)) continue;
      if (w != kNone) {  // the line w - u - v runs w - v now
        r.sharp.erase(undirected_edge_key(u, v));
        r.sharp.erase(undirected_edge_key(u, w));
        r.sharp.insert(undirected_edge_key(w, v));
      }
      ++collapses;
      break;
    }
  }
  return collapses;
}

int valence_deviation(const HalfEdgeMesh& h, const std::vector<int>& valence, std::uint32_t v,
                      int change) {
  const int ideal = h.is_border_vertex(v) ? 4 : 6;
  return (valence[v] + change - ideal) * (valence[v] + change - ideal);
}

/// Flips interior edges whose flip brings the four vertices' valences closer to 6 (4 on a
/// border) where the two faces are nearly coplanar and the new diagonal stays within the
/// tolerance of the old one.
std::size_t flip_towards_regular_valence(Remesher& r) {
  HalfEdgeMesh& h = r.mesh;
  std::size_t flips = 0;
  std::vector<int> valence(h.vertex_count());
  tbb::parallel_for(std::size_t{0}, valence.size(), [&](std::size_t v) {
    valence[v] = static_cast<int>(neighbour_vertices(h, static_cast<std::uint32_t>(v)).size());
  });
  for (std::uint32_t e : edges(h)) {
    if (h.is_border(e)) continue;
    const std::uint32_t t = h.twin(e);
    const std::uint32_t a = h.from(e), b = h.to(e);
    if (r.is_sharp(a, b)) continue;  // a sharp edge stays
    const std::uint32_t c = h.to(HalfEdgeMesh::next(e)), d = h.to(HalfEdgeMesh::next(t));
    const int before = valence_deviation(h, valence, a, 0) + valence_deviation(h, valence, b, 0) +
                       valence_deviation(h, valence, c, 0) + valence_deviation(h, valence, d, 0);
    const int after = valence_deviation(h, valence, a, -1) + valence_deviation(h, valence, b, -1) +
                      valence_deviation(h, valence, c, 1) + valence_deviation(h, valence, d, 1);
    if (after >= before) continue;
    const Vec3 &pa = h.position(a), &pb = h.position(b), &pc = h.position(c), &pd = h.position(d);
    const Vec3 n1 = face_cross(h, HalfEdgeMesh::face(e)), n2 = face_cross(h, HalfEdgeMesh::face(t));
    if (!within_turn(n1, n2, r.min_turn_cos)) continue;
    const Vec3 across = (pb - pa).cross(pd - pc);
    if (across.squaredNorm() == 0.0f) continue;
    if (std::abs((pc - pa).dot(across)) > r.tolerance * across.norm()) continue;  // diagonals apart
    if (!h.flip(e)) continue;
    --valence[a];
    --valence[b];
    ++valence[c];
    ++valence[d];
    ++flips;
  }
  return flips;
}

/// Moves every interior vertex towards the centroid of its neighbours within its tangent
/// plane, then back onto the input surface. Moves are computed in parallel from the current
/// positions, then applied in vertex order, each only when none of its faces turns by more
/// than the allowed angle.
void relax_tangentially(Remesher& r) {
  HalfEdgeMesh& h = r.mesh;
  const std::size_t n = h.vertex_count();
  std::vector<Vec3> moved(n);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    const auto v = static_cast<std::uint32_t>(i);
    moved[i] = h.position(v);
    if (removed(h, v) || h.is_border_vertex(v) || !r.is_free(v)) return;  // feature vertices stay
    const std::vector<std::uint32_t> around = neighbour_vertices(h, v);
    Vec3 centroid = Vec3::Zero();
    for (std::uint32_t w : around) centroid += h.position(w);
    centroid /= static_cast<float>(around.size());
    const Vec3 normal = vertex_normal(h, v);
    Vec3 step = centroid - h.position(v);
    step -= normal * normal.dot(step);
    if (step.norm() < kSmallestMove * r.target[v]) return;  // settled
    const Vec3 projected = onto_input(r, h.position(v) + step, normal);
    if (projected != h.position(v) + step) moved[i] = projected;  // else: no surface to follow
  });
  for (std::uint32_t v = 0; v < n; ++v) {
    if (moved[v] == h.position(v)) continue;
    const std::vector<std::uint32_t> ring = h.ring(v);
    std::vector<Vec3> before;
    before.reserve(ring.size());
    for (std::uint32_t e : ring) before.push_back(face_cross(h, HalfEdgeMesh::face(e)));
    const Vec3 old = h.position(v);
    h.set_position(v, moved[v]);
    for (std::size_t k = 0; k < ring.size(); ++k) {
      const Vec3 after = face_cross(h, HalfEdgeMesh::face(ring[k]));
      if (!face_has_area(h, HalfEdgeMesh::face(ring[k])) ||
          !within_turn(before[k], after, r.min_turn_cos)) {
        h.set_position(v, old);
        break;
      }
    }
  }
}

TriangleMesh output_mesh(const Remesher& r) {
  const HalfEdgeMesh& h = r.mesh;
  TriangleMesh all;
  all.vertices.resize(h.vertex_count());
  for (std::uint32_t v = 0; v < h.vertex_count(); ++v) all.vertices[v] = h.position(v);
  all.colors = r.colors;
  std::vector<Triangle> triangles;
  triangles.reserve(h.live_face_count());
  for (std::uint32_t f = 0; f < h.face_count(); ++f)
    if (h.face_alive(f)) triangles.push_back(corners(h, f));
  return compact_vertices(all, triangles);
}

}  // namespace

TriangleMesh adaptive_remesh(const TriangleMesh& mesh, const AdaptiveRemeshConfig& config,
                             AdaptiveRemeshReport* report, const MeshFeatures* given) {
  AdaptiveRemeshReport rep;
  rep.vertices_in = mesh.vertices.size();
  if (mesh.triangles.empty()) {
    if (report != nullptr) *report = rep;
    return mesh;
  }
  const float median = median_edge_length(mesh);
  const MeshFeatures features =
      given != nullptr ? *given
                       : detect_features(mesh, config.feature_angle_deg, config.feature_min_length);
  // Feature vertices onto their sides' planes first: the remesh keeps them and enlarges their
  // faces, so an extraction's stray edge vertex would spread its error.
  TriangleMesh snapped;
  if (!features.edges.empty()) {
    snapped = mesh;
    rep.snapped = snap_feature_vertices(snapped, features, kSnapMoveEdges * median,
                                        kSnapFlatnessEdges * median)
                      .moved;
  }
  const TriangleMesh& source = features.edges.empty() ? mesh : snapped;
  const MeshDistanceIndex surface(source);
  Remesher r{source, surface, HalfEdgeMesh(source), {}, {}, {}, 0.0f, 0.0f, 0.0f, {}, {}};
  r.kind = features.vertex_kind;
  for (const auto& e : features.edges) r.sharp.insert(undirected_edge_key(e[0], e[1]));
  rep.sharp_edges_in = features.edges.size();
  rep.corners = features.count(MeshFeatures::VertexKind::kCorner);
  r.min_turn_cos = std::cos(config.max_normal_turn_deg * static_cast<float>(M_PI) / 180.0f);
  r.max_border_turn_sin = std::sin(config.max_border_turn_deg * static_cast<float>(M_PI) / 180.0f);
  if (mesh.colors.size() == mesh.vertices.size()) r.colors = mesh.colors;
  const float min_edge = config.min_edge > 0.0f ? config.min_edge : median;
  const float max_edge =
      std::max(min_edge, config.max_edge > 0.0f ? config.max_edge : 8.0f * median);

  const std::size_t n = r.mesh.vertex_count();
  r.curvature.assign(n, 0.0f);
  const Adjacency adj = adjacency(r.mesh);
  // The input is as accurate as it is smooth: a clean extraction's chords are remeshed within
  // its own small deviations, a noisy scan's within its noise.
  r.tolerance = config.tolerance > 0.0f
                    ? config.tolerance
                    : std::clamp(kToleranceRoughness * surface_roughness(r.mesh, adj, r.kind),
                                 kLeastToleranceEdges * median, 0.25f * median);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t v) {
    if (!removed(r.mesh, static_cast<std::uint32_t>(v)))
      r.curvature[v] = r.is_free(static_cast<std::uint32_t>(v))
                           ? fitted_curvature(r.mesh, adj, static_cast<std::uint32_t>(v),
                                              config.curvature_rings, r.kind)
                           : 0.0f;  // along its line; its free neighbours set the lengths
  });
  r.target =
      target_lengths(r.mesh, adj, r.curvature, r.tolerance, min_edge, max_edge, config.gradation);

  for (int i = 0; i < config.iterations; ++i) {
    rep.splits += split_long_edges(r);
    rep.collapses += collapse_short_edges(r);
    rep.flips += flip_towards_regular_valence(r);
    relax_tangentially(r);
  }
  rep.tolerance = r.tolerance;
  rep.min_target = *std::min_element(r.target.begin(), r.target.end());
  rep.max_target = *std::max_element(r.target.begin(), r.target.end());
  TriangleMesh out = output_mesh(r);
  rep.vertices_out = out.vertices.size();
  if (report != nullptr) *report = rep;
  return out;
}

}  // namespace meshflow
