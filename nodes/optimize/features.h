#pragma once
// The feature graph of a mesh: its sharp edges (the two faces meet at more than a threshold
// angle) and the vertices where feature lines end, branch or bend (corners). The reducing
// optimize steps receive it and keep it: decimation never removes a corner and collapses along a
// feature line only onto that line, remeshing moves feature vertices only along their line.

#include <array>
#include <cstdint>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow {

/// The default --feature-angle: faces meeting at more than 40 degrees form a sharp edge (a
/// marching-cubes staircase on a smooth surface stays well below it at a voxel of 1 % of the
/// diagonal; CAD edges, even a 45-degree chamfer, are above it).
constexpr float kDefaultFeatureAngleDeg = 40.0f;

/// The default shortest feature line, in median edge lengths of the mesh (see detect_features):
/// on a scanned room the 40-degree test also fires on bumps, whose sharp edges form short,
/// zigzagging, branching runs; a CAD edge or a wall's corner runs straight over many edges.
constexpr float kMinFeatureLineEdges = 5.0f;
/// Where the voxel is known (the pipelines, `meshflow optimize --voxel`), the same count of
/// voxels: an extracted mesh's median edge is about one voxel, and a mesh reduced before, whose
/// median edge is many voxels long, keeps its lines (optimize_config_for_voxel()).

struct MeshFeatures {
  enum class VertexKind : std::uint8_t { kFree, kLine, kCorner };
  /// Sharp edges as {a, b} with a < b, ascending.
  std::vector<std::array<std::uint32_t, 2>> edges;
  /// Per vertex: kFree (no sharp edge), kLine (two sharp edges that continue one another: the
  /// line turns by less than the feature angle and the faces on each side by less than twice
  /// it, at most 90 degrees), kCorner (one, three or more sharp edges, or two that do not continue
  /// one another).
  std::vector<VertexKind> vertex_kind;

  /// Whether {a, b} is a sharp edge. O(log edges).
  bool has_edge(std::uint32_t a, std::uint32_t b) const;
  /// The number of vertices of each kind.
  std::size_t count(VertexKind kind) const;
};

/// Sharp edges of `mesh` and the vertex kinds (see MeshFeatures).
/// Candidates: edges with exactly two faces whose normals differ by more than `angle_deg`
/// degrees (border and non-manifold edges are never sharp). They form feature lines, runs of
/// candidates broken at corners (see VertexKind). A line shorter than `min_line_length` metres
/// is noise and dropped, unless it joins two corners where two longer lines each meet it (a
/// chamfer's short edge): short lines with a loose end (spurs) and short loops first, the
/// others once no spur is left; the lines left then join anew and the test repeats until
/// nothing changes. min_line_length 0: kMinFeatureLineEdges x the mesh's median edge length;
/// negative: no line is dropped. angle_deg >= 180: no features. The candidates in parallel, the
/// rest serial; the same for any thread count. O(V + T + rounds x (V + candidates)), rounds about
/// the depth of the noise's branching.
MeshFeatures detect_features(const TriangleMesh& mesh, float angle_deg = kDefaultFeatureAngleDeg,
                             float min_line_length = 0.0f);

}  // namespace meshflow
