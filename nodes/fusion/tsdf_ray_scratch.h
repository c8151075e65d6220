#pragma once
// The along-ray integrator's rays and per-frame lists (tsdf_ray_integration.cpp);
// TsdfFrameIntegrator keeps a RayScratch across frames so that the lists' capacity is reused.
// Internal to nodes/fusion.

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "runtime/voxel_key.h"

namespace meshflow {

/// Pixels of a tile whose points fall in one voxel, as one ray.
struct MergedRay {
  Eigen::Vector3f point_sum = Eigen::Vector3f::Zero();  ///< world metres
  std::array<float, 3> color_sum{};                     ///< RGB, 0..255
  float weight = 0.0f;                                  ///< sum of observation weights
  float band = 0.0f;                                    ///< behind the point, metres (largest)
  float held = 0.0f;         ///< the pixels' largest noise allowance behind the point, metres
  std::uint32_t pixels = 0;  ///< merged pixels
  Eigen::Vector3i voxel;     ///< the voxel nearest its pixels' points
};

/// One voxel a ray's walk crosses within its band: what the ray blends into it.
struct RayVoxel {
  float distance;       ///< signed distance along the ray, metres, clipped to the truncation
  std::uint16_t index;  ///< the voxel in its block: x + 8 (y + 8 z)
  std::uint8_t held;    ///< 1 beyond the held band: updated only while unobserved (weight 0)
  std::uint8_t first;   ///< 1 on the first voxel of a ray's run in a block
};

/// The most voxels one ray's walk crosses in one block (a path through 8^3 cells that moves
/// one axis at a time, each axis one way).
constexpr std::size_t kMaxRunVoxels = 3 * 7 + 1;

/// A block a ray crosses, and the ray's voxels in it.
struct RayBlock {
  VoxelKey block;          ///< pack_key() of its coordinates
  std::uint32_t row, ray;  ///< the ray: its row of tiles, its place among the row's rays
  std::uint32_t first;     ///< its first voxel in the row's RayScratch::row_voxels
  std::uint32_t count;     ///< its voxels in the block
};

/// A ray's voxels in one block, as the block's update reads them.
struct RayRun {
  const RayVoxel* voxels;        ///< `count` voxels, in walk order (kMaxRunVoxels readable)
  const Eigen::Vector4f* blend;  ///< the ray's mean RGB x weight and weight
  std::uint32_t count;
};

/// A growable array of a trivially copyable T whose room past size() may be written before
/// it is counted (room(), then commit()): a loop writes every candidate and counts only those
/// it keeps, without a branch.
template <typename T>
class RayList {
 public:
  /// Entries counted so far. O(1).
  std::size_t size() const { return size_; }
  /// The first entry (size() of them, contiguous); null before the first room(). O(1).
  const T* data() const { return data_.get(); }
  /// Forgets the entries and keeps the room (no deallocation). O(1).
  void clear() { size_ = 0; }
  /// Room for n entries past size() (pointers from earlier calls are invalidated); returns
  /// where they begin. Amortised O(n).
  T* room(std::size_t n) {
    if (size_ + n > capacity_) grow(size_ + n);
    return data_.get() + size_;
  }
  /// Counts n more entries, written through room().
  void commit(std::size_t n) { size_ += n; }
  /// Entry i < size().
  T& operator[](std::size_t i) { return data_[i]; }

 private:
  void grow(std::size_t need) {
    const std::size_t capacity = std::max(need, 2 * capacity_);
    std::unique_ptr<T[]> bigger(new T[capacity]);
    std::copy(data_.get(), data_.get() + size_, bigger.get());
    data_ = std::move(bigger);
    capacity_ = capacity;
  }
  std::unique_ptr<T[]> data_;
  std::size_t size_ = 0, capacity_ = 0;
};

/// One frame's lists of the along-ray integration, cleared and refilled every frame.
struct RayScratch {
  std::vector<std::vector<MergedRay>> tile_row_rays;     ///< per row of 8 x 8 pixel tiles
  std::vector<std::vector<Eigen::Vector4f>> row_blends;  ///< per row: each ray's RGB x w, w
  /// Per row: its rays' walks (kMaxRunVoxels readable past the end).
  std::vector<RayList<RayVoxel>> row_voxels;
  std::vector<RayList<RayBlock>> row_pairs;  ///< (block, ray) per row of tiles
  std::vector<RayList<VoxelKey>> row_keys;   ///< per row of tiles: its blocks' keys
  std::vector<RayBlock> pairs;               ///< joined in ray order
  std::vector<std::uint32_t> pair_blocks;    ///< per pair: its block's position among the keys
  std::vector<RayRun> block_runs;   ///< the non-empty runs by block, each block's in ray order
  std::vector<std::size_t> starts;  ///< per block: its first entry in block_runs
};

}  // namespace meshflow
