#pragma once
// Hole filling (the reconstruction thesis's optimisation stage): border loops of up to a given
// number of edges are closed by a minimum-weight triangulation of the loop; the outer border of
// every connected component (its longest loop) stays open, so a scan keeps its outline, unless
// the loop is far too short to bound the component (a closed object's surface with a hole).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "nodes/optimize/features.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

struct HoleFillingConfig {
  /// Loops with more border edges stay open (at 5 cm voxels, 30 edges is a hole of about 0.5 m
  /// across: a gap between scan lines, an occluded patch behind a small object).
  std::size_t max_edges = 30;
  /// The longest loop of each connected component is its outer border and is never closed,
  /// unless its squared length is below 5 % of 4 pi x the component's area (a disk's outline
  /// has 100 %): then the component is a closed surface and the loop a hole. Off: every loop up
  /// to max_edges is a hole.
  bool keep_outer_border = true;
  /// Sharp edges (detect_features() with this angle, degrees, and feature_min_length metres:
  /// 0 = from the mesh) are not filled across: where feature lines end on a hole's border, the
  /// fill continues them (see fill_holes). 180: no features.
  float feature_angle_deg = kDefaultFeatureAngleDeg;
  float feature_min_length = 0.0f;
};

struct HoleFillingReport {
  std::size_t loops = 0;            ///< border loops found
  std::size_t outer_borders = 0;    ///< kept as the outline of their component
  std::size_t too_large = 0;        ///< more than max_edges edges
  std::size_t held_open = 0;        ///< through a held vertex (fill_holes' `held`), left open
  std::size_t filled = 0;           ///< closed
  std::size_t not_fillable = 0;     ///< ambiguous loops (through a non-manifold vertex), left open
  std::size_t centre_vertices = 0;  ///< holes fanned from an added centre vertex (see below)
  std::size_t along_features = 0;   ///< holes filled along the feature lines ending on them
  std::size_t added_triangles = 0;
};

/// The features of the mesh fill_holes() receives, where its caller has them (the optimize
/// steps carry them): with `graph`, nothing is detected; else with `marks`, the lines reaching
/// a hole are found as the seeded graph has them.
struct HoleFeatures {
  /// The whole mesh's graph (detect_features() at the config's angle and shortest line, or its
  /// seeded form): its lines ending on a hole are the ones detect_features_reaching() finds
  /// (the same fills, no detection).
  const MeshFeatures* graph = nullptr;
  /// The mesh maker's feature vertices (one byte per vertex; another size: ignored): lines
  /// holding an edge between two of them are no noise (detect_features(mesh, seed, ...)).
  const std::vector<std::uint8_t>* marks = nullptr;
};

/// Returns `mesh` with its small holes closed. Border loops are followed along the border
/// edges (runtime border_edges); a loop through a vertex with two border edges leaving it (a
/// non-manifold vertex, which the clean step splits) is ambiguous, left open and counted as not
/// fillable. Each hole (loop of n border vertices) gets the n - 2 triangles minimising the sum
/// of area + 0.1 x squared edge lengths (the second term prefers short diagonals where areas
/// tie, as in a flat hole) among the triangulations that add no edge already in the mesh and
/// no triangle without area (its area below 1e-4 of its squared edge lengths), oriented like
/// the faces around it; no vertices are added, so edges elsewhere are untouched. A hole that
/// every such triangulation would close with an edge the mesh already has (a pinched loop,
/// whose diagonals exist on the other side) is fanned from a vertex added at its centroid.
/// Feature lines (config.feature_angle_deg) that end on a hole's border are continued across
/// it, so no fill cuts an edge or a corner off (a minimum-area fill would: a chamfer has less
/// area than the two faces it replaces): two lines running into the hole from opposite sides
/// along one straight line are joined by a diagonal, and a hole where three or more lines end
/// that do not pair up so gets a vertex at their lines' least-squares meeting point (a lost
/// corner), joined to each; the parts between are filled as above. When that is not possible
/// (the diagonal exists, the corner lies off the hole) the plain fill is used.
/// Vertices, normals and colours are kept as they are; new triangles follow the old ones, holes in
/// the order of their first border edge. Loops are triangulated in parallel; the output does not
/// depend on the thread count. O(T + sum of n^3 over holes), plus, when a hole is to be filled
/// and features are on, detect_features_reaching() from the holes' vertices (the lines that
/// reach a hole; the same lines as the whole mesh's detect_features() there).
/// `held` (optional, one byte per vertex): loops through a vertex whose byte is non-zero stay
/// open (a chunk's seam, finished in place: its loops go on in the neighbouring chunk).
/// `known` (optional): what the caller knows of the features already (HoleFeatures).
TriangleMesh fill_holes(const TriangleMesh& mesh, const HoleFillingConfig& config = {},
                        HoleFillingReport* report = nullptr,
                        const std::vector<std::uint8_t>* held = nullptr,
                        const HoleFeatures& known = {});

}  // namespace meshflow
