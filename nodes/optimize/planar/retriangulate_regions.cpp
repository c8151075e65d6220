#include "nodes/optimize/planar/retriangulate_regions.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Constrained_triangulation_face_base_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "runtime/half_edge_mesh.h"

namespace meshflow {
namespace {

// CGAL's constrained Delaunay triangulation: vertices carry their mesh index (none for the
// points where crossing constraints are split), faces their nesting depth (odd = inside).
struct MeshVertex {
  std::uint32_t index = HalfEdgeMesh::kNone;
};
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<MeshVertex, Kernel>;
using FaceBase = CGAL::Constrained_triangulation_face_base_2<
    Kernel, CGAL::Triangulation_face_base_with_info_2<int, Kernel>>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<
    Kernel, CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>, CGAL::Exact_predicates_tag>;

using Loop = std::vector<std::uint32_t>;  // vertex indices, the region on the left

// Contour half-edges of region r as (from vertex, half-edge), sorted.
std::vector<std::pair<std::uint32_t, std::uint32_t>> contour_half_edges(
    const HalfEdgeMesh& h, const std::vector<std::int32_t>& region_of_face,
    const std::vector<std::uint32_t>& faces, std::int32_t r) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> leaving;
  for (std::uint32_t f : faces)
    for (std::uint32_t e = 3 * f; e < 3 * f + 3; ++e) {
      const std::uint32_t t = h.twin(e);
      if (t == HalfEdgeMesh::kNone || region_of_face[HalfEdgeMesh::face(t)] != r)
        leaving.emplace_back(h.from(e), e);
    }
  std::sort(leaving.begin(), leaving.end());
  return leaving;
}

// The contour loops of region r. Where the region touches itself at a vertex (two contour
// edges leave it), the region's faces around that vertex are given up (set to -1 in
// region_of_face, removed from `faces`) until no such vertex is left, so every contour vertex
// is on exactly one loop. Writes only entries of region r.
void region_contours(const HalfEdgeMesh& h, std::vector<std::int32_t>& region_of_face,
                     std::vector<std::uint32_t>& faces, std::int32_t r, std::vector<Loop>& loops) {
  loops.clear();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> leaving;
  for (;;) {
    leaving = contour_half_edges(h, region_of_face, faces, r);
    bool pinched = false;
    for (std::size_t i = 1; i < leaving.size(); ++i) {
      if (leaving[i].first != leaving[i - 1].first) continue;
      pinched = true;
      for (std::uint32_t e : h.ring(leaving[i].first))
        if (region_of_face[HalfEdgeMesh::face(e)] == r) region_of_face[HalfEdgeMesh::face(e)] = -1;
    }
    if (!pinched) break;
    faces.erase(std::remove_if(faces.begin(), faces.end(),
                               [&](std::uint32_t f) { return region_of_face[f] != r; }),
                faces.end());
  }
  auto next = [&](std::uint32_t e) {
    const auto it =
        std::lower_bound(leaving.begin(), leaving.end(), std::make_pair(h.to(e), std::uint32_t{0}));
    return it - leaving.begin();
  };
  std::vector<std::uint8_t> seen(leaving.size(), 0);
  for (std::size_t start = 0; start < leaving.size(); ++start) {
    if (seen[start]) continue;
    Loop loop;
    for (std::size_t i = start; !seen[i]; i = static_cast<std::size_t>(next(leaving[i].second))) {
      seen[i] = 1;
      loop.push_back(leaving[i].first);
    }
    loops.push_back(std::move(loop));
  }
}

double point_segment_distance(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                              const Eigen::Vector3f& b) {
  const Eigen::Vector3d d = (b - a).cast<double>(), w = (p - a).cast<double>();
  const double length2 = d.squaredNorm();
  const double s = length2 > 0.0 ? std::clamp(w.dot(d) / length2, 0.0, 1.0) : 0.0;
  return (w - s * d).norm();
}

// Douglas-Peucker over chain[0..n-1] (both ends kept): clears keep[] of the dropped vertices and
// returns the largest distance of a dropped vertex from its simplified segment.
double simplify_chain(const std::vector<std::uint32_t>& chain,
                      const std::vector<Eigen::Vector3f>& p, double tolerance,
                      std::vector<std::uint8_t>& keep) {
  double deviation = 0.0;
  std::vector<std::pair<std::size_t, std::size_t>> pending{{0, chain.size() - 1}};
  while (!pending.empty()) {
    const auto [i, j] = pending.back();
    pending.pop_back();
    if (j < i + 2) continue;
    double farthest = -1.0;
    std::size_t at = i + 1;
    for (std::size_t k = i + 1; k < j; ++k) {
      const double d = point_segment_distance(p[chain[k]], p[chain[i]], p[chain[j]]);
      if (d > farthest) {
        farthest = d;
        at = k;
      }
    }
    if (farthest > tolerance) {
      pending.emplace_back(i, at);
      pending.emplace_back(at, j);
    } else {
      for (std::size_t k = i + 1; k < j; ++k) keep[chain[k]] = 0;
      deviation = std::max(deviation, farthest);
    }
  }
  return deviation;
}

// How a region is handled; a region that cannot be triangulated moves one state down.
enum RegionState : std::uint8_t { kSimplified = 0, kFullContour = 1, kKept = 2 };

// Which contour vertices may go: those whose faces all lie in regions with simplified
// contours, in one region on the mesh border or in two regions inside. 1 = fixed.
// Feature corners (`pinned`, empty: none) are fixed too.
std::vector<std::uint8_t> fixed_vertices(const HalfEdgeMesh& h,
                                         const std::vector<std::int32_t>& region_of_face,
                                         const std::vector<std::uint8_t>& state,
                                         const std::vector<std::uint8_t>& pinned) {
  std::vector<std::uint8_t> fixed(h.vertex_count(), 1);
  tbb::parallel_for(std::size_t{0}, h.vertex_count(), [&](std::size_t i) {
    const auto v = static_cast<std::uint32_t>(i);
    if (h.outgoing(v) == HalfEdgeMesh::kNone || (!pinned.empty() && pinned[v])) return;
    std::int32_t first = -1, second = -1;
    bool movable = true;
    for (std::uint32_t e : h.ring(v)) {
      const std::int32_t r = region_of_face[HalfEdgeMesh::face(e)];
      if (r < 0 || state[static_cast<std::size_t>(r)] != kSimplified) {
        movable = false;
        break;
      }
      if (first < 0 || r == first) {
        first = r;
      } else if (second < 0 || r == second) {
        second = r;
      } else {
        movable = false;  // three regions meet
        break;
      }
    }
    const bool border = h.is_border_vertex(v);
    if (movable && second >= 0 && border) movable = false;
    fixed[i] = movable ? 0 : 1;
  });
  return fixed;
}

// Splits every loop at fixed vertices (a loop without any gets two anchors: its smallest
// vertex index and the vertex farthest from it) and simplifies each chain in a direction that
// does not depend on which side walks it, so both regions along a chain drop the same
// vertices. Returns the largest deviation.
double simplify_contours(const std::vector<Loop>& loops, const std::vector<Eigen::Vector3f>& p,
                         const std::vector<std::uint8_t>& fixed, double tolerance,
                         std::vector<std::uint8_t>& keep) {
  double deviation = 0.0;
  for (const Loop& loop : loops) {
    const std::size_t n = loop.size();
    std::vector<std::size_t> anchors;
    for (std::size_t i = 0; i < n; ++i)
      if (fixed[loop[i]]) anchors.push_back(i);
    if (anchors.empty()) {
      const std::size_t a =
          static_cast<std::size_t>(std::min_element(loop.begin(), loop.end()) - loop.begin());
      std::size_t b = a;
      float far = -1.0f;
      for (std::size_t i = 0; i < n; ++i) {
        const float d = (p[loop[i]] - p[loop[a]]).squaredNorm();
        if (d > far || (d == far && loop[i] < loop[b])) {
          far = d;
          b = i;
        }
      }
      anchors = {std::min(a, b), std::max(a, b)};
    }
    for (std::size_t k = 0; k < anchors.size(); ++k) {
      const std::size_t begin = anchors[k];
      const std::size_t end = k + 1 < anchors.size() ? anchors[k + 1] : anchors[0] + n;
      std::vector<std::uint32_t> chain;
      for (std::size_t i = begin; i <= end; ++i) chain.push_back(loop[i % n]);
      const bool reverse = chain.front() != chain.back()
                               ? chain.front() > chain.back()
                               : chain.size() > 2 && chain[1] > chain[chain.size() - 2];
      if (reverse) std::reverse(chain.begin(), chain.end());
      deviation = std::max(deviation, simplify_chain(chain, p, tolerance, keep));
    }
  }
  return deviation;
}

// Gives up region r's faces around each of `vertices` (they leave the region).
void give_up_faces(const HalfEdgeMesh& h, const std::vector<std::uint32_t>& vertices,
                   std::int32_t r, std::vector<std::int32_t>& region_of_face,
                   std::vector<std::uint32_t>& faces) {
  for (std::uint32_t v : vertices)
    for (std::uint32_t e : h.ring(v))
      if (region_of_face[HalfEdgeMesh::face(e)] == r) region_of_face[HalfEdgeMesh::face(e)] = -1;
  faces.erase(std::remove_if(faces.begin(), faces.end(),
                             [&](std::uint32_t f) { return region_of_face[f] != r; }),
              faces.end());
}

struct RegionTriangulation {
  std::vector<Triangle> triangles;  ///< empty: failed
  /// On failure, the mesh vertices at the fault when it is local (two vertices on one point
  /// of the plane, the ends of crossing edges); empty otherwise.
  std::vector<std::uint32_t> faulty;
};

// What inserting a region's loops into the triangulation found.
struct InsertedLoops {
  std::vector<std::vector<Cdt::Vertex_handle>> handles;  ///< per loop, its kept vertices
  std::size_t vertices = 0, outer_loops = 0;
  double signed_area = 0.0;  ///< outlines counter-clockwise (positive), holes clockwise
  bool too_short = false;    ///< a loop kept fewer than three vertices
};

// Inserts the kept vertices of every loop, projected onto the plane (axis_u, axis_v), and the
// loop's edges as constraints. Two vertices on one point of the plane are a fault: every such
// pair goes to `faulty` (and no constraint is inserted after the first).
InsertedLoops insert_loops(Cdt& cdt, const std::vector<Loop>& loops,
                           const std::vector<std::uint8_t>& keep,
                           const std::vector<Eigen::Vector3f>& p, const Eigen::Vector3f& normal,
                           std::vector<std::uint32_t>& faulty) {
  const Eigen::Vector3f axis_u = normal.unitOrthogonal(), axis_v = normal.cross(axis_u);
  auto plane_point = [&](std::uint32_t v) {
    return Kernel::Point_2(axis_u.dot(p[v]), axis_v.dot(p[v]));
  };
  InsertedLoops in;
  for (const Loop& loop : loops) {
    double area = 0.0;
    std::vector<Cdt::Vertex_handle>& handles = in.handles.emplace_back();
    for (std::uint32_t v : loop) {
      if (!keep[v]) continue;
      Cdt::Vertex_handle handle = cdt.insert(plane_point(v));
      if (cdt.number_of_vertices() == in.vertices) {  // on the point of another vertex
        faulty.insert(faulty.end(), {handle->info().index, v});
        continue;
      }
      ++in.vertices;
      handle->info().index = v;
      handles.push_back(handle);
    }
    if (!faulty.empty()) continue;  // collecting every coincidence, then failing
    if (handles.size() < 3) {
      in.too_short = true;
      return in;
    }
    for (std::size_t i = 0; i < handles.size(); ++i) {
      const Cdt::Vertex_handle a = handles[i], b = handles[(i + 1) % handles.size()];
      cdt.insert_constraint(a, b);
      area += 0.5 * (a->point().x() * b->point().y() - b->point().x() * a->point().y());
    }
    in.signed_area += area;
    in.outer_loops += area > 0.0 ? 1 : 0;  // counter-clockwise: an outline, not a hole
  }
  return in;
}

// Crossing constraints were split at new points: the mesh vertices next to them.
void blame_crossings(const Cdt& cdt, std::vector<std::uint32_t>& faulty) {
  for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v) {
    if (v->info().index != HalfEdgeMesh::kNone) continue;
    auto around = cdt.incident_vertices(v), first = around;
    do {
      if (!cdt.is_infinite(around) && around->info().index != HalfEdgeMesh::kNone)
        faulty.push_back(around->info().index);
    } while (++around != first);
  }
}

// Each face's nesting depth (face info) by flooding from the outside, one more across every
// constrained edge: odd depths lie inside the polygon.
void mark_nesting_depth(Cdt& cdt) {
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info() = -1;
  std::vector<std::pair<Cdt::Face_handle, int>> seeds{{cdt.infinite_face(), 0}};
  while (!seeds.empty()) {
    const auto [seed, depth] = seeds.back();
    seeds.pop_back();
    if (seed->info() != -1) continue;
    seed->info() = depth;
    std::vector<Cdt::Face_handle> stack{seed};
    while (!stack.empty()) {
      const Cdt::Face_handle f = stack.back();
      stack.pop_back();
      for (int i = 0; i < 3; ++i) {
        const Cdt::Face_handle n = f->neighbor(i);
        if (n->info() != -1) continue;
        if (cdt.is_constrained(Cdt::Edge(f, i))) {
          seeds.emplace_back(n, depth + 1);
        } else {
          n->info() = depth;
          stack.push_back(n);
        }
      }
    }
  }
}

// The faces inside the polygon (odd depth) as mesh triangles; returns their area.
double inside_triangles(const Cdt& cdt, std::vector<Triangle>& triangles) {
  double area = 0.0;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    if (f->info() % 2 == 0) continue;
    triangles.push_back(Triangle{f->vertex(0)->info().index, f->vertex(1)->info().index,
                                 f->vertex(2)->info().index});
    area +=
        std::abs(CGAL::area(f->vertex(0)->point(), f->vertex(1)->point(), f->vertex(2)->point()));
  }
  return area;
}

// Why a triangulation came out unfaithful: a loop with the outside on its left is folded over
// in the plane (a sliver of the region turned over, as cutting creases can leave): its vertices
// are the fault. A loop that turns back on itself (a hairpin: the edges before and after a
// vertex overlap) bounds no area there but adds triangles: its vertex is the fault.
void blame_folds_and_hairpins(const Cdt& cdt, const InsertedLoops& in,
                              std::vector<std::uint32_t>& faulty) {
  for (const std::vector<Cdt::Vertex_handle>& handles : in.handles) {
    Cdt::Face_handle face;
    int i = 0;
    if (!cdt.is_edge(handles[0], handles[1], face, i)) continue;
    if (face->vertex(Cdt::ccw(i)) != handles[0]) face = face->neighbor(i);  // the left side
    if (face->info() % 2 != 0) continue;
    for (const Cdt::Vertex_handle& v : handles) faulty.push_back(v->info().index);
  }
  for (const std::vector<Cdt::Vertex_handle>& handles : in.handles) {
    const std::size_t n = handles.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Kernel::Point_2& a = handles[(i + n - 1) % n]->point();
      const Kernel::Point_2& b = handles[i]->point();
      const Kernel::Point_2& c = handles[(i + 1) % n]->point();
      if (CGAL::orientation(a, b, c) == CGAL::COLLINEAR && CGAL::angle(a, b, c) == CGAL::ACUTE)
        faulty.push_back(handles[i]->info().index);
    }
  }
}

// Triangulates the polygon with holes formed by the kept vertices of `loops` in the region's
// plane. Fails when it cannot be done faithfully: fewer than three vertices in a loop, two
// vertices on one point of the plane, crossing edges, or a folded projection.
RegionTriangulation triangulate_region(const std::vector<Loop>& loops,
                                       const std::vector<std::uint8_t>& keep,
                                       const std::vector<Eigen::Vector3f>& p,
                                       const Eigen::Vector3f& normal) {
  RegionTriangulation out;
  Cdt cdt;
  const InsertedLoops in = insert_loops(cdt, loops, keep, p, normal, out.faulty);
  if (in.too_short || !out.faulty.empty()) return out;
  if (cdt.number_of_vertices() != in.vertices) {
    blame_crossings(cdt, out.faulty);
    return out;
  }
  mark_nesting_depth(cdt);
  const double inside_area = inside_triangles(cdt, out.triangles);
  // Faithful polygons with holes: n + 2 (holes) - 2 (polygons) triangles, and the loops' signed
  // areas (outlines counter-clockwise, holes clockwise) add up to the area triangulated.
  const std::size_t holes = loops.size() - in.outer_loops;
  if (in.vertices + 2 * holes < 2 * in.outer_loops + 1) return {};  // (faulty stays empty)
  const std::size_t expected = in.vertices + 2 * holes - 2 * in.outer_loops;
  if (out.triangles.size() != expected ||
      std::abs(in.signed_area - inside_area) > 1e-4 * inside_area) {
    out.triangles.clear();
    blame_folds_and_hairpins(cdt, in, out.faulty);
  }
  return out;
}

// An edge that two new triangulations create both, or one creates while the faces that stay
// have it too, would join more than two faces. Each region whose triangulation has such an
// edge fails, with the edge's ends as its fault (it gives up its faces there and tries again).
void fail_at_shared_new_edges(const TriangleMesh& mesh,
                              const std::vector<std::int32_t>& region_of_face,
                              const std::vector<std::uint8_t>& state,
                              std::vector<RegionTriangulation>& results) {
  auto replaced = [&](std::int32_t region) {
    return region >= 0 && state[static_cast<std::size_t>(region)] != kKept &&
           !results[static_cast<std::size_t>(region)].triangles.empty();
  };
  std::vector<std::uint64_t> keys;
  auto add = [&](const Triangle& t) {
    for (int k = 0; k < 3; ++k) keys.push_back(undirected_edge_key(t[k], t[(k + 1) % 3]));
  };
  for (std::uint32_t f = 0; f < mesh.triangles.size(); ++f)
    if (!replaced(region_of_face[f])) add(mesh.triangles[f]);
  for (const RegionTriangulation& result : results)
    for (const Triangle& t : result.triangles) add(t);
  std::sort(keys.begin(), keys.end());
  std::vector<std::uint64_t> crowded;
  for (std::size_t i = 2; i < keys.size(); ++i)
    if (keys[i] == keys[i - 2] && (crowded.empty() || crowded.back() != keys[i]))
      crowded.push_back(keys[i]);
  if (crowded.empty()) return;
  for (std::size_t i = 0; i < results.size(); ++i) {
    if (!replaced(static_cast<std::int32_t>(i))) continue;
    std::vector<std::uint32_t> faulty;
    for (const Triangle& t : results[i].triangles)
      for (int k = 0; k < 3; ++k)
        if (std::binary_search(crowded.begin(), crowded.end(),
                               undirected_edge_key(t[k], t[(k + 1) % 3])))
          faulty.insert(faulty.end(), {t[k], t[(k + 1) % 3]});
    if (faulty.empty()) continue;
    results[i].triangles.clear();
    results[i].faulty = std::move(faulty);
  }
}

// Every region's faces, contours, state and (once triangulated) result; region_of_face as the
// regions give up faces.
struct RegionWork {
  std::vector<std::int32_t> region_of_face;
  std::vector<std::vector<std::uint32_t>> faces;
  std::vector<std::vector<Loop>> contours;
  std::vector<std::uint8_t> state;  ///< RegionState
  std::vector<RegionTriangulation> results;
  std::vector<std::uint8_t> keep;  ///< per vertex: kept by the contour simplification
};

// Every region's contours, region by region (serial: giving up faces at pinches edits
// region_of_face); a region without faces is kept.
// A contour vertex off its region's plane would become a corner of the region's new, large
// triangles and tilt them (an extraction's stray vertex beside a sharp edge, up to a voxel off:
// its faces join no region). The region gives up its faces around such vertices, a ring per
// round, so its contour runs on the plane and the stray vertex keeps its own small faces.
// Off: farther than twice the region's 95th-percentile deviation, and than `least` metres.
void give_up_off_plane_contour(const HalfEdgeMesh& h, const PlanarRegion& region, float least,
                               std::int32_t id, RegionWork& work) {
  constexpr int kRounds = 4;
  const float limit = std::max(2.0f * region.deviation, least);
  const std::size_t r = static_cast<std::size_t>(id);
  for (int round = 0; round < kRounds && !work.faces[r].empty(); ++round) {
    std::vector<std::uint32_t> off;
    for (const Loop& loop : work.contours[r])
      for (std::uint32_t v : loop)
        if (std::abs(region.normal.dot(h.position(v)) - region.offset) > limit) off.push_back(v);
    if (off.empty()) return;
    give_up_faces(h, off, id, work.region_of_face, work.faces[r]);
    region_contours(h, work.region_of_face, work.faces[r], id, work.contours[r]);
  }
}

// `least`: see give_up_off_plane_contour.
RegionWork start_regions(const HalfEdgeMesh& h, const PlanarSegmentation& segmentation,
                         float least) {
  const std::size_t regions = segmentation.regions.size();
  RegionWork work;
  work.region_of_face = segmentation.region_of_face;
  work.faces.resize(regions);
  work.contours.resize(regions);
  work.state.assign(regions, kSimplified);
  work.results.resize(regions);
  for (std::size_t i = 0; i < regions; ++i) {
    const auto id = static_cast<std::int32_t>(i);
    work.faces[i] = segmentation.regions[i].faces;
    region_contours(h, work.region_of_face, work.faces[i], id, work.contours[i]);
    give_up_off_plane_contour(h, segmentation.regions[i], least, id, work);
    if (work.faces[i].empty()) work.state[i] = kKept;
  }
  return work;
}

// A region that fails at a known place (two vertices on one point of its plane, crossing
// edges) gives up its faces there and is tried again, a bounded number of rounds; otherwise
// (or then) it is tried again with its full contours, which also fixes them for its
// neighbours, and one that still fails is kept as it was. Repeat until nothing fails.
void triangulate_with_repairs(const TriangleMesh& mesh, const HalfEdgeMesh& h,
                              const PlanarSegmentation& segmentation,
                              const RetriangulationConfig& config,
                              const std::vector<std::uint8_t>& pinned, RegionWork& work,
                              RetriangulationReport& r) {
  constexpr int kRepairRounds = 8;
  const std::size_t regions = work.state.size();
  for (int round = 0, changed = 1; changed; ++round) {
    const std::vector<std::uint8_t> fixed =
        fixed_vertices(h, work.region_of_face, work.state, pinned);
    work.keep.assign(mesh.vertices.size(), 1);
    r.max_contour_deviation = 0.0;
    for (std::size_t i = 0; i < regions; ++i)
      if (work.state[i] == kSimplified)
        r.max_contour_deviation =
            std::max(r.max_contour_deviation,
                     simplify_contours(work.contours[i], mesh.vertices, fixed,
                                       static_cast<double>(config.contour_tolerance), work.keep));
    tbb::parallel_for(std::size_t{0}, regions, [&](std::size_t i) {
      work.results[i] = work.state[i] != kKept
                            ? triangulate_region(work.contours[i], work.keep, mesh.vertices,
                                                 segmentation.regions[i].normal)
                            : RegionTriangulation{};
    });
    fail_at_shared_new_edges(mesh, work.region_of_face, work.state, work.results);
    changed = 0;
    for (std::size_t i = 0; i < regions; ++i) {
      if (work.state[i] == kKept || !work.results[i].triangles.empty()) continue;
      changed = 1;
      std::vector<std::uint32_t>& faulty = work.results[i].faulty;
      faulty.erase(std::remove(faulty.begin(), faulty.end(), HalfEdgeMesh::kNone), faulty.end());
      if (!faulty.empty() && round < kRepairRounds) {
        const auto id = static_cast<std::int32_t>(i);
        give_up_faces(h, faulty, id, work.region_of_face, work.faces[i]);
        region_contours(h, work.region_of_face, work.faces[i], id, work.contours[i]);
        if (work.faces[i].empty()) work.state[i] = kKept;
      } else {
        ++work.state[i];
      }
    }
  }
}

// The mesh's faces outside the retriangulated regions, then each such region's new triangles,
// vertices compacted; counts go to the report.
TriangleMesh replace_regions(const TriangleMesh& mesh, const RegionWork& work,
                             RetriangulationReport& r) {
  const std::size_t regions = work.state.size();
  std::vector<Triangle> triangles;
  for (std::uint32_t f = 0; f < mesh.triangles.size(); ++f) {
    const std::int32_t region = work.region_of_face[f];
    if (region < 0 || work.state[static_cast<std::size_t>(region)] == kKept)
      triangles.push_back(mesh.triangles[f]);
    else
      ++r.removed_faces;
  }
  for (std::size_t i = 0; i < regions; ++i) {
    if (work.state[i] == kKept) {
      ++r.kept;
      continue;
    }
    const std::vector<Triangle>& fill = work.results[i].triangles;
    ++r.retriangulated;
    r.added_faces += fill.size();
    for (const Loop& loop : work.contours[i]) {
      r.contour_vertices += loop.size();
      for (std::uint32_t v : loop) r.dropped_contour_vertices += work.keep[v] ? 0 : 1;
    }
    triangles.insert(triangles.end(), fill.begin(), fill.end());
  }
  return compact_vertices(mesh, triangles);
}

}  // namespace

TriangleMesh retriangulate_regions(const TriangleMesh& mesh, const PlanarSegmentation& segmentation,
                                   const RetriangulationConfig& config,
                                   RetriangulationReport* report, const MeshFeatures* features) {
  RetriangulationReport r;
  r.regions = segmentation.regions.size();
  const HalfEdgeMesh h(mesh);
  // A contour vertex may lie off its plane by a twentieth of the contour tolerance at least, or
  // by the segmentation's tolerance where that is smaller (a smooth mesh's exact planes: a
  // vertex off them by a twentieth would tilt the new triangles by that).
  float least = 0.05f * config.contour_tolerance;
  if (segmentation.tolerance > 0.0f) least = std::min(least, segmentation.tolerance);
  RegionWork work = start_regions(h, segmentation, least);
  std::vector<std::uint8_t> pinned;  // the feature graph's corners
  if (config.feature_angle_deg < 180.0f && !segmentation.regions.empty()) {
    MeshFeatures detected;
    if (features == nullptr) {
      detected = detect_features(mesh, config.feature_angle_deg, config.feature_min_length);
      features = &detected;
    }
    if (!features->edges.empty()) {
      pinned.resize(mesh.vertices.size());
      for (std::size_t v = 0; v < pinned.size(); ++v)
        pinned[v] = features->vertex_kind[v] == MeshFeatures::VertexKind::kCorner ? 1 : 0;
    }
  }
  triangulate_with_repairs(mesh, h, segmentation, config, pinned, work, r);
  TriangleMesh out = replace_regions(mesh, work, r);
  if (report != nullptr) *report = r;
  return out;
}

}  // namespace meshflow
