#pragma once
// The close stage (--close): a watertight surface from a scan with unseen parts. Between the
// distance and extract stages, the signed distance of the corners without data (the unseen
// undersides, holes, the inside and outside away from the data) is filled by volumetric
// diffusion (volume_diffusion.h) over a dense lattice of the grid's corners around the data;
// corners with data keep their distances exactly, so the surface where there is data is the one
// the open reconstruction extracts. Where the cloud knows its sensor, corners its lines of sight
// crossed before reaching their points are seen empty: held outside, never filled.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>

#include "nodes/close/volume_diffusion.h"
#include "runtime/distance_field.h"
#include "runtime/point_cloud.h"
#include "runtime/sparse_grid.h"

namespace meshflow {

struct CloseConfig {
  bool enabled = false;  ///< the pipeline's close stage runs only when set (--close)
  /// The lattice reaches this many voxels beyond the grid's corners; its faces are held outside
  /// (at +margin_voxels voxels), so every object ends up enclosed.
  float margin_voxels = 3.0f;
  /// A line of sight marks the corners it passes as seen empty up to this many voxels before
  /// its point (the noise and the distance band stay data's).
  float free_space_stop_voxels = 2.0f;
  /// Lattices with more corners are refused (memory: 5 bytes per corner); a larger voxel, or
  /// crop, brings a scene under it.
  std::size_t max_lattice_corners = std::size_t{1} << 26;
  DiffusionConfig diffusion;
};

/// What close_distance_field() did.
struct CloseReport {
  bool ran = false;
  Eigen::Vector3i lattice = Eigen::Vector3i::Zero();  ///< corners per axis
  int levels = 0;                                     ///< resolution levels of the solve
  std::size_t observed = 0;     ///< corners with data, held at their distances
  std::size_t seen_empty = 0;   ///< corners on lines of sight, held outside
  std::size_t filled = 0;       ///< corners whose distance came from the diffusion
  std::size_t cells_added = 0;  ///< cells the closed surface crosses that the grid lacked
};

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
/// a watertight mesh. Throws meshflow::Error("close", ...) when the lattice would exceed
/// config.max_lattice_corners. Parallel (planes of the lattice, points, cells); the output does
/// not depend on the thread count. O(lattice x sweeps + points x range / voxel).
ClosedDistance close_distance_field(const SparseGrid& grid, const DistanceField& field,
                                    const PointCloud& cloud, const CloseConfig& config = {},
                                    CloseReport* report = nullptr);

}  // namespace meshflow
