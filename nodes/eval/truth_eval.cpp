#include "nodes/eval/truth_eval.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

namespace meshflow {
namespace {

std::vector<float> distances_of(const std::vector<Eigen::Vector3f>& points,
                                const std::function<float(const Eigen::Vector3f&)>& distance) {
  std::vector<float> d(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) d[i] = distance(points[i]);
                    });
  return d;
}

}  // namespace

std::vector<Eigen::Vector3f> surface_samples(const TriangleMesh& mesh, std::size_t count,
                                             std::uint32_t seed) {
  std::vector<double> cumulative;
  cumulative.reserve(mesh.triangles.size());
  double area = 0.0;
  for (const Triangle& t : mesh.triangles) {
    const Eigen::Vector3f& a = mesh.vertices[t[0]];
    area +=
        0.5 * static_cast<double>((mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a).norm());
    cumulative.push_back(area);
  }
  std::vector<Eigen::Vector3f> out;
  if (!(area > 0.0)) return out;
  std::mt19937_64 rng(seed);
  auto uniform = [&rng] { return static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0); };
  out.reserve(count);
  for (std::size_t s = 0; s < count; ++s) {
    const double pick = uniform() * area;
    const std::size_t k = std::min<std::size_t>(
        static_cast<std::size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), pick) -
                                 cumulative.begin()),
        mesh.triangles.size() - 1);
    const Triangle& t = mesh.triangles[k];
    const auto r1 = static_cast<float>(std::sqrt(uniform()));
    const auto r2 = static_cast<float>(uniform());
    out.push_back((1.0f - r1) * mesh.vertices[t[0]] + r1 * (1.0f - r2) * mesh.vertices[t[1]] +
                  r1 * r2 * mesh.vertices[t[2]]);
  }
  return out;
}

TruthEvaluation evaluate_against_truth(const TriangleMesh& mesh,
                                       const std::function<float(const Eigen::Vector3f&)>& distance,
                                       std::size_t area_samples) {
  TruthEvaluation e;
  e.vertices = distance_stats(distances_of(mesh.vertices, distance));
  e.area = distance_stats(distances_of(surface_samples(mesh, area_samples), distance));
  e.topology = mesh_topology(mesh);
  return e;
}

}  // namespace meshflow
