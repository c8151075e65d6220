#include "nodes/optimize/planar/planar_regions.h"

#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace meshflow {
namespace {

Eigen::Vector3f unit_face_normal(const HalfEdgeMesh& m, std::uint32_t f) {
  const Eigen::Vector3f& a = m.position(m.from(3 * f));
  const Eigen::Vector3f n =
      (m.position(m.from(3 * f + 1)) - a).cross(m.position(m.from(3 * f + 2)) - a);
  const float len = n.norm();
  return len > 0.0f ? Eigen::Vector3f(n / len) : Eigen::Vector3f::Zero();
}

// A mesh whose roughness is far below the plane tolerance asked for (see grow_planar_regions).
constexpr float kSmoothRoughnessFactor = 100.0f;
constexpr float kSmoothToleranceShare = 1e-3f;

// Rounds of the trimmed plane refit (fit_plane): each keeps the vertices within 3 robust
// deviations of the last plane; a plane tilted by a few far vertices comes back in 3-5.
constexpr int kPlaneTrimRounds = 8;

// The vertices of region r's faces, ascending.
std::vector<std::uint32_t> planar_region_vertices(const HalfEdgeMesh& m, const PlanarRegion& r) {
  std::vector<std::uint32_t> vertices;
  for (std::uint32_t f : r.faces)
    for (std::uint32_t k = 0; k < 3; ++k) vertices.push_back(m.from(3 * f + k));
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  return vertices;
}

// The 95th percentile of `distances` (reordered).
float planar_percentile95(std::vector<float>& distances) {
  if (distances.empty()) return 0.0f;
  const auto p95 = distances.begin() + static_cast<std::ptrdiff_t>(distances.size() * 95 / 100);
  std::nth_element(distances.begin(), p95, distances.end());
  return *p95;
}

// Least-squares plane through `points` (centroid and smallest principal axis), oriented like
// `side`: normal and offset.
void least_squares_plane(const HalfEdgeMesh& m, const std::vector<std::uint32_t>& points,
                         const Eigen::Vector3f& side, Eigen::Vector3f& normal, float& offset) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (std::uint32_t v : points) centroid += m.position(v).cast<double>();
  centroid /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::uint32_t v : points) {
    const Eigen::Vector3d d = m.position(v).cast<double>() - centroid;
    covariance += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  Eigen::Vector3d n = eigen.eigenvectors().col(0).normalized();
  if (n.cast<float>().dot(side) < 0.0f) n = -n;
  normal = n.cast<float>();
  offset = static_cast<float>(n.dot(centroid));
}

// The plane of region r: least squares through its vertices; with `trim` >= 0, refitted (up to
// kPlaneTrimRounds times) through those within max(trim, 3 robust deviations: 1.4826 x the
// median distance) of the last plane, so a few vertices off an exact plane (an extraction's
// stray spots) do not tilt it, while a noisy plane keeps everything within `trim`. Also sets
// r.deviation, the 95th percentile distance of all its vertices.
void fit_plane(const HalfEdgeMesh& m, PlanarRegion& r, const Eigen::Vector3f& side,
               float trim = -1.0f) {
  const std::vector<std::uint32_t> vertices = planar_region_vertices(m, r);
  least_squares_plane(m, vertices, side, r.normal, r.offset);
  std::vector<float> distances(vertices.size()), sorted;
  std::vector<std::uint32_t> trimmed;
  std::size_t kept = vertices.size();
  for (int round = 0;; ++round) {
    for (std::size_t i = 0; i < vertices.size(); ++i)
      distances[i] = std::abs(r.normal.dot(m.position(vertices[i])) - r.offset);
    if (trim < 0.0f || round == kPlaneTrimRounds) break;
    sorted = distances;
    const auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
    std::nth_element(sorted.begin(), middle, sorted.end());
    const float limit = std::max(trim, 3.0f * 1.4826f * *middle);
    trimmed.clear();
    for (std::size_t i = 0; i < vertices.size(); ++i)
      if (distances[i] <= limit) trimmed.push_back(vertices[i]);
    if (trimmed.size() == kept || trimmed.size() < 3) break;  // converged
    kept = trimmed.size();
    least_squares_plane(m, trimmed, side, r.normal, r.offset);
  }
  r.deviation = planar_percentile95(distances);
}

// A face is an inlier of region r when its three corners lie within `tolerance` of r's plane.
bool inlier(const HalfEdgeMesh& m, const PlanarRegion& r, std::uint32_t f, float tolerance) {
  for (std::uint32_t k = 0; k < 3; ++k)
    if (std::abs(r.normal.dot(m.position(m.from(3 * f + k))) - r.offset) > tolerance) return false;
  return true;
}

// Shrinks region r to the part its plane explains: up to three times, its inlier faces (within
// `tolerance`), their largest edge-connected part (the first in face order on ties), and the
// plane refitted to that. Returns false when fewer than `min_faces` remain or the plane's
// 95th-percentile deviation still exceeds the tolerance. A cluttered wall keeps its wall; a
// curved surface keeps at most a band within the tolerance of a plane, usually too small.
// The planes are fitted with fit_plane(..., trim).
bool keep_explained_part(const HalfEdgeMesh& m, PlanarRegion& r, const Eigen::Vector3f& side,
                         float tolerance, float trim, std::size_t min_faces) {
  fit_plane(m, r, side, trim);
  for (int round = 0; round < 3 && r.deviation > 0.0f; ++round) {
    std::vector<std::uint32_t> inliers;
    for (std::uint32_t f : r.faces)
      if (inlier(m, r, f, tolerance)) inliers.push_back(f);
    if (inliers.size() == r.faces.size()) break;
    // Largest edge-connected part of the inliers (faces sorted: binary search membership).
    std::vector<std::uint8_t> seen(inliers.size(), 0);
    std::vector<std::uint32_t> best, part, queue;
    for (std::size_t s = 0; s < inliers.size(); ++s) {
      if (seen[s]) continue;
      part.clear();
      queue.assign(1, static_cast<std::uint32_t>(s));
      seen[s] = 1;
      for (std::size_t head = 0; head < queue.size(); ++head) {
        const std::uint32_t f = inliers[queue[head]];
        part.push_back(f);
        for (std::uint32_t k = 0; k < 3; ++k) {
          const std::uint32_t t = m.twin(3 * f + k);
          if (t == HalfEdgeMesh::kNone) continue;
          const auto it = std::lower_bound(inliers.begin(), inliers.end(), HalfEdgeMesh::face(t));
          if (it == inliers.end() || *it != HalfEdgeMesh::face(t)) continue;
          const auto at = static_cast<std::size_t>(it - inliers.begin());
          if (seen[at]) continue;
          seen[at] = 1;
          queue.push_back(static_cast<std::uint32_t>(at));
        }
      }
      if (part.size() > best.size()) best = part;
    }
    if (best.size() < min_faces) return false;
    std::sort(best.begin(), best.end());
    r.faces = std::move(best);
    fit_plane(m, r, side, trim);
  }
  return r.deviation <= tolerance;
}

RegionClass classify(const Eigen::Vector3f& n, const Eigen::Vector3f& up) {
  const float c = n.dot(up.normalized());
  if (c > 0.9f) return RegionClass::kFloor;     // faces up: a floor or a table top
  if (c < -0.9f) return RegionClass::kCeiling;  // faces down
  if (std::abs(c) < 0.2f) return RegionClass::kWall;
  return RegionClass::kOther;
}

// Robust roughness of the mesh inside its grown regions (metres): 1.4826 x the median, over
// the vertices whose faces all lie in one region, of the distance along that region's normal
// from the vertex to the mean of its ring neighbours. Noise of standard deviation s gives about
// s; a smooth curved surface only curvature x edge^2 / 4 (a sphere 29 voxels in radius meshed
// at 0.6-voxel edges: 0.003 voxel), so the estimate tells scanner noise from curvature.
float roughness(const HalfEdgeMesh& m, const PlanarSegmentation& s) {
  const std::size_t count = m.vertex_count();
  std::vector<float> d(count, -1.0f);
  tbb::parallel_for(std::size_t{0}, count, [&](std::size_t vi) {
    const auto v = static_cast<std::uint32_t>(vi);
    if (m.is_border_vertex(v)) return;
    const std::vector<std::uint32_t> ring = m.ring(v);
    if (ring.size() < 3) return;
    const std::int32_t region = s.region_of_face[HalfEdgeMesh::face(ring.front())];
    if (region < 0) return;
    Eigen::Vector3f mean = Eigen::Vector3f::Zero();
    for (std::uint32_t h : ring) {
      if (s.region_of_face[HalfEdgeMesh::face(h)] != region) return;
      mean += m.position(m.to(h));
    }
    mean /= static_cast<float>(ring.size());
    d[vi] = std::abs(s.regions[static_cast<std::size_t>(region)].normal.dot(m.position(v) - mean));
  });
  d.erase(std::remove(d.begin(), d.end(), -1.0f), d.end());
  if (d.empty()) return 0.0f;
  const auto middle = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
  std::nth_element(d.begin(), middle, d.end());
  return 1.4826f * *middle;
}

// Drops the regions not `explained` (their faces join no region) and renumbers the others;
// faces that a kept region shed join no region either.
void keep_explained_regions(PlanarSegmentation& s, const std::vector<std::uint8_t>& explained) {
  std::vector<PlanarRegion> kept;
  for (std::size_t i = 0; i < s.regions.size(); ++i) {
    if (explained[i])
      kept.push_back(std::move(s.regions[i]));
    else
      ++s.curved;
  }
  s.regions = std::move(kept);
  std::fill(s.region_of_face.begin(), s.region_of_face.end(), -1);
  for (std::size_t r = 0; r < s.regions.size(); ++r)
    for (std::uint32_t f : s.regions[r].faces) s.region_of_face[f] = static_cast<std::int32_t>(r);
}

}  // namespace

PlanarSegmentation grow_planar_regions(const HalfEdgeMesh& m, const PlanarRegionConfig& config) {
  const std::size_t faces = m.face_count();
  std::vector<Eigen::Vector3f> normals(faces);
  tbb::parallel_for(std::size_t{0}, faces, [&](std::size_t f) {
    normals[f] = m.face_alive(static_cast<std::uint32_t>(f))
                     ? unit_face_normal(m, static_cast<std::uint32_t>(f))
                     : Eigen::Vector3f::Zero();
  });
  PlanarSegmentation out;
  out.region_of_face.assign(faces, -1);
  std::vector<std::uint8_t> visited(faces, 0);
  std::vector<Eigen::Vector3f> sides;
  std::vector<std::uint32_t> queue;
  for (std::uint32_t seed = 0; seed < faces; ++seed) {
    if (visited[seed] || !m.face_alive(seed) || normals[seed].isZero()) continue;
    // Breadth-first across edges; faces of a dropped region stay visited (they are not seeds).
    queue.assign(1, seed);
    visited[seed] = 1;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const std::uint32_t f = queue[head];
      for (std::uint32_t k = 0; k < 3; ++k) {
        const std::uint32_t t = m.twin(3 * f + k);
        if (t == HalfEdgeMesh::kNone) continue;
        const std::uint32_t g = HalfEdgeMesh::face(t);
        if (visited[g] || normals[g].dot(normals[seed]) <= config.normal_threshold) continue;
        visited[g] = 1;
        queue.push_back(g);
      }
    }
    if (queue.size() < config.min_region_faces) {
      for (std::uint32_t f : queue) visited[f] = 0;  // may still join a later region
      visited[seed] = 1;                             // but is no seed again
      continue;
    }
    PlanarRegion r;
    r.faces = queue;
    std::sort(r.faces.begin(), r.faces.end());
    Eigen::Vector3f side = Eigen::Vector3f::Zero();
    for (std::uint32_t f : r.faces) {
      out.region_of_face[f] = static_cast<std::int32_t>(out.regions.size());
      side += normals[f];
    }
    sides.push_back(side);
    out.regions.push_back(std::move(r));
  }
  tbb::parallel_for(std::size_t{0}, out.regions.size(),
                    [&](std::size_t i) { fit_plane(m, out.regions[i], sides[i]); });
  if (config.max_deviation > 0.0f) {
    // Loose: the tolerance asked for, or the noise's. Tight: a mesh far smoother than that (an
    // exact extraction: roughness 1e-6 voxel) is held to kSmoothRoughnessFactor x its
    // roughness, at least kSmoothToleranceShare x the tolerance asked for: its planes are exact,
    // and a curved part (a cylinder) is flat only in bands too narrow for a region.
    const float rough = config.fixed_tolerance > 0.0f ? 0.0f : roughness(m, out);
    const float loose = std::max({config.max_deviation, 3.0f * rough, config.fixed_tolerance});
    const float tight =
        config.fixed_tolerance > 0.0f
            ? config.fixed_tolerance
            : std::max(3.0f * rough, std::min(config.max_deviation,
                                              kSmoothRoughnessFactor * rough +
                                                  kSmoothToleranceShare * config.max_deviation));
    out.tolerance = tight;
    // Only a smooth mesh's planes are trimmed: a scan's are least squares through its noise.
    const float trim = tight < loose ? tight : -1.0f;
    std::vector<std::uint8_t> explained(out.regions.size(), 1);
    tbb::parallel_for(std::size_t{0}, out.regions.size(), [&](std::size_t i) {
      PlanarRegion& r = out.regions[i];
      const std::size_t least = config.min_region_faces;
      explained[i] =
          keep_explained_part(m, r, sides[i], loose, trim, least) &&
          (r.deviation <= tight || keep_explained_part(m, r, sides[i], tight, trim, least));
    });
    keep_explained_regions(out, explained);
  }
  for (PlanarRegion& r : out.regions) r.kind = classify(r.normal, config.up);
  return out;
}

std::size_t project_onto_planes(HalfEdgeMesh& m, const PlanarSegmentation& s,
                                float max_projection) {
  const std::size_t vertex_count = m.vertex_count();
  std::vector<std::uint8_t> moved(vertex_count, 0);
  tbb::parallel_for(std::size_t{0}, vertex_count, [&](std::size_t vi) {
    const auto v = static_cast<std::uint32_t>(vi);
    const std::vector<std::uint32_t> ring = m.ring(v);
    if (ring.empty()) return;
    const std::int32_t region = s.region_of_face[HalfEdgeMesh::face(ring.front())];
    if (region < 0) return;
    for (std::uint32_t h : ring)
      if (s.region_of_face[HalfEdgeMesh::face(h)] != region) return;
    const PlanarRegion& r = s.regions[static_cast<std::size_t>(region)];
    const Eigen::Vector3f p = m.position(v);
    const float distance = r.normal.dot(p) - r.offset;
    if (max_projection > 0.0f && std::abs(distance) > max_projection) return;
    m.set_position(v, p - distance * r.normal);
    moved[v] = 1;
  });
  std::size_t count = 0;
  for (std::uint8_t x : moved) count += x;
  return count;
}

}  // namespace meshflow
