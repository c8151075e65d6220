#pragma once
// A large scanned scene with analytic truth, generated in a streaming way: rolling terrain with
// box buildings on blocks between streets, sampled uniformly over the visible surface (terrain
// outside the footprints, walls above the ground, roofs) with exact outward normals. The input of
// the out-of-core benchmarks and tests (tens of millions of points without a download).

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "nodes/synthetic/shapes.h"
#include "runtime/point_cloud.h"

namespace meshflow::synthetic {

struct CitySceneConfig {
  float size = 300.0f;     ///< side of the square site, metres (centred on the origin)
  float block = 50.0f;     ///< city block pitch, metres (a building per block, streets between)
  float relief = 4.0f;     ///< terrain height amplitude, metres
  std::uint32_t seed = 1;  ///< building sizes and sample positions
};

/// The scene: terrain z = terrain_height(x, y) and the buildings (boxes whose bottom is buried
/// below the lowest terrain point of their footprint).
class CityScene {
 public:
  /// Lays out the blocks and buildings of `config` (throws meshflow::Error for a non-positive
  /// size or block). O(blocks).
  explicit CityScene(const CitySceneConfig& config);

  /// Terrain height (metres) at (x, y): a sum of a few long-wavelength sines. O(1).
  float terrain_height(float x, float y) const;
  /// Unit upward normal of the terrain at (x, y). O(1).
  Eigen::Vector3f terrain_normal(float x, float y) const;
  /// Unsigned distance (metres) from p to the visible surface: the terrain (to first order in
  /// its slope) or a building's walls and roof, whichever is nearer. O(buildings).
  float surface_distance(const Eigen::Vector3f& p) const;
  /// Visible surface area, m^2 (terrain outside footprints, walls above ground, roofs). Exact
  /// to the precision of the per-wall quadrature; computed once in the constructor.
  double area() const { return area_; }

  /// The buildings, one per block, row by row.
  const std::vector<Box>& buildings() const { return buildings_; }
  /// The configuration the scene was made with.
  const CitySceneConfig& config() const { return config_; }
  /// Axis-aligned bounds of the surface, metres.
  Eigen::AlignedBox3f bounds() const;

  /// Draws `points` samples uniformly over the visible surface with their outward normals (and
  /// Gaussian noise of `noise_sigma` metres along the normal), handing them to `sink` in
  /// batches of spatially nearby points (one patch of the surface at a time), in an order and
  /// with values that depend only on the config, `points` and `noise_sigma`. Memory is one
  /// batch (about a million points at most). Exactly `points` samples in all.
  void sample(std::uint64_t points, float noise_sigma,
              const std::function<void(const PointCloud& batch)>& sink) const;

 private:
  // One piece of visible surface sampled as a unit: a terrain tile, a building's wall or roof.
  struct Patch {
    enum Kind { kTerrain, kWall, kRoof } kind;
    int building = -1;  // walls and roofs
    int side = 0;       // walls: 0..3 (-x, +x, -y, +y)
    Eigen::Vector2f lo, hi;
    double area = 0.0;
  };
  bool in_footprint(float x, float y) const;
  double wall_area(int building, int side) const;
  void sample_patch(const Patch& patch, std::uint64_t index, std::uint64_t count, float noise,
                    PointCloud& out) const;

  CitySceneConfig config_;
  std::vector<Box> buildings_;
  std::vector<Patch> patches_;
  double area_ = 0.0;
};

}  // namespace meshflow::synthetic
