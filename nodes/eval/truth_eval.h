#pragma once
// Accuracy of a mesh against an analytic surface (the exact distance of a synthetic object):
// the distances of its vertices and of points spread uniformly over its area. The area samples
// weigh a large flat triangle as much as the many small ones it replaced, which vertex errors
// do not (after retriangulation most vertices sit on region borders).

#include <cstddef>
#include <functional>
#include <vector>

#include "nodes/eval/surface_eval.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

/// `count` points drawn uniformly by area over the triangles of `mesh` (deterministic for a
/// seed; none for a mesh without area). Serial; O(T + count log T).
std::vector<Eigen::Vector3f> surface_samples(const TriangleMesh& mesh, std::size_t count,
                                             std::uint32_t seed = 1);

struct TruthEvaluation {
  DistanceStats vertices;  ///< every vertex's distance to the true surface, metres
  DistanceStats area;      ///< distances of surface_samples(), metres
  MeshTopology topology;
};

/// Distances of `mesh` to the surface whose exact unsigned distance is `distance` (metres;
/// must be thread-safe). Parallel over points, deterministic. O(V + samples) distance calls.
TruthEvaluation evaluate_against_truth(const TriangleMesh& mesh,
                                       const std::function<float(const Eigen::Vector3f&)>& distance,
                                       std::size_t area_samples = 200000);

}  // namespace meshflow
