#pragma once
// The rim of an open surface: where a scan ends, the signed distance of the last points'
// tangent planes stays valid up to the distance band's width past them, so the extracted mesh
// runs on for up to two voxels beyond the data (the bunny's rim: 32 mm at 18 mm voxels).
// Peeling the border back to the data keeps every rim within a voxel of it.

#include <cstdint>
#include <vector>

#include "nodes/search/spatial_index.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

/// Removes border triangles (those with an edge no other triangle shares) with a corner of such
/// an edge farther than `max_distance` metres from the nearest of `positions` (`points` is an
/// index over them) — or, where the
/// data are sparser, farther than twice that point's distance to its own nearest neighbour —,
/// then the border triangles that uncovers, round after round until a round removes none (at
/// most 16 rounds);
/// unreferenced vertices are dropped (normals and colours follow). A closed mesh, and an open
/// one whose border lies on the data, is returned unchanged. Interior triangles are never
/// tested, so sparse data inside a surface opens no holes. `removed` (optional) receives the
/// number of triangles removed; `kept` (optional) the input index of each output vertex
/// (ascending), for per-vertex data to follow. Deterministic; O(V + T) for the incidence, then O(B
/// (d + log n)) for B triangles tested (the border and the triangles each removal uncovers) of
/// vertex degree d.
TriangleMesh trim_rim(const TriangleMesh& mesh, const std::vector<Eigen::Vector3f>& positions,
                      const SpatialIndex& points, float max_distance,
                      std::size_t* removed = nullptr, std::vector<std::uint32_t>* kept = nullptr);

/// Per vertex, 1 if it lies beyond the data as trim_rim() judges a border corner (farther than
/// `max_distance` from the nearest point and than twice that point's spacing), else 0. For
/// meshes trimmed later (chunks, trimmed once stitched). Parallel; O(V log n).
std::vector<std::uint8_t> vertices_beyond_data(const std::vector<Eigen::Vector3f>& vertices,
                                               const std::vector<Eigen::Vector3f>& positions,
                                               const SpatialIndex& points, float max_distance);

/// trim_rim() with every vertex's verdict given (`beyond`, one per vertex, from
/// vertices_beyond_data()) instead of measured. Same rounds, same result. `kept` (optional)
/// receives the input index of each output vertex (ascending), for per-vertex data to follow.
TriangleMesh trim_rim(const TriangleMesh& mesh, const std::vector<std::uint8_t>& beyond,
                      std::size_t* removed = nullptr, std::vector<std::uint32_t>* kept = nullptr);

}  // namespace meshflow
