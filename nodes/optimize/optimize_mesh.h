#pragma once
// The optimisation stage as a composition of steps, run in the order the user lists them:
// clean (degenerate faces, small components), holes (close small border loops), planes
// (planar regions, vertices projected onto their plane), sharpen (the bevels between planar
// regions cut along the planes' intersection lines), retriangulate (planar regions
// triangulated anew from their simplified contours), remesh (curvature-aware: large triangles
// where the surface is flat, small ones where it bends), decimate (constrained QEM).

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "nodes/decimate/qem_decimation.h"
#include "nodes/optimize/cleanup/hole_filling.h"
#include "nodes/optimize/cleanup/mesh_cleanup.h"
#include "nodes/optimize/features.h"
#include "nodes/optimize/planar/planar_regions.h"
#include "nodes/optimize/planar/retriangulate_regions.h"
#include "nodes/optimize/planar/sharp_edges.h"
#include "nodes/optimize/remesh/adaptive_remesh.h"
#include "runtime/triangle_mesh.h"

namespace meshflow {

enum class OptimizeStep { kClean, kHoles, kPlanes, kSharpen, kRetriangulate, kRemesh, kDecimate };
const char* optimize_step_name(OptimizeStep step);

/// "default" (clean, holes), "none", or a comma-separated list of step names in the order they
/// should run ("clean,holes,planes,sharpen,retriangulate,remesh,decimate"); a step may repeat.
/// Throws meshflow::Error naming the unknown step and the valid names.
std::vector<OptimizeStep> parse_optimize_steps(const std::string& list);

struct OptimizeConfig {
  std::vector<OptimizeStep> steps{OptimizeStep::kClean, OptimizeStep::kHoles};
  /// Sharp edges: faces meeting at more than this many degrees (detect_features(), on the mesh
  /// each reducing step receives); the steps keep them. 180: no features.
  float feature_angle_deg = kDefaultFeatureAngleDeg;
  /// Feature lines shorter than this are noise (metres; detect_features()). 0:
  /// kMinFeatureLineEdges x the median edge length of the mesh optimize_mesh() receives, the
  /// same for every step.
  float feature_min_length = 0.0f;
  /// Whether the decimate step passes the feature graph to QEM (qem_decimate with feature
  /// edges: corners stay, feature-line vertices collapse only along their line).
  bool decimate_keeps_features = true;
  CleanupConfig cleanup;
  HoleFillingConfig holes;
  PlanarRegionConfig planes;  ///< planes, sharpen and retriangulate
  SharpEdgeConfig sharpen;
  RetriangulationConfig retriangulation;
  AdaptiveRemeshConfig remesh;
  /// Decimation defaults for a reconstructed map: plain quadric errors (no depth weighting),
  /// a quarter of the triangles kept.
  QemConfig decimate = [] {
    QemConfig q;
    q.divide_by_depth2 = false;
    return q;
  }();
  /// Called before each step runs (from the calling thread): for progress lines. Optional.
  std::function<void(OptimizeStep)> on_step;
};

/// What one step did.
struct OptimizeStepReport {
  OptimizeStep step = OptimizeStep::kClean;
  std::size_t triangles_in = 0, triangles_out = 0;
  double seconds = 0.0;
  /// Step-specific counts ("2 holes filled (+10 triangles), 1 too large"), or why the step was
  /// skipped (the half-edge steps need a 2-manifold and pass anything else on unchanged).
  std::string detail;
  bool skipped = false;
};

struct OptimizeReport {
  std::vector<OptimizeStepReport> steps;
  CleanupReport cleanup;  ///< of the last clean step
};

/// Runs config.steps on `mesh` in order and returns the result; normals and colours follow
/// their vertices, and normals are recomputed from the faces when a planes step moved
/// vertices. A step that
/// cannot run on this mesh (non-manifold input for the half-edge steps) is skipped with
/// its reason in the report rather than failing the frame. Each step is parallel where its
/// kernel is and deterministic; see the kernels for costs.
TriangleMesh optimize_mesh(const TriangleMesh& mesh, const OptimizeConfig& config,
                           OptimizeReport* report = nullptr);

/// optimize_mesh() on a mesh whose maker marked the vertices it placed on sharp features
/// (`feature_vertices`, one byte per vertex of `mesh`, non-zero on such a vertex: extended
/// marching cubes' feature vertices from extract_surface()). The feature graph keeps lines of
/// edges between marked vertices (detect_features(mesh, seed, ...)) while the steps keep the
/// vertices (clean, holes and planes; the bytes follow them, 0 on added ones); after a step
/// that remeshes, the graph is detected. Flags of another size are ignored. Same costs.
TriangleMesh optimize_mesh(const TriangleMesh& mesh, const OptimizeConfig& config,
                           OptimizeReport* report,
                           const std::vector<std::uint8_t>& feature_vertices);

/// A byte per vertex that follows the vertices through the steps (0 on vertices a step adds);
/// vertices with any of `held_bits` set are held fixed: the clean step keeps all their fans and
/// the components holding them, the holes step leaves loops through them open (a chunk's seam,
/// finished where the chunk was meshed: the neighbouring chunk holds the rest of those fans,
/// components and loops).
struct HeldVertices {
  std::vector<std::uint8_t> flags;  ///< one per vertex of the mesh
  std::uint8_t held_bits = 1;
  /// Vertices with any of these bits set are the mesh maker's feature vertices: the seed of the
  /// feature graph, as optimize_mesh(mesh, config, report, feature_vertices) takes it (a chunk's
  /// extended marching cubes vertices, so that its holes step fills as one process's does).
  std::uint8_t feature_bits = 0;
};

/// optimize_mesh() with `held` (flags one per vertex of `mesh`; on return one per vertex of the
/// result). Only the clean and holes steps can hold vertices (and the clean step not with
/// kSplit): any other step throws meshflow::Error naming it. Same costs.
TriangleMesh optimize_mesh(const TriangleMesh& mesh, const OptimizeConfig& config,
                           OptimizeReport* report, HeldVertices& held);

/// One line per step: "clean  120345 -> 120001 triangles  3.1 ms  removed ...".
std::string format_optimize_report(const OptimizeReport& report);

}  // namespace meshflow
