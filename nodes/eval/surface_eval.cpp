#include "nodes/eval/surface_eval.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "nodes/search/mesh_distance_index.h"
#include "nodes/search/spatial_index.h"
#include "runtime/error.h"

namespace meshflow {
namespace {

std::uint32_t find_root(std::vector<std::uint32_t>& parent, std::uint32_t v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];
  return v;
}

float unoriented_angle_deg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  const float c = std::min(1.0f, std::abs(a.normalized().dot(b.normalized())));
  return std::acos(c) * 57.2957795f;
}

// The triangle's area when its winding normal points against `reference_normal`, else 0.
double facing_against_area(const TriangleMesh& mesh, const Triangle& f,
                           const Eigen::Vector3f& reference_normal) {
  const Eigen::Vector3f cross =
      (mesh.vertices[f[1]] - mesh.vertices[f[0]]).cross(mesh.vertices[f[2]] - mesh.vertices[f[0]]);
  return cross.dot(reference_normal) < 0.0f ? 0.5 * static_cast<double>(cross.norm()) : 0.0;
}

}  // namespace

double signed_volume(const TriangleMesh& mesh) {
  double volume = 0.0;
  for (const Triangle& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[t[1]].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[t[2]].cast<double>();
    volume += a.dot(b.cross(c));
  }
  return volume / 6.0;
}

DistanceStats distance_stats(std::vector<float> d) {
  DistanceStats s;
  s.samples = d.size();
  if (d.empty()) return s;
  double sum = 0.0, sum_sq = 0.0;
  for (float x : d) {
    sum += x;
    sum_sq += static_cast<double>(x) * x;
    s.max = std::max(s.max, static_cast<double>(x));
  }
  s.mean = sum / static_cast<double>(d.size());
  s.rms = std::sqrt(sum_sq / static_cast<double>(d.size()));
  auto quantile = [&](double q) {
    const std::size_t rank =
        std::min(d.size() - 1,
                 std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(q * d.size()))) - 1);
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(rank), d.end());
    return static_cast<double>(d[rank]);
  };
  s.median = quantile(0.5);
  s.p95 = quantile(0.95);
  return s;
}

MeshTopology mesh_topology(const TriangleMesh& mesh) {
  MeshTopology t;
  t.edges = edge_statistics(mesh);
  for (const Triangle& f : mesh.triangles) {
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2] || face_normal(mesh, f).isZero())
      ++t.degenerate_faces;
  }
  // Loops: connected components of the border-edge graph.
  std::vector<std::uint32_t> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0u);
  std::vector<std::uint8_t> on_boundary(mesh.vertices.size(), 0);
  for (const BorderEdge& e : border_edges(mesh)) {
    on_boundary[e.a] = on_boundary[e.b] = 1;
    parent[find_root(parent, e.a)] = find_root(parent, e.b);
  }
  for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v)
    if (on_boundary[v] && find_root(parent, v) == v) ++t.boundary_loops;
  return t;
}

SurfaceEvaluation evaluate_surface(const TriangleMesh& mesh, const TriangleMesh& reference) {
  if (mesh.triangles.empty()) throw Error("eval", "mesh", "has no triangles");
  if (reference.vertices.empty()) throw Error("eval", "reference", "has no points");
  for (std::size_t i = 0; i < reference.vertices.size(); ++i)
    if (!reference.vertices[i].allFinite())
      throw Error("eval", "reference point " + std::to_string(i), "is not finite");
  SurfaceEvaluation e;
  e.vertices = mesh.vertices.size();
  e.triangles = mesh.triangles.size();
  e.topology = mesh_topology(mesh);

  TriangleMesh with_normals;
  const TriangleMesh* m = &mesh;
  if (mesh.normals.size() != mesh.vertices.size()) {
    with_normals = mesh;
    compute_vertex_normals(with_normals);
    m = &with_normals;
  }
  const MeshDistanceIndex mesh_index(*m);

  std::vector<float> forward(m->vertices.size()), angles(m->vertices.size(), -1.0f);
  std::vector<double> against_area(m->triangles.size(), 0.0);  // area facing against
  const bool point_reference = reference.triangles.empty();
  const bool reference_normals =
      point_reference ? reference.normals.size() == reference.vertices.size() : true;
  if (point_reference) {
    const KdTreeIndex kd(reference.vertices);
    tbb::parallel_for(std::size_t{0}, m->vertices.size(), [&](std::size_t i) {
      std::uint32_t idx = 0;
      float d2 = 0.0f;
      kd.knn(m->vertices[i], 1, &idx, &d2);
      forward[i] = std::sqrt(d2);
      if (reference_normals)
        angles[i] = unoriented_angle_deg(m->normals[i], reference.normals[idx]);
    });
    if (reference_normals) {
      tbb::parallel_for(std::size_t{0}, m->triangles.size(), [&](std::size_t t) {
        const Triangle& f = m->triangles[t];
        const Eigen::Vector3f c = (m->vertices[f[0]] + m->vertices[f[1]] + m->vertices[f[2]]) / 3;
        std::uint32_t idx = 0;
        float d2 = 0.0f;
        kd.knn(c, 1, &idx, &d2);
        against_area[t] = facing_against_area(*m, f, reference.normals[idx]);
      });
    }
  } else {
    const MeshDistanceIndex reference_index(reference);
    tbb::parallel_for(std::size_t{0}, m->vertices.size(), [&](std::size_t i) {
      const auto hit = reference_index.closest(m->vertices[i]);
      forward[i] = hit.distance;
      angles[i] = unoriented_angle_deg(m->normals[i],
                                       face_normal(reference, reference.triangles[hit.triangle]));
    });
    tbb::parallel_for(std::size_t{0}, m->triangles.size(), [&](std::size_t t) {
      const Triangle& f = m->triangles[t];
      const Eigen::Vector3f c = (m->vertices[f[0]] + m->vertices[f[1]] + m->vertices[f[2]]) / 3;
      const auto hit = reference_index.closest(c);
      against_area[t] =
          facing_against_area(*m, f, face_normal(reference, reference.triangles[hit.triangle]));
    });
  }
  if (reference_normals) {
    double total = 0.0, against = 0.0;  // summed in triangle order: deterministic
    for (std::size_t t = 0; t < m->triangles.size(); ++t) {
      const Triangle& f = m->triangles[t];
      const double area =
          0.5 * static_cast<double>((m->vertices[f[1]] - m->vertices[f[0]])
                                        .cross(m->vertices[f[2]] - m->vertices[f[0]])
                                        .norm());
      total += area;
      against += against_area[t];
    }
    e.inside_out_area_share = total > 0.0 ? against / total : 0.0;
  } else {
    e.inside_out_area_share = std::numeric_limits<double>::quiet_NaN();
  }
  std::vector<float> backward(reference.vertices.size());
  tbb::parallel_for(std::size_t{0}, reference.vertices.size(), [&](std::size_t i) {
    backward[i] = mesh_index.closest(reference.vertices[i]).distance;
  });
  e.mesh_to_reference = distance_stats(std::move(forward));
  e.reference_to_mesh = distance_stats(std::move(backward));
  std::vector<float> valid_angles;
  for (float a : angles)
    if (a >= 0.0f && std::isfinite(a)) valid_angles.push_back(a);  // -1: no normal
  if (!valid_angles.empty()) {
    const DistanceStats a = distance_stats(std::move(valid_angles));
    e.normal_mean_deg = a.mean;
    e.normal_p95_deg = a.p95;
    e.normal_samples = a.samples;
  }
  return e;
}

}  // namespace meshflow
