#pragma once
// Quadric error metric decimation (Garland & Heckbert 1997) with the constraints of the depth-map
// triangulation work the method builds on: half-edge collapses that keep every vertex at its
// measured position, errors divided by depth^2 (sensor noise grows with depth^2), no collapse
// that turns a face by more than 60 degrees, borders collapsed only along themselves, and a
// penalty that keeps sharp edges and avoids needle triangles.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow {

struct QemConfig {
  float target_ratio = 0.25f;  ///< stop when this share of the triangles is left
  /// Errors are divided by depth^2, the squared distance of the kept vertex from `viewpoint`
  /// (metres); off: plain quadric errors.
  bool divide_by_depth2 = true;
  Eigen::Vector3f viewpoint = Eigen::Vector3f::Zero();
  float max_normal_turn_deg = 60.0f;  ///< no face may turn more than this in one collapse
  /// A border vertex collapses only onto a border neighbour along its border, and only when
  /// its two border edges turn by less than this (nearly parallel), so outlines keep shape.
  float max_border_turn_deg = 10.0f;
  float sharp_edge_deg = 60.0f;  ///< collapsing an edge whose two faces differ more is penalised
  float min_angle_deg = 13.0f;   ///< a collapse leaving a smaller inner angle is penalised
  float penalty = 10.0f;         ///< the factor of both penalties
  /// How a pass takes its collapses. On: collapses of which no two share a vertex of their
  /// closed neighbourhoods (u and its ring), chosen cheapest first among the pass's candidates,
  /// all evaluated and then applied in parallel (walk_chunk does not matter): more passes, about
  /// 1.3 x the instructions of the walk, closer to the input (kurt3d and the synthetic room,
  /// mean and p95 distance 1-3 % less). Off: the walk below, one collapse at a time, cheapest
  /// first, each evaluated on the mesh its earlier collapses left. The output depends on it,
  /// never on the thread count.
  bool independent_collapses = false;
  /// Without independent_collapses, a pass's walk evaluates its candidates (and again those next to
  /// earlier collapses) in chunks of this many, in parallel at each chunk's start (again serially
  /// only where the chunk's earlier collapses changed them): a single mesh scales with threads. 0 =
  /// one at a time, serially: fewer evaluations and no waits, for callers that keep every core busy
  /// with other work (frames in flight). The output depends on it, never on the thread count.
  std::size_t walk_chunk = 256;
  /// Record every collapse, in the order applied, in QemReport::collapse_sequence (for
  /// progressive meshes: replayed in reverse they are the vertex splits).
  bool record_collapses = false;
  /// Per input vertex, nonzero: locked, never removed (never the u of a collapse; other vertices
  /// may still collapse onto it, and it keeps its position as every kept vertex does). Empty: none
  /// locked; otherwise one entry per vertex (else qem_decimate() throws Error). Locking every
  /// vertex of a border keeps that border's edges as they are (progressive tiles' seams).
  std::vector<std::uint8_t> locked;
};

struct QemReport {
  std::size_t collapses = 0;
  std::size_t passes = 0;
  // Candidate collapses refused (every pass counts its own):
  std::size_t rejected_topology = 0;  ///< would make the mesh non-manifold
  std::size_t rejected_normal = 0;    ///< would turn or degenerate a face
  std::size_t rejected_border = 0;    ///< would move a border off itself
  std::size_t rejected_feature = 0;   ///< would move a corner or a feature vertex off its line
  /// With QemConfig::record_collapses: each collapse u -> v as {u, v} (input vertex numbers),
  /// in the order applied.
  std::vector<std::array<std::uint32_t, 2>> collapse_sequence;
};

/// Decimates `mesh` by half-edge collapses u -> v (v keeps its position) in passes: each pass
/// bounds every vertex's cheapest collapse from below by its plain quadric cost (Q_u + Q_v)(v),
/// in parallel and only for vertices next to a change, sorts the bounds and takes collapses
/// cheapest first up to 2.5 x the bound of the collapse that would reach the target, each
/// evaluated fully (the checks above, the penalties, the link condition) and taken if it stays
/// within that limit. With independent_collapses, every candidate within the limit is evaluated
/// in parallel on the mesh as the pass starts, and those whose closed neighbourhoods no cheaper
/// taken one touches are applied together, in parallel; else the walk evaluates each on the mesh
/// as it is then, unless an evaluation is still current (in parallel chunks: walk_chunk). Passes
/// repeat until target_ratio of the triangles remain or no valid collapse is left. Vertices whose
/// faces do not form one fan or several border fans (a non-manifold edge, a face repeating a
/// corner), and their neighbours, are never removed. Output vertices are a subset of the input
/// vertices (same positions, same order, normals and colours kept); triangles stay consistently
/// oriented and manifold where the input was, listed from their smallest vertex's neighbour ring
/// (the input's as given when nothing collapsed). Deterministic: the same output for any thread
/// count. About O(T x valence^2) per pass, a handful of passes (a few dozen with
/// independent_collapses, each over fewer vertices). Throws Error for a corner that indexes no
/// vertex.
TriangleMesh qem_decimate(const TriangleMesh& mesh, const QemConfig& config = {},
                          QemReport* report = nullptr);

/// The same, keeping the sharp edges `feature_edges` ({a, b} vertex pairs of `mesh`, any order;
/// nodes/optimize/features.h finds them): a vertex with three or more of them (a corner) never
/// moves; one with one (a loose end: noise, closed CAD lines have none) moves only onto that
/// neighbour, shortening its line; one with two (on a feature line) collapses only onto one of
/// those two neighbours (the line then runs through the kept vertex; its feature quadrics
/// price a bend); every feature edge adds the planes through it perpendicular to its
/// faces, weighted by penalty x its length^2, to its ends' quadrics (as boundary constraints
/// are in Garland & Heckbert), so the cost counts leaving the line. Feature edges of the output
/// are the input's, or chords of a feature line. An empty list: as above, same output.
TriangleMesh qem_decimate(const TriangleMesh& mesh,
                          const std::vector<std::array<std::uint32_t, 2>>& feature_edges,
                          const QemConfig& config, QemReport* report = nullptr);

}  // namespace meshflow
