#pragma once
// The close stage (--close): a watertight surface from a scan with unseen parts. Between the
// distance and extract stages, the signed distance of the corners without data (the unseen
// undersides, holes, the inside and outside away from the data) is filled over a lattice of the
// grid's corners around the data, by default from the diffused gradient of the observed
// distances (below; volume_diffusion.h's solver); corners with data keep their distances
// exactly, so the surface where there is data is the one the open reconstruction extracts. A
// lattice whose diffusion or indicator fill is inside on the data's box (the fill would go on
// past the lattice) grows on that side by a quarter of its extent, twice at most, and is solved
// again. Where the cloud knows its sensor, corners its lines of sight crossed before reaching
// their points are seen empty: held outside, never filled.
//
// A lattice of up to max_dense_corners is solved at once. A larger one (a building, a street)
// is solved in two passes: a coarse lattice (every 2^k-th corner, as few as fit the limit)
// over the whole box, then cubic tiles of tile_cells cells solved one by one at full
// resolution, each holding its faces at the coarse solution: neighbouring tiles share their
// face values, so the surface is crack-free across tiles; tiles without data whose coarse
// values are all outside are skipped (nothing crosses them). Memory stays that of one lattice
// of max_dense_corners plus a tile per thread, whatever the scene's size.
//
// A whole lattice of a cloud's distances has three fills (CloseConfig::fill). The gradient
// fill, the default (gradient_fill.h): the observed distance's gradient diffused, the distance
// its potential, so the surface goes on across unseen parts the way it was heading (a sphere's
// unseen cap curves on, a box's unseen bottom closes nearly flat near the data's box), with the
// corners on lattice lines through observed tunnels (through_lines.h) held outside like lines
// of sight, so a through-hole seen from above stays open where its lower part was unseen. Its
// lattice grows once, before it solves, on the sides where the observed surface turns to close
// past the data's box (a sphere's unseen cap, a tube's underside: gradient_fill_reach(), the
// depth at which the surface's fitted turn would face that side; grown by
// gradient_reach_fraction of it), and never after (a box's walls do not turn: its faces stay
// near, which closes its unseen bottom nearly flat). Diffusion of the distance itself (above): a
// harmonic fill stays between its held values, so it closes a box's unseen bottom as a deep dome
// (5x the gradient fill's filled error on the tests' box and chamfered cube). The indicator fill:
// the observed surface's inside indicator spread as a double layer (a Poisson solve, the field
// Poisson surface reconstruction solves for: an unseen box bottom closes flat at its rim, a
// sphere's cap too flat), tunnels kept open as the gradient fill's. CloseFill::automatic validates
// the three without ground truth: the observed corners near the rim of the observed surface (where
// it goes on into unobserved space) are held out and each fill predicts them from the rest.
// Experimental: that rim error does not rank the fills as their filled-region error does (at a
// sharp rim, a box's, diffusion and the indicator predict the held-out walls better and fill
// far worse; tests/graph/test_scanned_objects.cpp prints both), so automatic keeps the gradient
// fill unless another's rim error is below half of its own (the gradient fill on all 12 test
// scans, whose filled error is the lowest of the three on each); it costs three more solves.
// Large (tiled) lattices and fused maps (no points) keep diffusion.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>

#include "nodes/close/volume_diffusion.h"
#include "runtime/distance_field.h"
#include "runtime/point_cloud.h"
#include "runtime/sparse_grid.h"

namespace meshflow {

/// The fill of a whole lattice of a cloud's distances (file comment).
enum class CloseFill : std::uint8_t {
  automatic,  ///< gradient, unless diffusion or the indicator predicts held-out observed corners
              ///< far better (file comment)
  diffusion,  ///< volumetric diffusion of the distance
  indicator,  ///< the observed surface's indicator as a double layer, observed tunnels kept open
  gradient,   ///< the diffused gradient's potential, observed tunnels kept open (the default)
};

struct CloseConfig {
  bool enabled = false;  ///< the pipeline's close stage runs only when set (--close)
  /// The lattice reaches this many voxels beyond the grid's corners (the gradient fill's farther
  /// where the surface turns to close: gradient_reach_fraction); its faces are held outside (at
  /// +margin_voxels voxels; the gradient fill's gradient_face_voxels further out), so every
  /// object ends up enclosed.
  float margin_voxels = 3.0f;
  /// The gradient fill holds a whole lattice's faces this many voxels further outside than
  /// margin_voxels (default 2: at +5 voxels, 3 voxels beyond the data's box): the potential then
  /// rises more steeply near the faces, and a fill carried on past the data (the top's field
  /// down through a box's inside) turns back sooner. Measured (the 12 test scans' filled error,
  /// before the room below): 0 / 1 / 2 / 3 gave the box 12.5 / 6.4 / 5.4 / 9.2e-3, the chamfered
  /// cube 16.2 / 10.0 / 4.9 / 5.4, the box with a hole 9.4 / 10.6 / 13.2 / 15.9.
  float gradient_face_voxels = 2.0f;
  /// The gradient fill's lattice grows past the data's box, before it solves, by this fraction
  /// of gradient_fill_reach()'s depth on each side where the observed surface turns to close
  /// within the data's length (0: never grows). Default 0.5: the potential overshoots a cap
  /// whose faces are far; on the sphere scan 0.35 / 0.5 / 0.6 / 0.75 / 1 gave filled errors
  /// 5.2 / 3.3 / 4.0 / 8.0 / 15e-3 (13.9 without), on the torus 0.5 gave 1.8 / 2.4 (5.1 / 3.5).
  float gradient_reach_fraction = 0.5f;
  /// A line of sight marks the corners it passes as seen empty up to this many voxels before
  /// its point (the noise and the distance band stay data's).
  float free_space_stop_voxels = 2.0f;
  /// A lattice of up to this many corners is solved at once; a larger one as a coarse lattice
  /// of at most this many corners plus tiles. Memory of a lattice: about 6.7 bytes a corner
  /// (value 4, held flag 1, sight mark 1, coarser levels 5/7), 7.7 when flat
  /// (volume_diffusion.h), so 225-260 MB at the default.
  std::size_t max_dense_corners = std::size_t{1} << 25;
  /// Cells along each side of a tile of a large lattice (its faces are held at the coarse
  /// solution; larger tiles follow the fine data farther, at 6.7 bytes a corner per thread).
  int tile_cells = 128;
  /// How a whole lattice of a cloud's distances is filled (file comment): the gradient's
  /// potential, diffusion, the indicator, or one of the three chosen per lattice by
  /// self-validation (automatic, experimental). The gradient fill takes about 10 bytes a corner
  /// more than diffusion, the indicator's solve about 23 (set max_dense_corners to 2^23 for
  /// about 190 MB). Large lattices and fused maps keep diffusion whatever this says.
  CloseFill fill = CloseFill::gradient;
  /// Automatic fill: observed corners within this many lattice steps of the observed surface's
  /// rim are held out and predicted by both fills.
  int validation_band = 3;
  DiffusionConfig diffusion;
};

/// What close_distance_field() did.
struct CloseReport {
  bool ran = false;
  Eigen::Vector3i lattice = Eigen::Vector3i::Zero();  ///< corners per axis
  int levels = 0;                                     ///< resolution levels of the (finest) solve
  int coarse_step = 1;         ///< > 1: a tiled solve over a coarse lattice of every n-th corner
  std::size_t tiles = 0;       ///< lattices solved at full resolution (1: the whole one at once)
  std::size_t observed = 0;    ///< corners with data, held at their distances
  std::size_t seen_empty = 0;  ///< corners on lines of sight, held outside
  /// Corners on lines through observed tunnels (through_lines.h), held outside.
  std::size_t through = 0;
  std::size_t filled = 0;       ///< corners whose distance came from the diffusion
  std::size_t cells_added = 0;  ///< cells the closed surface crosses that the grid lacked
  /// The lattice grew beyond the margin: room for the gradient fill where the surface turns to
  /// close, or a diffusion or indicator fill that reached its faces.
  bool grown = false;
  bool indicator = false;  ///< the lattice was filled from the indicator
  /// How the (whole) lattice was filled: config.fill, automatic's choice, or diffusion (tiles,
  /// fused maps).
  CloseFill fill = CloseFill::diffusion;
  /// Automatic fill: observed corners held out near the surface's rim (0: no validation ran),
  /// and each fill's mean error predicting their distances, in voxels (clamped at 2 a corner):
  /// the gradient fill's, diffusion's and the indicator's.
  std::size_t held_out = 0;
  float held_out_error_gradient = 0.0f;
  float held_out_error_diffusion = 0.0f;
  float held_out_error_indicator = 0.0f;
};

/// The fill's name as --json and the report print it: "gradient", "diffusion", "indicator" or
/// "automatic". Thread-safe; O(1).
const char* close_fill_name(CloseFill fill);

/// The grid and distances the extract stage meshes into a closed surface.
struct ClosedDistance {
  SparseGrid grid;
  DistanceField distance;
};

/// `grid` (from voxelize) with the cells the filled surface crosses added, and a distance
/// field valid at every corner: the original value where `field` is valid, else the diffused
/// one. Positive is outside (the side the normals face, as the distance stage signs it); the
/// lattice's faces are held outside. Lines of sight from cloud.sensor_origin to each of
/// cloud.positions mark seen-empty corners when cloud.has_sensor_origin. The zero set of the
/// result is closed and bounds the negative region; marching cubes over the returned grid give
/// a watertight mesh. Any lattice size (see the file comment for large ones). Parallel
/// (tiles, planes of a lattice, points, cells); the output does not depend on the thread count.
/// Time O(lattice x sweeps + points x range / voxel) for a dense lattice; a tiled one costs
/// the coarse lattice plus O(points) per tile solved (its lines of sight are clipped to it).
ClosedDistance close_distance_field(const SparseGrid& grid, const DistanceField& field,
                                    const PointCloud& cloud, const CloseConfig& config = {},
                                    CloseReport* report = nullptr);

}  // namespace meshflow
