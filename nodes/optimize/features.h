#pragma once
// The feature graph of a mesh: its sharp edges (the two faces meet at more than a threshold
// angle) and the vertices where feature lines end, branch or bend (corners). The reducing
// optimize steps receive it and keep it: decimation never removes a corner and collapses along a
// feature line only onto that line, remeshing moves feature vertices only along their line.

#include <array>
#include <cstdint>
#include <vector>

#include "runtime/triangle_mesh.h"
#include "runtime/vertex_triangles.h"

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
/// negative: no line is dropped. angle_deg >= 180: no features. Candidates from face normals
/// (once) in one parallel pass over the vertices: a vertex whose faces all lie within half the
/// angle of their mean normal ends no sharp edge; every other one judges its edges to higher
/// vertices from its own faces. The lines on the candidates' vertices only; deterministic, the
/// same for any thread count. O(T + V + bent vertices x valence log valence + rounds x
/// candidates log candidates), rounds about the depth of the noise's branching.
MeshFeatures detect_features(const TriangleMesh& mesh, float angle_deg = kDefaultFeatureAngleDeg,
                             float min_line_length = 0.0f);

/// detect_features() on a mesh whose maker marked the vertices it placed on sharp features
/// (`seed`, one byte per vertex, non-zero on such a vertex: extended marching cubes' feature
/// vertices, extract_surface()): detect_features(), except that a line holding an edge between
/// two marked vertices is never dropped as noise, however short (EMC's lines break into short
/// pieces at a cell where it fell back to marching cubes: the L-shape's true edges are covered
/// 99.5 % instead of 95.6 % at a voxel of 1 % of its diagonal). The marked edges alone are no
/// graph (90.8 % there), nor do marked edges at a lower angle help (20 degrees: 94.1 %).
/// The marks are read where detect_features() finds its candidates: the same pass, the same
/// costs, deterministic. A `seed` of another size than the vertex count:
/// detect_features(mesh, angle_deg,
/// min_line_length).
MeshFeatures detect_features(const TriangleMesh& mesh, const std::vector<std::uint8_t>& seed,
                             float angle_deg = kDefaultFeatureAngleDeg,
                             float min_line_length = 0.0f);

/// detect_features(mesh, ...) or, with `seed` (nullptr, or one of another size: none),
/// detect_features(mesh, *seed, ...), on the incidence `around` = vertex_triangles(mesh) that the
/// caller has built anyway (the decimator, for its rings): the same graph, without building it
/// again. Same costs otherwise.
MeshFeatures detect_features(const TriangleMesh& mesh, const VertexTriangles& around,
                             const std::vector<std::uint8_t>* seed,
                             float angle_deg = kDefaultFeatureAngleDeg,
                             float min_line_length = 0.0f);

/// detect_features() on the feature lines that reach `seeds` (vertex indices) only: the sharp
/// edges and vertex kinds detect_features(mesh, angle_deg, min_line_length) gives on the
/// connected sets of candidate edges (joined at shared vertices) that hold a seed; nothing
/// elsewhere (those vertices kFree). Each such set is judged on its own there too, so this is
/// exactly that part of the whole mesh's graph, found by a search from the seeds through the
/// candidates instead of a pass over every face: for a step that needs the lines at a few places
/// (the hole filler: the lines ending on a hole's border). `around` is vertex_triangles(mesh).
/// `marks` (optional, one byte per vertex; another size: none): the mesh maker's feature
/// vertices, as detect_features(mesh, marks, ...) reads them (that graph's part then).
/// Serial; deterministic. O(seeds + V + reached vertices x valence^2 + rounds x their
/// candidates log candidates); min_line_length 0 adds the whole mesh's median edge length.
MeshFeatures detect_features_reaching(const TriangleMesh& mesh, const VertexTriangles& around,
                                      const std::vector<std::uint32_t>& seeds,
                                      float angle_deg = kDefaultFeatureAngleDeg,
                                      float min_line_length = 0.0f,
                                      const std::vector<std::uint8_t>* marks = nullptr);

}  // namespace meshflow
