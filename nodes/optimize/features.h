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

/// Sharp edges connected to fewer than this many others (by shared vertices) are dropped as
/// noise: on a scanned room the 40-degree test also fires on short runs of bumpy faces, whose
/// locked ends would stop decimation; a CAD edge spans many edges of the mesh.
constexpr std::size_t kMinFeatureEdges = 10;

struct MeshFeatures {
  enum class VertexKind : std::uint8_t { kFree, kLine, kCorner };
  /// Sharp edges as {a, b} with a < b, ascending.
  std::vector<std::array<std::uint32_t, 2>> edges;
  /// Per vertex: kFree (no sharp edge), kLine (two sharp edges turning by less than the feature
  /// angle: an inner vertex of a feature line), kCorner (one, three or more sharp edges, or two
  /// that turn by more than the feature angle).
  std::vector<VertexKind> vertex_kind;

  /// Whether {a, b} is a sharp edge. O(log edges).
  bool has_edge(std::uint32_t a, std::uint32_t b) const;
  /// The number of vertices of each kind.
  std::size_t count(VertexKind kind) const;
};

/// Sharp edges of `mesh` (an edge with exactly two faces whose normals differ by more than
/// `angle_deg` degrees, in a connected set of at least kMinFeatureEdges of them; border and
/// non-manifold edges are never sharp) and the vertex kinds
/// (see MeshFeatures). angle_deg >= 180: no features. Serial, deterministic; O(T log T).
MeshFeatures detect_features(const TriangleMesh& mesh, float angle_deg = kDefaultFeatureAngleDeg);

}  // namespace meshflow
