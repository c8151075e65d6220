#include "nodes/optimize/planar/plane_intersections.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>

#include "nodes/optimize/feature_snap.h"

namespace meshflow {
namespace {

// The planes of the distinct regions around v; empty when a face around v is in no region.
std::vector<FeaturePlane> intersection_planes(const HalfEdgeMesh& m, const PlanarSegmentation& s,
                                              std::uint32_t v) {
  std::vector<std::int32_t> regions;
  for (std::uint32_t h : m.ring(v)) {
    const std::int32_t r = s.region_of_face[HalfEdgeMesh::face(h)];
    if (r < 0) return {};
    if (std::find(regions.begin(), regions.end(), r) == regions.end()) regions.push_back(r);
  }
  std::vector<FeaturePlane> planes;
  for (std::int32_t r : regions) {
    const PlanarRegion& region = s.regions[static_cast<std::size_t>(r)];
    planes.push_back(
        {region.normal.cast<double>().normalized(), static_cast<double>(region.offset)});
  }
  return planes;
}

// Whether moving v to `to` keeps each of its faces with area and within 90 degrees of its
// orientation.
bool intersection_keeps_faces(const HalfEdgeMesh& m, std::uint32_t v, const Eigen::Vector3f& to) {
  for (std::uint32_t h : m.ring(v)) {
    const Eigen::Vector3f& b = m.position(m.to(h));
    const Eigen::Vector3f& c = m.position(m.to(HalfEdgeMesh::next(h)));
    const Eigen::Vector3f before = (b - m.position(v)).cross(c - m.position(v));
    if (!has_area(to, b, c) || before.dot((b - to).cross(c - to)) <= 0.0f) return false;
  }
  return true;
}

}  // namespace

PlaneIntersectionReport project_onto_plane_intersections(HalfEdgeMesh& m,
                                                         const PlanarSegmentation& s,
                                                         const MeshFeatures& features,
                                                         float max_move) {
  PlaneIntersectionReport report;
  const std::size_t n = m.vertex_count();
  if (features.edges.empty() || features.vertex_kind.size() != n) return report;
  std::vector<Eigen::Vector3f> target(n);
  std::vector<std::uint8_t> kind(n, 0);  // 0: stays, 2: onto a line, 3: onto a corner
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    const auto v = static_cast<std::uint32_t>(i);
    if (features.vertex_kind[v] == MeshFeatures::VertexKind::kFree ||
        m.outgoing(v) == HalfEdgeMesh::kNone)
      return;
    const std::vector<FeaturePlane> planes = intersection_planes(m, s, v);
    if (planes.size() < 2 || !planes_meet(planes)) return;
    const Eigen::Vector3d here = m.position(v).cast<double>();
    target[i] = (here + move_onto_planes(here, planes)).cast<float>();
    kind[i] = planes.size() == 2 ? 2 : 3;
  });
  for (std::uint32_t v = 0; v < n; ++v) {
    if (kind[v] == 0 || target[v] == m.position(v)) continue;
    const float move = (target[v] - m.position(v)).norm();
    if (!target[v].allFinite() || (max_move > 0.0f && move > max_move) ||
        !intersection_keeps_faces(m, v, target[v])) {
      ++report.refused;
      continue;
    }
    m.set_position(v, target[v]);
    ++(kind[v] == 2 ? report.to_line : report.to_corner);
  }
  return report;
}

}  // namespace meshflow
