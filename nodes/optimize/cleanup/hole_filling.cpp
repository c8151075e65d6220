#include "nodes/optimize/cleanup/hole_filling.h"

#include <tbb/parallel_for.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <vector>

#include "runtime/mesh_components.h"
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

// Stands for a vertex a hole's fill adds (a lost corner) until it has its index.
constexpr std::uint32_t kAddedVertex = UINT32_MAX;

// Minimum-weight triangulation of the polygon `loop` (vertex indices in border order, at
// `points`) by dynamic programming over its diagonals; triangles come out reversed against the
// border so they face like the surrounding mesh. Empty when every triangulation needs an
// existing edge.
std::vector<Triangle> triangulate_loop(const std::vector<std::uint32_t>& loop,
                                       const std::vector<Eigen::Vector3f>& points,
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
    const Eigen::Vector3d a = points[i].cast<double>(), b = points[m].cast<double>(),
                          c = points[j].cast<double>();
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

std::vector<Eigen::Vector3f> loop_points(const std::vector<std::uint32_t>& loop,
                                         const std::vector<Eigen::Vector3f>& positions) {
  std::vector<Eigen::Vector3f> points;
  points.reserve(loop.size());
  for (std::uint32_t v : loop) points.push_back(positions[v]);
  return points;
}

// The sharp edges around each vertex: how many, and the other ends of the first two.
struct HoleFeatureLinks {
  std::vector<std::uint32_t> degree;
  std::vector<std::array<std::uint32_t, 2>> ends;
};

HoleFeatureLinks hole_feature_links(std::size_t vertices, const MeshFeatures& features) {
  HoleFeatureLinks links;
  links.degree.assign(vertices, 0);
  links.ends.assign(vertices, {0, 0});
  for (const auto& e : features.edges)
    for (int k = 0; k < 2; ++k) {
      std::uint32_t& d = links.degree[e[k]];
      if (d < 2) links.ends[e[k]][d] = e[1 - k];
      ++d;
    }
  return links;
}

// A feature line ending on a hole's border: where on the loop, and the line's direction there
// (unit, into the hole), from its last few edges.
struct HoleEntry {
  std::size_t at;
  Eigen::Vector3f direction;
};

std::vector<HoleEntry> hole_entries(const std::vector<std::uint32_t>& loop,
                                    const std::vector<Eigen::Vector3f>& positions,
                                    const HoleFeatureLinks& links) {
  constexpr int kDirectionEdges = 4;
  std::vector<HoleEntry> entries;
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const std::uint32_t v = loop[i];
    if (links.degree[v] != 1) continue;  // no line, or one that goes on (or branches) here
    std::uint32_t previous = v, current = links.ends[v][0];
    for (int step = 1; step < kDirectionEdges && links.degree[current] == 2; ++step) {
      const std::uint32_t next =
          links.ends[current][0] == previous ? links.ends[current][1] : links.ends[current][0];
      previous = current;
      current = next;
    }
    const Eigen::Vector3f d = positions[v] - positions[current];
    if (d.squaredNorm() > 0.0f) entries.push_back({i, d.normalized()});
  }
  return entries;
}

// Whether entries a and b are the two ends of one straight line through the hole: opposite
// directions, each pointing at the other (within about 11 degrees).
bool one_line_through(const HoleEntry& a, const HoleEntry& b, const Eigen::Vector3f& pa,
                      const Eigen::Vector3f& pb) {
  constexpr float kCos = 0.98f;
  const Eigen::Vector3f ab = pb - pa;
  const float length = ab.norm();
  return length > 0.0f && a.direction.dot(b.direction) < -kCos &&
         a.direction.dot(ab) > kCos * length && -b.direction.dot(ab) > kCos * length;
}

// The point nearest (least squares) to the lines of `entries`, ahead of each of them (where
// lines meeting at a lost corner meet); false when they are nearly parallel or meet behind one.
bool lost_corner(const std::vector<std::uint32_t>& loop,
                 const std::vector<Eigen::Vector3f>& positions,
                 const std::vector<HoleEntry>& entries, Eigen::Vector3f& corner) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const HoleEntry& e : entries) {
    const Eigen::Vector3d d = e.direction.cast<double>();
    const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - d * d.transpose();
    a += across;
    b += across * positions[loop[e.at]].cast<double>();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(a);
  if (!(eigen.eigenvalues()[0] > 0.05 * static_cast<double>(entries.size()))) return false;
  corner = a.ldlt().solve(b).cast<float>();
  double perimeter = 0.0;
  for (std::size_t i = 0; i < loop.size(); ++i)
    perimeter +=
        static_cast<double>((positions[loop[(i + 1) % loop.size()]] - positions[loop[i]]).norm());
  for (const HoleEntry& e : entries) {
    const Eigen::Vector3f to = corner - positions[loop[e.at]];
    // Ahead along the line (within about 26 degrees) and no farther than the hole is long.
    if (!corner.allFinite() || e.direction.dot(to) < 0.9f * to.norm() ||
        static_cast<double>(to.norm()) > 0.5 * perimeter)
      return false;
  }
  return true;
}

// The polygons that continue the feature lines across a hole (see fill_holes), in mesh vertex
// indices (kAddedVertex: the lost corner); empty when the lines give no such plan.
std::vector<std::vector<std::uint32_t>> feature_polygons(
    const std::vector<std::uint32_t>& loop, const std::vector<Eigen::Vector3f>& positions,
    const std::vector<HoleEntry>& entries, const std::vector<std::uint64_t>& edges,
    Eigen::Vector3f& corner) {
  if (entries.size() < 2) return {};
  const std::size_t n = loop.size();
  std::vector<std::size_t> partner(entries.size(), SIZE_MAX);
  for (std::size_t i = 0; i < entries.size(); ++i)
    for (std::size_t j = i + 1; j < entries.size() && partner[i] == SIZE_MAX; ++j)
      if (partner[j] == SIZE_MAX &&
          one_line_through(entries[i], entries[j], positions[loop[entries[i].at]],
                           positions[loop[entries[j].at]]))
        partner[i] = j, partner[j] = i;
  const auto paired = static_cast<std::size_t>(
      std::count_if(partner.begin(), partner.end(), [](std::size_t p) { return p != SIZE_MAX; }));
  std::vector<std::vector<std::uint32_t>> polygons;
  if (paired == entries.size()) {  // lines through the hole: split it along each
    polygons.push_back(loop);
    for (std::size_t i = 0; i < entries.size(); ++i) {
      if (partner[i] < i) continue;
      const std::uint32_t a = loop[entries[i].at], b = loop[entries[partner[i]].at];
      if (std::binary_search(edges.begin(), edges.end(), undirected_edge_key(a, b))) return {};
      bool split = false;
      for (std::size_t p = 0; p < polygons.size() && !split; ++p) {
        const std::vector<std::uint32_t>& poly = polygons[p];
        const auto ia =
            static_cast<std::size_t>(std::find(poly.begin(), poly.end(), a) - poly.begin());
        const auto ib =
            static_cast<std::size_t>(std::find(poly.begin(), poly.end(), b) - poly.begin());
        if (ia == poly.size() || ib == poly.size()) continue;
        const std::size_t lo = std::min(ia, ib), hi = std::max(ia, ib);
        if (hi == lo + 1 || (lo == 0 && hi == poly.size() - 1)) {  // already an edge of it
          split = true;
          continue;
        }
        std::vector<std::uint32_t> first(poly.begin() + static_cast<std::ptrdiff_t>(lo),
                                         poly.begin() + static_cast<std::ptrdiff_t>(hi) + 1);
        std::vector<std::uint32_t> second(poly.begin() + static_cast<std::ptrdiff_t>(hi),
                                          poly.end());
        second.insert(second.end(), poly.begin(),
                      poly.begin() + static_cast<std::ptrdiff_t>(lo) + 1);
        polygons[p] = std::move(first);
        polygons.push_back(std::move(second));
        split = true;
      }
      if (!split) return {};  // crossing lines
    }
    return polygons;
  }
  if (paired > 0 || !lost_corner(loop, positions, entries, corner)) return {};
  for (std::size_t k = 0; k < entries.size(); ++k) {  // one polygon per arc and the corner
    const std::size_t from = entries[k].at;
    const std::size_t to = entries[(k + 1) % entries.size()].at + (k + 1 == entries.size() ? n : 0);
    std::vector<std::uint32_t>& poly = polygons.emplace_back();
    for (std::size_t i = from; i <= to; ++i) poly.push_back(loop[i % n]);
    poly.push_back(kAddedVertex);
  }
  return polygons;
}

// A hole's triangles (kAddedVertex standing for `corner` where it needs one): along the
// feature lines ending on it when they give a plan that triangulates, else the plain fill.
struct HoleFill {
  std::vector<Triangle> triangles;  ///< empty: every triangulation repeats an edge
  bool along_features = false;
  bool corner = false;
  Eigen::Vector3f corner_point = Eigen::Vector3f::Zero();
};

HoleFill fill_hole(const std::vector<std::uint32_t>& loop,
                   const std::vector<Eigen::Vector3f>& positions,
                   const std::vector<std::uint64_t>& edges, const HoleFeatureLinks* links) {
  HoleFill fill;
  if (links != nullptr) {
    const std::vector<HoleEntry> entries = hole_entries(loop, positions, *links);
    const std::vector<std::vector<std::uint32_t>> polygons =
        feature_polygons(loop, positions, entries, edges, fill.corner_point);
    // The mesh's edges and those of the parts already triangulated: two parts share vertices
    // (a split line's ends, the lost corner), so a diagonal one part drew is not drawn again
    // by the next (it would carry four faces).
    std::vector<std::uint64_t> taken = edges;
    for (const std::vector<std::uint32_t>& poly : polygons) {
      std::vector<Eigen::Vector3f> points;
      points.reserve(poly.size());
      for (std::uint32_t v : poly)
        points.push_back(v == kAddedVertex ? fill.corner_point : positions[v]);
      const std::vector<Triangle> part = triangulate_loop(poly, points, taken);
      if (part.empty()) {
        fill.triangles.clear();
        break;
      }
      for (const Triangle& t : part)
        for (int k = 0; k < 3; ++k) taken.push_back(undirected_edge_key(t[k], t[(k + 1) % 3]));
      std::sort(taken.begin(), taken.end());
      taken.erase(std::unique(taken.begin(), taken.end()), taken.end());
      fill.corner |= poly.back() == kAddedVertex;
      fill.triangles.insert(fill.triangles.end(), part.begin(), part.end());
    }
    fill.along_features = !fill.triangles.empty();
    if (fill.along_features) return fill;
    fill.corner = false;
  }
  fill.triangles = triangulate_loop(loop, loop_points(loop, positions), edges);
  return fill;
}

// Appends a vertex at `point` with the loop's mean normal and colour, when the mesh has them.
void append_vertex(TriangleMesh& mesh, const Eigen::Vector3f& point,
                   const std::vector<std::uint32_t>& loop) {
  Eigen::Vector3f normal = Eigen::Vector3f::Zero(), colour = Eigen::Vector3f::Zero();
  for (std::uint32_t v : loop) {
    if (!mesh.normals.empty()) normal += mesh.normals[v];
    if (!mesh.colors.empty())
      colour += Eigen::Vector3f(mesh.colors[v].r, mesh.colors[v].g, mesh.colors[v].b);
  }
  mesh.vertices.push_back(point);
  if (!mesh.normals.empty()) mesh.normals.push_back(normal.normalized());
  if (!mesh.colors.empty()) {
    const Eigen::Vector3f rgb = colour / static_cast<float>(loop.size());
    mesh.colors.push_back(Rgb8{static_cast<std::uint8_t>(std::lround(rgb.x())),
                               static_cast<std::uint8_t>(std::lround(rgb.y())),
                               static_cast<std::uint8_t>(std::lround(rgb.z()))});
  }
}

// The loop closed by a fan around a vertex added at its centroid: its edges are all new, so it
// is always possible. Each triangle runs its loop edge in the loop's direction, against the
// face beyond that edge, so the fan is oriented like the faces around the hole.
std::vector<Triangle> fan_from_centre(const std::vector<std::uint32_t>& loop, TriangleMesh& mesh) {
  Eigen::Vector3f centre = Eigen::Vector3f::Zero();
  for (std::uint32_t v : loop) centre += mesh.vertices[v];
  const auto c = static_cast<std::uint32_t>(mesh.vertices.size());
  append_vertex(mesh, centre / static_cast<float>(loop.size()), loop);
  std::vector<Triangle> fan;
  for (std::size_t k = 0; k < loop.size(); ++k)
    fan.push_back(Triangle{loop[k], c, loop[(k + 1) % loop.size()]});
  return fan;
}

// Area of each component (indexed by its label, as vertex_component_labels() gives per vertex),
// m^2.
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
                        HoleFillingReport* report, const std::vector<std::uint8_t>* held,
                        const HoleFeatures& known) {
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
    const std::vector<std::uint32_t> component =
        vertex_component_labels(mesh.triangles, mesh.vertices.size());
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

  const auto through_held = [held](const std::vector<std::uint32_t>& loop) {
    return held != nullptr && std::any_of(loop.begin(), loop.end(), [held](std::uint32_t v) {
             return v < held->size() && (*held)[v] != 0;
           });
  };
  std::vector<const std::vector<std::uint32_t>*> holes;
  for (std::size_t l = 0; l < loops.size(); ++l) {
    if (outer[l])
      ++r.outer_borders;
    else if (through_held(loops[l]))
      ++r.held_open;
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
  std::optional<HoleFeatureLinks> links;
  if (!holes.empty() && config.feature_angle_deg < 180.0f) {
    if (known.graph != nullptr && known.graph->vertex_kind.size() == mesh.vertices.size()) {
      if (!known.graph->edges.empty())
        links = hole_feature_links(mesh.vertices.size(), *known.graph);
    } else {
      // Only the lines that reach a hole's border matter: found from its vertices, not from a
      // pass over every face (most of a depth frame's clean-up time when it was).
      std::vector<std::uint32_t> seeds;
      for (const auto* hole : holes) seeds.insert(seeds.end(), hole->begin(), hole->end());
      const MeshFeatures features = detect_features_reaching(
          mesh, around, seeds, config.feature_angle_deg, config.feature_min_length, known.marks);
      if (!features.edges.empty()) links = hole_feature_links(mesh.vertices.size(), features);
    }
  }
  std::vector<HoleFill> fills(holes.size());
  tbb::parallel_for(std::size_t{0}, holes.size(), [&](std::size_t i) {
    fills[i] = fill_hole(*holes[i], mesh.vertices, edges_within(mesh, around, *holes[i], in_hole),
                         links ? &*links : nullptr);
  });

  TriangleMesh out = mesh;
  for (std::size_t i = 0; i < fills.size(); ++i) {
    std::vector<Triangle>& fill = fills[i].triangles;
    if (fill.empty()) {  // every triangulation repeats an edge: fan from a new centre
      fill = fan_from_centre(*holes[i], out);
      ++r.centre_vertices;
    } else if (fills[i].corner) {  // the lost corner becomes a vertex
      const auto corner = static_cast<std::uint32_t>(out.vertices.size());
      append_vertex(out, fills[i].corner_point, *holes[i]);
      for (Triangle& t : fill)
        for (std::uint32_t& v : t) v = v == kAddedVertex ? corner : v;
    }
    ++r.filled;
    r.along_features += fills[i].along_features ? 1 : 0;
    r.added_triangles += fill.size();
    out.triangles.insert(out.triangles.end(), fill.begin(), fill.end());
  }
  if (report != nullptr) *report = r;
  return out;
}

}  // namespace meshflow
