#include "nodes/optimize/cleanup/hole_filling.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "runtime/disjoint_sets.h"
#include "runtime/vertex_triangles.h"

namespace meshflow {
namespace {

// The mesh's edges between vertices of `loop` (sorted keys), for "would this diagonal duplicate
// an edge?". `in_loop` marks the loop's vertices.
std::vector<std::uint64_t> edges_within(const TriangleMesh& mesh, const VertexTriangles& around,
                                        const std::vector<std::uint32_t>& loop,
                                        const std::vector<std::uint8_t>& in_loop) {
  std::vector<std::uint64_t> edges;
  for (std::uint32_t v : loop)
    for (const std::uint32_t* t = around.begin(v); t != around.end(v); ++t)
      for (std::uint32_t x : mesh.triangles[*t])
        if (x != v && in_loop[x]) edges.push_back(undirected_edge_key(v, x));
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

// Border loops as vertex lists (each vertex followed by the target of its border edge), in the
// order of their first border edge. A loop through a vertex with two border edges leaving it
// (a non-manifold vertex) is ambiguous and is not returned; `ambiguous` counts such loops.
std::vector<std::vector<std::uint32_t>> border_loops(const TriangleMesh& mesh,
                                                     const VertexTriangles& around,
                                                     std::size_t& ambiguous) {
  constexpr std::uint32_t kNoEdge = UINT32_MAX, kTwoEdges = UINT32_MAX - 1;
  const std::vector<BorderEdge> border = border_edges(mesh, around);
  std::vector<std::uint32_t> leaving(mesh.vertices.size(), kNoEdge);
  for (std::uint32_t e = 0; e < border.size(); ++e) {
    std::uint32_t& slot = leaving[border[e].a];
    slot = slot == kNoEdge ? e : kTwoEdges;
  }
  std::vector<std::vector<std::uint32_t>> loops;
  std::vector<std::uint8_t> walked(border.size(), 0);
  ambiguous = 0;
  for (std::uint32_t start = 0; start < border.size(); ++start) {
    if (walked[start]) continue;
    std::vector<std::uint32_t> loop;
    bool closed = false;
    for (std::uint32_t e = start;;) {
      walked[e] = 1;
      loop.push_back(border[e].a);
      const std::uint32_t next = leaving[border[e].b];
      if (next >= kTwoEdges) break;  // no way on, or two
      if (next == start) {
        closed = true;
        break;
      }
      if (walked[next]) break;
      e = next;
    }
    if (closed)
      loops.push_back(std::move(loop));
    else
      ++ambiguous;
  }
  return loops;
}

// Component label (a representative vertex) of every vertex: union-find over triangle corners.
std::vector<std::uint32_t> vertex_components(const TriangleMesh& mesh) {
  DisjointSets sets(mesh.vertices.size());
  for (const Triangle& t : mesh.triangles) {
    sets.unite(t[0], t[1]);
    sets.unite(t[0], t[2]);
  }
  return sets.labels();
}

// Minimum-weight triangulation of the polygon `loop` (vertex indices in border order) by
// dynamic programming over its diagonals; triangles come out reversed against the border so
// they face like the surrounding mesh. Empty when every triangulation needs an existing edge.
std::vector<Triangle> triangulate_loop(const std::vector<std::uint32_t>& loop,
                                       const std::vector<Eigen::Vector3f>& positions,
                                       const std::vector<std::uint64_t>& edges) {
  if (loop.size() < 3) return {};
  const std::size_t n = loop.size();
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  std::vector<double> weight(n * n, kInfinity);
  std::vector<std::uint32_t> split(n * n, 0);
  auto at = [n](std::size_t i, std::size_t j) { return i * n + j; };
  auto usable = [&](std::size_t i, std::size_t j) {         // i < j
    if (j == i + 1 || (i == 0 && j == n - 1)) return true;  // a border edge
    return !std::binary_search(edges.begin(), edges.end(), undirected_edge_key(loop[i], loop[j]));
  };
  auto triangle_weight = [&](std::size_t i, std::size_t m, std::size_t j) -> double {
    const Eigen::Vector3d a = positions[loop[i]].cast<double>(),
                          b = positions[loop[m]].cast<double>(),
                          c = positions[loop[j]].cast<double>();
    const double area = 0.5 * (b - a).cross(c - a).norm();
    const double squares = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
    // Collinear corners (a straight stretch of border) would make a triangle without area.
    if (!(area > 1e-4 * squares)) return kInfinity;
    return area + 0.1 * squares;
  };
  for (std::size_t i = 0; i + 1 < n; ++i) weight[at(i, i + 1)] = 0.0;
  for (std::size_t span = 2; span < n; ++span)
    for (std::size_t i = 0; i + span < n; ++i) {
      const std::size_t j = i + span;
      if (!usable(i, j)) continue;
      for (std::size_t m = i + 1; m < j; ++m) {
        const double w = weight[at(i, m)] + weight[at(m, j)];
        if (!(w < weight[at(i, j)])) continue;  // also skips infinite sub-polygons
        const double total = w + triangle_weight(i, m, j);
        if (total < weight[at(i, j)]) {
          weight[at(i, j)] = total;
          split[at(i, j)] = static_cast<std::uint32_t>(m);
        }
      }
    }
  std::vector<Triangle> triangles;
  if (weight[at(0, n - 1)] == kInfinity) return triangles;
  std::vector<std::pair<std::size_t, std::size_t>> pending{{0, n - 1}};
  while (!pending.empty()) {
    const auto [i, j] = pending.back();
    pending.pop_back();
    if (j < i + 2) continue;
    const std::size_t m = split[at(i, j)];
    triangles.push_back(Triangle{loop[j], loop[m], loop[i]});
    pending.emplace_back(i, m);
    pending.emplace_back(m, j);
  }
  return triangles;
}

// The loop closed by a fan around a vertex added at its centroid (normal and colour averaged
// over the loop, when the mesh has them): its edges are all new, so it is always possible.
// Each triangle runs its loop edge in the loop's direction, against the face beyond that edge,
// so the fan is oriented like the faces around the hole.
std::vector<Triangle> fan_from_centre(const std::vector<std::uint32_t>& loop, TriangleMesh& mesh) {
  Eigen::Vector3f centre = Eigen::Vector3f::Zero(), normal = Eigen::Vector3f::Zero();
  Eigen::Vector3f colour = Eigen::Vector3f::Zero();
  for (std::uint32_t v : loop) {
    centre += mesh.vertices[v];
    if (!mesh.normals.empty()) normal += mesh.normals[v];
    if (!mesh.colors.empty())
      colour += Eigen::Vector3f(mesh.colors[v].r, mesh.colors[v].g, mesh.colors[v].b);
  }
  const float count = static_cast<float>(loop.size());
  const auto c = static_cast<std::uint32_t>(mesh.vertices.size());
  mesh.vertices.push_back(centre / count);
  if (!mesh.normals.empty()) mesh.normals.push_back(normal.normalized());
  if (!mesh.colors.empty()) {
    const Eigen::Vector3f rgb = colour / count;
    mesh.colors.push_back(Rgb8{static_cast<std::uint8_t>(std::lround(rgb.x())),
                               static_cast<std::uint8_t>(std::lround(rgb.y())),
                               static_cast<std::uint8_t>(std::lround(rgb.z()))});
  }
  std::vector<Triangle> fan;
  for (std::size_t k = 0; k < loop.size(); ++k)
    fan.push_back(Triangle{loop[k], c, loop[(k + 1) % loop.size()]});
  return fan;
}

// Area of each component (indexed by its label, as vertex_components() gives per vertex), m^2.
std::vector<double> component_areas(const TriangleMesh& mesh,
                                    const std::vector<std::uint32_t>& component) {
  std::vector<double> area(mesh.vertices.size(), 0.0);
  for (const Triangle& t : mesh.triangles) {
    const Eigen::Vector3f& a = mesh.vertices[t[0]];
    area[component[t[0]]] +=
        0.5 * static_cast<double>((mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a).norm());
  }
  return area;
}

// Whether a loop of `length` metres can be the outline of a surface of `area` m^2. A disk's
// outline satisfies length^2 = 4 pi area, and the outline of any scanned sheet is longer still
// (its border is ragged); a loop far shorter than that cannot bound the component, which is then
// a closed surface with a hole (e.g. a closed object's mesh with a gap at a sharp edge).
bool could_be_outline(double length, double area) {
  constexpr double kShortestOutline = 0.05;  // of the disk's length^2 / area
  return length * length >= kShortestOutline * 4.0 * M_PI * area;
}

}  // namespace

TriangleMesh fill_holes(const TriangleMesh& mesh, const HoleFillingConfig& config,
                        HoleFillingReport* report) {
  HoleFillingReport r;
  std::size_t ambiguous = 0;
  const VertexTriangles around = vertex_triangles(mesh);
  const std::vector<std::vector<std::uint32_t>> loops = border_loops(mesh, around, ambiguous);
  r.loops = loops.size() + ambiguous;
  r.not_fillable = ambiguous;

  // The outer border of each component: its longest loop (the first on ties).
  std::vector<double> lengths(loops.size(), 0.0);
  for (std::size_t l = 0; l < loops.size(); ++l)
    for (std::size_t i = 0; i < loops[l].size(); ++i)
      lengths[l] += static_cast<double>(
          (mesh.vertices[loops[l][(i + 1) % loops[l].size()]] - mesh.vertices[loops[l][i]]).norm());
  std::vector<std::uint8_t> outer(loops.size(), 0);
  if (config.keep_outer_border) {
    const std::vector<std::uint32_t> component = vertex_components(mesh);
    std::vector<std::size_t> longest(mesh.vertices.size(), SIZE_MAX);
    for (std::size_t l = 0; l < loops.size(); ++l) {
      std::size_t& best = longest[component[loops[l].front()]];
      if (best == SIZE_MAX || lengths[l] > lengths[best]) best = l;
    }
    const std::vector<double> area = component_areas(mesh, component);
    for (std::size_t c = 0; c < longest.size(); ++c) {
      const std::size_t best = longest[c];
      if (best != SIZE_MAX && could_be_outline(lengths[best], area[c])) outer[best] = 1;
    }
  }

  std::vector<const std::vector<std::uint32_t>*> holes;
  for (std::size_t l = 0; l < loops.size(); ++l) {
    if (outer[l])
      ++r.outer_borders;
    else if (loops[l].size() > config.max_edges)
      ++r.too_large;
    else
      holes.push_back(&loops[l]);
  }

  // Loops share no vertex (each border vertex has one border edge leaving it), so each hole's
  // marks and triangulation are its own.
  std::vector<std::uint8_t> in_hole(mesh.vertices.size(), 0);
  for (const auto* hole : holes)
    for (std::uint32_t v : *hole) in_hole[v] = 1;
  std::vector<std::vector<Triangle>> fills(holes.size());
  tbb::parallel_for(std::size_t{0}, holes.size(), [&](std::size_t i) {
    fills[i] =
        triangulate_loop(*holes[i], mesh.vertices, edges_within(mesh, around, *holes[i], in_hole));
  });

  TriangleMesh out = mesh;
  for (std::size_t i = 0; i < fills.size(); ++i) {
    if (fills[i].empty()) {  // every triangulation repeats an edge: fan from a new centre
      fills[i] = fan_from_centre(*holes[i], out);
      ++r.centre_vertices;
    }
    ++r.filled;
    r.added_triangles += fills[i].size();
    out.triangles.insert(out.triangles.end(), fills[i].begin(), fills[i].end());
  }
  if (report != nullptr) *report = r;
  return out;
}

}  // namespace meshflow
