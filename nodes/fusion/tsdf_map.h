#pragma once
// The map of a TSDF fusion (voxblox's layer): a sparse, block-hashed truncated signed distance
// field. Space is divided into blocks of 8 x 8 x 8 voxels, allocated only where a frame's
// truncation band passes; each voxel keeps a distance, a weight and a colour. The map knows
// nothing of frames: an integrator (tsdf_volume.h) writes it, the mesher, the map file and the
// samplers read it.

#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include "runtime/point_cloud.h"
#include "runtime/voxel_key.h"

namespace meshflow {

constexpr int kTsdfBlockSide = 8;
constexpr int kTsdfBlockVoxels = kTsdfBlockSide * kTsdfBlockSide * kTsdfBlockSide;
/// The largest |block coordinate| of a volume: the mesher packs the global index of every voxel
/// of a block and of its +1 neighbours into a VoxelKey, so (|b| + 2) x 8 must stay packable
/// (+-32 765 blocks: +-2.6 km at 1 cm voxels, +-13 km at 5 cm).
constexpr std::int32_t kMaxTsdfBlockIndex = kMaxCellIndex / kTsdfBlockSide - 2;

/// True when a block with these coordinates can be stored and meshed.
inline bool tsdf_block_in_range(const Eigen::Vector3i& block_coords) {
  // Compared from both sides: abs() of INT_MIN (a corrupt map file) would overflow.
  return (block_coords.array() >= -kMaxTsdfBlockIndex).all() &&
         (block_coords.array() <= kMaxTsdfBlockIndex).all();
}

/// The block holding voxel (i, j, k): floor division by 8, for negative indices too.
inline Eigen::Vector3i tsdf_block_of_voxel(const Eigen::Vector3i& voxel) {
  return {voxel.x() >> 3, voxel.y() >> 3, voxel.z() >> 3};
}

enum class TsdfWeighting {
  kConstant,      ///< every observation weighs 1
  kInverseDepth,  ///< weight 1 / depth^2 (metres): near measurements count more (noise ~ depth^2)
};

/// How a frame's measurements reach the voxels.
enum class TsdfIntegrator {
  /// Every voxel of each block the band touches is projected into the image and takes the
  /// pixel it lands on (KinectFusion's, Open3D's): parallel over blocks.
  kProjective,
  /// Each pixel's ray walks the voxels of its band (truncation in front, band behind) and
  /// updates them with the distance along the ray; consecutive pixels of a row whose points
  /// fall in one voxel merge into one ray weighing their count (voxblox's merged-ray
  /// integrator). Updates only voxels near measured rays; parallel over blocks, rays applied in
  /// pixel order.
  kAlongRay,
};

struct TsdfConfig {
  float voxel_size = 0.01f;        ///< metres
  float truncation_voxels = 4.0f;  ///< truncation distance in voxels (in front of the surface)
  /// The band behind a measured surface that a frame updates, along the ray, in voxels at least,
  /// and to kBehindNoiseMultiple x the frame's estimated depth noise (noise_per_depth2 x depth^2).
  /// Per pixel it widens to one voxel across the surface (divided by the cosine between the ray
  /// and the surface normal, from the depth two pixels either side on the same surface, within a
  /// 6 % jump, up to 76 degrees, assumed at silhouettes), never past the truncation; projective
  /// integration lets the widening reach only voxels no frame has observed (the far wall of a
  /// narrow hole stays as its own views saw it). A short band keeps the far side of thin walls
  /// and faces beside sharp edges from being overwritten by views of the near side (a 2 cm plate
  /// at 1 cm: 5x more accurate, 7x more complete than truncation_voxels, Open3D's symmetric band).
  float behind_voxels = 2.0f;
  TsdfWeighting weighting = TsdfWeighting::kConstant;
  float max_weight = 256.0f;  ///< accumulated weight is capped here (a slowly moving average)
  bool fuse_color = true;     ///< average the frame's colour into the voxels when it has one
  TsdfIntegrator integrator = TsdfIntegrator::kProjective;
  /// Projective integration: a voxel reads the depth at its exact projection, its nearest
  /// pixel's depth corrected by the depth slope there (central differences to neighbours on the
  /// same surface: within 6 pixel footprints, 6 depth / fx, of its depth; 0 across depth
  /// edges). false: the nearest pixel's depth as it is (KinectFusion's and Open3D's rule, off
  /// by up to half a pixel's depth step on a slanted surface: the sphere orbit fuses 1.6x less
  /// accurately).
  bool subpixel_depth = true;
  /// Free-space carving: after its band, a frame also visits the existing blocks it did not
  /// touch that hold surface (an observed voxel at distance <= 0), and a voxel there inside the
  /// image, not already at +truncation, takes +truncation, as a projective update gives the free
  /// voxels of a touched block, when every pixel its cell can project to (a pixel wider each
  /// side) is measured and lies more than a truncation behind it. Surface seen once and then seen
  /// through (a person who walked by, flying pixels, a mis-registered frame) leaves the map;
  /// surface seen n times needs frames seeing through it in proportion to n. Allocates no block, so
  /// memory stays bounded by the surface band; unmeasured pixels and depth edges (a nearer object's
  /// outline) carve nothing. Costs a min/max depth pyramid and one projected bounding sphere per
  /// untouched block per frame. Caveat: structure the sensor cannot see (thin wires, glass) is
  /// carved by frames that see past it.
  bool carve_free_space = true;
  /// integrate() refuses a frame whose new blocks would take memory_bytes() past this (bytes;
  /// 0 = no limit): the map stays as it was and the frame's error names the limit.
  std::size_t max_memory_bytes = 0;
  /// integrate() refuses a frame that would add more blocks than this (0 = no limit), leaving
  /// the map unchanged: a pose that jumps by kilometres or depth in the wrong unit. A 640 x 480
  /// frame adds at most a few tens of thousands at 4 mm voxels; 250 000 blocks are 1.5 GB.
  std::size_t max_new_blocks_per_frame = 250000;

  /// Truncation distance in metres.
  float truncation() const { return truncation_voxels * voxel_size; }
};

/// One voxel: the signed distance to the surface along the camera ray (metres, clipped to
/// +-truncation; positive in front of the surface), its accumulated weight (0 = never observed)
/// and its colour.
struct TsdfVoxel {
  float distance = 0.0f;
  float weight = 0.0f;
  Rgb8 color;
};

/// Block (bx, by, bz) holds voxels (8 bx + x, 8 by + y, 8 bz + z) for x, y, z in 0..7; voxel
/// (i, j, k) samples the point (i, j, k) * voxel_size. Voxel (x, y, z) is voxels[x + 8 y + 64 z].
struct TsdfBlock {
  Eigen::Vector3i coords;
  std::array<TsdfVoxel, kTsdfBlockVoxels> voxels;
  std::uint64_t modified = 0;  ///< the volume's generation when a voxel last changed
};

/// Blocks of voxels in a hash index, with the settings that define them (voxel size,
/// truncation, maximum weight, weighting, colour: what a map file records). Not thread-safe
/// against a writer; any number of readers at once. Move-only.
class TsdfMap {
 public:
  /// Throws meshflow::Error on a voxel size outside (0, 1000] metres, or a non-positive or
  /// non-finite truncation or maximum weight. `config`'s integration settings (behind_voxels,
  /// integrator, carving, limits) are kept as given but are the integrator's to use.
  explicit TsdfMap(const TsdfConfig& config = {});
  /// Takes `other`'s blocks and settings (other is left empty). O(1).
  TsdfMap(TsdfMap&& other) = default;
  /// Takes `other`'s blocks and settings (other is left empty). O(1).
  TsdfMap& operator=(TsdfMap&& other) = default;
  TsdfMap(const TsdfMap&) = delete;
  TsdfMap& operator=(const TsdfMap&) = delete;
  ~TsdfMap() = default;

  /// The settings the map was made with.
  const TsdfConfig& config() const { return config_; }
  /// Blocks allocated so far.
  std::size_t block_count() const { return blocks_.size(); }
  /// Bytes held by the blocks and their index.
  std::size_t memory_bytes() const { return blocks_.size() * kBytesPerBlock; }
  /// Bytes one more block adds to memory_bytes().
  static constexpr std::size_t kBytesPerBlock =
      sizeof(TsdfBlock) + sizeof(VoxelKey) + sizeof(std::uint32_t) + 3 * sizeof(void*);
  /// Incremented by every change (begin_change()); blocks record it when they change.
  std::uint64_t generation() const { return generation_; }

  /// Block i, 0 <= i < block_count(), numbered in allocation order.
  const TsdfBlock& block(std::size_t i) const { return *blocks_[i]; }
  /// The block with these block coordinates, or nullptr if it was never allocated. O(1).
  const TsdfBlock* find(const Eigen::Vector3i& block_coords) const;
  /// Block indices sorted by block key (z, then y, then x): a deterministic iteration order.
  /// O(blocks).
  std::vector<std::uint32_t> blocks_in_key_order() const;

  /// Adds a block with the given voxels (used by the map reader). Throws meshflow::Error if the
  /// block exists already or its coordinates are out of range (tsdf_block_in_range()).
  void insert_block(const Eigen::Vector3i& coords,
                    const std::array<TsdfVoxel, kTsdfBlockVoxels>& voxels);

  // --- for integrators -----------------------------------------------------------------------

  /// Block i for writing (one writer per block at a time; mark it with the generation of
  /// begin_change() when a voxel changes).
  TsdfBlock& block_for_update(std::size_t i) { return *blocks_[i]; }
  /// Starts a change (one frame's): returns the new generation() for the blocks it modifies.
  std::uint64_t begin_change() { return ++generation_; }
  /// The block numbers of `keys` (pack_key() of block coordinates, sorted, unique) into
  /// `blocks`, allocating the missing ones (zeroed in parallel, numbered in key order: the
  /// result does not depend on the number of threads); adds their count to `allocated`. Throws
  /// meshflow::Error, leaving the map unchanged, when more than `max_new_blocks` would be added
  /// or memory_bytes() would pass `max_memory_bytes` (0: no limit for either). O(keys).
  void find_or_allocate(const std::vector<VoxelKey>& keys, std::size_t max_new_blocks,
                        std::size_t max_memory_bytes, std::size_t& allocated,
                        std::vector<std::uint32_t>& blocks);

 private:
  // Appends blocks with these coordinates (zeroed in parallel, in one slab), numbered in order;
  // returns the first one's number.
  std::uint32_t allocate(const std::vector<Eigen::Vector3i>& coords);

  TsdfConfig config_;
  std::vector<std::unique_ptr<unsigned char[]>> slabs_;  // the blocks' storage, one per batch
  std::vector<TsdfBlock*> blocks_;                       // in allocation order, into the slabs
  std::unordered_map<VoxelKey, std::uint32_t> index_;    // pack_key(block coords) -> block
  std::uint64_t generation_ = 0;
};

}  // namespace meshflow
