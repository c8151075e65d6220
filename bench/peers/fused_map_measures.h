#pragma once
// Fused maps measured against a reference (bench/peers/fusion_vs_open3d.cpp): an input's frames
// with the points both meshes are compared with, the accuracy and completeness of one mesh, and
// the breakdown of the reference points one mesh covers and the other misses by meshflow's map.

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nodes/fusion/tsdf_map.h"
#include "nodes/io/sequence.h"
#include "nodes/synthetic/closed_objects.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::fusion_peer {

/// An input: its frames and the reference both meshes are measured against.
struct Scene {
  std::string name;
  std::unique_ptr<io::Sequence> sequence;
  std::vector<Eigen::Vector3f> reference;         // truth samples, or the frames' points
  std::optional<synthetic::ClosedObject> object;  // the exact surface; none for recorded frames
  double unit = 1.0;                              // metres per reported distance unit
  std::vector<char> seen;  // per reference point: some frame measured it (seen_by_frames())
};

/// Per point: whether some frame measured it, i.e. the depth at its nearest pixel lies within
/// `tolerance` (metres) of the point's own depth in that camera. Loads every frame; parallel
/// over the points, deterministic; O(points x frames).
std::vector<char> seen_by_frames(const io::Sequence& sequence,
                                 const std::vector<Eigen::Vector3f>& points, float tolerance);

/// Every second pixel of every second row of every frame with a depth in (0.1, 10) m, in the
/// world (bench/python/bench_fusion_vs_open3d.py's Redwood reference). Serial; O(pixels).
std::vector<Eigen::Vector3f> frame_points(const io::Sequence& sequence);

/// One mesh against the scene's reference; distances in scene.unit.
struct Measures {
  double accuracy = 0.0, completeness = 0.0, within = 0.0, within_twice = 0.0;
  double seen = 0.0, seen_within = 0.0, seen_within_twice = 0.0;  // of the points frames measured
  std::size_t triangles = 0, border_edges = 0;
  std::vector<float> to_mesh;  // metres, per reference point
};

/// `mesh` against `scene`: completeness from every reference point's distance to the mesh (shares
/// within tau and 2 tau metres, of all points and of those some frame measured); accuracy the
/// mesh's area-sampled mean distance to the exact surface, or without one the mean distance of
/// its vertices to the nearest reference point. Parallel, deterministic; O((R + V) log T).
Measures measure(const TriangleMesh& mesh, const Scene& scene, float tau);

/// Prints one line of m's figures under the name `tool`.
void report(const char* tool, const Measures& m, float tau);

/// Prints the reference points within tau of one mesh and not of the other (ours: meshflow's,
/// whose `map` is given), by meshflow's cell there — observed corners on both sides, some corners
/// unobserved (and where: in no block or in a block never updated), none — and with
/// `patches_too` by the object's patch. O(R).
void breakdown(const Scene& scene, const TsdfMap& map, const Measures& ours, const Measures& theirs,
               float tau, float min_weight, bool patches_too);

}  // namespace meshflow::fusion_peer
