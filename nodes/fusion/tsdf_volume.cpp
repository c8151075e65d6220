#include "nodes/fusion/tsdf_volume.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <new>
#include <string>
#include <type_traits>

#include "nodes/depth/depth_noise.h"
#include "nodes/fusion/tsdf_band.h"
#include "nodes/fusion/tsdf_projective_update.h"
#include "runtime/error.h"
#include "runtime/parallel.h"
#include "runtime/radix_sort.h"
#include "runtime/simd.h"

namespace meshflow {
namespace {

// The keys a row emitted lately, one slot per block coordinates modulo 4 on each axis (direct
// mapped): neighbouring pixels touch the same handful of adjacent blocks, which never share a
// slot, so one comparison drops almost every repeat before the global sort (a repeat that gets
// through is removed there).
class RecentKeys {
 public:
  bool seen_or_add(const Eigen::Vector3i& block, VoxelKey key) {
    VoxelKey& slot = keys_[static_cast<std::size_t>((block.x() & 3) | (block.y() & 3) << 2 |
                                                    (block.z() & 3) << 4)];
    if (slot == key) return true;
    slot = key;
    return false;
  }

 private:
  std::array<VoxelKey, 64> keys_ = [] {
    std::array<VoxelKey, 64> a;
    a.fill(~VoxelKey{0});  // never a packed key
    return a;
  }();
};

// What the blocks a frame touches depend on besides its pose.
struct BandGeometry {
  const PinholeIntrinsics& intrinsics;
  const TsdfConfig& config;
  const float* pixels;  ///< per pixel: depth, band behind it (metres; depth 0 = invalid)
};

using simd::Floats8;
using simd::Ints8;

// Eight consecutive pixels of a row: their depth (0 = invalid or past the row's end), the
// blocks lo..hi (per axis) of the box around each one's ray segment, and those whose box does
// not lie inside the previous pixel's, a valid one's (that pixel left the last box emitted
// around its own, so a box inside it adds nothing).
struct EightPixels {
  float ray[3] = {};            ///< the first pixel's world ray (voxel units); then the next's
  float previous_depth = 0.0f;  ///< of the pixel before the first (0: none or invalid)
  alignas(32) float depth[8] = {};
  alignas(32) std::int32_t lo[3][8] = {};  ///< on entry, lane 7: the previous pixel's box
  alignas(32) std::int32_t hi[3][8] = {};
  unsigned valid = 0;  ///< bit j: pixel j is valid
  unsigned open = 0;   ///< bit j: pixel j is valid and its box not inside the previous pixel's
};

// floor_to_int() lane by lane.
#define MESHFLOW_FLOOR_TO_INT8(x, out)                                                   \
  do {                                                                                   \
    const Floats8 c = (x) >= -kFloorLimit ? ((x) <= kFloorLimit ? (x) : limit) : -limit; \
    const Ints8 i = __builtin_convertvector(c, Ints8);                                   \
    (out) = i + (c < __builtin_convertvector(i, Floats8));                               \
  } while (false)

// The block boxes of the `n` <= 8 pixels whose (depth, band) start at `pixels`
// (touched_blocks_of_row()'s per-pixel arithmetic, each lane exactly the scalar operations:
// IEEE products and sums, no FMA contraction; lane j's ray is p.ray plus `step` added j times,
// one sum after another); lanes of invalid pixels are filled but meaningless. `origin`: the
// camera centre in voxel units. Advances p.ray past the eight pixels.
MESHFLOW_AVX2_CLONES void boxes_of_eight(const Eigen::Vector3f& origin, const Eigen::Vector3f& step,
                                         float truncation, const float* pixels, int n,
                                         EightPixels& p) {
  constexpr float kFloorLimit = 1073741824.0f;  // floor_to_int()'s 2^30
  const Floats8 limit = Floats8{} + kFloorLimit;
  float padded[16] = {};
  const float* source = pixels;
  if (n < 8) {
    for (int j = 0; j < 2 * n; ++j) padded[j] = pixels[j];
    source = padded;
  }
  Floats8 first, second;
  __builtin_memcpy(&first, source, sizeof first);
  __builtin_memcpy(&second, source + 8, sizeof second);
  const Floats8 d = __builtin_shufflevector(first, second, 0, 2, 4, 6, 8, 10, 12, 14);
  const Floats8 band = __builtin_shufflevector(first, second, 1, 3, 5, 7, 9, 11, 13, 15);
  const Floats8 ahead = d - truncation;
  const Floats8 near = ahead < 0.0f ? Floats8{} : ahead;  // std::max(d - truncation, 0)
  const Floats8 far = d + band;
  const Floats8 previous_d =
      __builtin_shufflevector(Floats8{} + p.previous_depth, d, 0, 8, 9, 10, 11, 12, 13, 14);
  Ints8 inside = previous_d > 0.0f;
  const Ints8 lane = {0, 1, 2, 3, 4, 5, 6, 7};
  for (int axis = 0; axis < 3; ++axis) {
    Floats8 ray = Floats8{} + p.ray[axis];
    for (int k = 1; k < 8; ++k) ray = lane >= k ? ray + step[axis] : ray;
    p.ray[axis] = ray[7] + step[axis];
    const Floats8 a = origin[axis] + ray * near, b = origin[axis] + ray * far;
    const Floats8 lo = b < a ? b : a, hi = a < b ? b : a;  // std::min, std::max
    Ints8 vlo, vhi;
    MESHFLOW_FLOOR_TO_INT8(lo, vlo);
    MESHFLOW_FLOOR_TO_INT8(hi, vhi);
    const Ints8 blo = vlo >> 3, bhi = (vhi + 1) >> 3;  // tsdf_block_of_voxel()
    Ints8 before_lo, before_hi;                        // the previous pixel's
    __builtin_memcpy(&before_lo, p.lo[axis], sizeof before_lo);
    __builtin_memcpy(&before_hi, p.hi[axis], sizeof before_hi);
    before_lo = __builtin_shufflevector(before_lo, blo, 7, 8, 9, 10, 11, 12, 13, 14);
    before_hi = __builtin_shufflevector(before_hi, bhi, 7, 8, 9, 10, 11, 12, 13, 14);
    inside &= (blo >= before_lo) & (bhi <= before_hi);
    __builtin_memcpy(p.lo[axis], &blo, sizeof blo);
    __builtin_memcpy(p.hi[axis], &bhi, sizeof bhi);
  }
  __builtin_memcpy(p.depth, &d, sizeof d);
  const Ints8 valid = d > 0.0f, open = valid & ~inside;
  p.valid = 0;
  p.open = 0;
  for (int j = 0; j < 8; ++j) {
    p.valid += static_cast<unsigned>(valid[j] & 1) << j;
    p.open += static_cast<unsigned>(open[j] & 1) << j;
  }
}

#undef MESHFLOW_FLOOR_TO_INT8

// Keys of the blocks whose voxels lie within the band of row v's valid pixels: for each pixel,
// every block overlapping the box around the ray segment from the truncation in front of the
// depth to its band behind it (band_pixels()). Keys inside the previous pixel's box or emitted
// recently are skipped; the caller sorts and dedupes the rest. The ray is advanced
// incrementally along the row (in voxel units); the boxes are found eight pixels at a time.
void touched_blocks_of_row(int width, int v, const BandGeometry& band,
                           const Eigen::Isometry3f& T_world_camera, std::vector<VoxelKey>& out,
                           std::size_t& pixels) {
  const PinholeIntrinsics& k = band.intrinsics;
  const float voxel = band.config.voxel_size, truncation = band.config.truncation();
  const float* row =
      band.pixels + 2 * static_cast<std::size_t>(v) * static_cast<std::size_t>(width);
  RecentKeys recent;
  Eigen::Vector3i last_lo(1, 1, 1), last_hi(0, 0, 0);  // an empty box
  const float inv_voxel = 1.0f / voxel;
  const Eigen::Matrix3f rotation = T_world_camera.linear() * inv_voxel;
  const Eigen::Vector3f origin = T_world_camera.translation() * inv_voxel;
  const float ry = (static_cast<float>(v) - k.cy) / k.fy;
  const Eigen::Vector3f ray_step = rotation.col(0) / k.fx;  // per pixel along u
  const Eigen::Vector3f ray = rotation * Eigen::Vector3f(-k.cx / k.fx, ry, 1.0f);  // at u = 0
  auto inside = [](const Eigen::Vector3i& p, const Eigen::Vector3i& lo, const Eigen::Vector3i& hi) {
    return p.x() >= lo.x() && p.y() >= lo.y() && p.z() >= lo.z() && p.x() <= hi.x() &&
           p.y() <= hi.y() && p.z() <= hi.z();
  };
  EightPixels eight;
  for (int axis = 0; axis < 3; ++axis) eight.ray[axis] = ray[axis];
  for (int u0 = 0; u0 < width; u0 += 8) {
    const int n = std::min(8, width - u0);
    eight.previous_depth = eight.depth[7];  // 0 before the first pixel
    boxes_of_eight(origin, ray_step, truncation, row + 2 * u0, n, eight);
    pixels += static_cast<std::size_t>(__builtin_popcount(eight.valid));
    for (unsigned open = eight.open; open != 0; open &= open - 1) {
      const int j = __builtin_ctz(open);
      const Eigen::Vector3i blo(eight.lo[0][j], eight.lo[1][j], eight.lo[2][j]);
      const Eigen::Vector3i bhi(eight.hi[0][j], eight.hi[1][j], eight.hi[2][j]);
      if (inside(blo, last_lo, last_hi) && inside(bhi, last_lo, last_hi)) continue;
      if (!tsdf_block_in_range(blo) || !tsdf_block_in_range(bhi)) {
        throw Error("tsdf", "pixel (" + std::to_string(u0 + j) + ", " + std::to_string(v) + ")",
                    "maps outside the volume's range (pose or depth far too large)");
      }
      for (int z = blo.z(); z <= bhi.z(); ++z)
        for (int y = blo.y(); y <= bhi.y(); ++y)
          for (int x = blo.x(); x <= bhi.x(); ++x) {
            const Eigen::Vector3i b(x, y, z);
            if (inside(b, last_lo, last_hi)) continue;
            const VoxelKey key = pack_key(b);
            if (!recent.seen_or_add(b, key)) out.push_back(key);
          }
      last_lo = blo;
      last_hi = bhi;
    }
  }
}

// Keys of the blocks within the band of the frame's valid pixels, sorted and unique, into
// `keys`: per row (in parallel, into `row_keys`, one buffer per row), then joined in row order;
// the buffers are kept across frames so that their capacity is reused. Adds the valid pixels to
// `pixels_used`.
void touched_block_keys(int width, int height, const BandGeometry& band,
                        const Eigen::Isometry3f& T_world_camera,
                        std::vector<std::vector<VoxelKey>>& row_keys, std::vector<VoxelKey>& keys,
                        std::size_t& pixels_used) {
  const auto rows = static_cast<std::size_t>(height);
  row_keys.resize(rows);
  std::vector<std::size_t> row_pixels(rows, 0);
  tbb::parallel_for(0, height, [&](int v) {
    const auto r = static_cast<std::size_t>(v);
    row_keys[r].clear();
    touched_blocks_of_row(width, v, band, T_world_camera, row_keys[r], row_pixels[r]);
  });
  for (std::size_t pixels : row_pixels) pixels_used += pixels;
  concatenate_parts(row_keys, keys);
  radix_sort_unique(keys);
}

}  // namespace

TsdfFrameIntegrator::TsdfFrameIntegrator(const TsdfConfig& config) : config_(config) {
  if (!(config.behind_voxels > 0.0f) || !std::isfinite(config.behind_voxels))
    throw Error("tsdf", "behind_voxels", "must be a positive number of voxels");
}

namespace {

// `config` with the settings `map` records (voxel size, truncation, weights, colour).
TsdfConfig with_settings_of(const TsdfMap& map, TsdfConfig config) {
  const TsdfConfig& m = map.config();
  config.voxel_size = m.voxel_size;
  config.truncation_voxels = m.truncation_voxels;
  config.max_weight = m.max_weight;
  config.weighting = m.weighting;
  config.fuse_color = m.fuse_color;
  return config;
}

}  // namespace

TsdfVolume::TsdfVolume(const TsdfConfig& config) : TsdfMap(config), integrator_(config) {}

TsdfVolume::TsdfVolume(TsdfMap map, const TsdfConfig& config)
    : TsdfMap(std::move(map)), integrator_(with_settings_of(*this, config)) {}

IntegrationStats TsdfFrameIntegrator::integrate(TsdfMap& map, const DepthFrame& frame) {
  if (map.config().voxel_size != config_.voxel_size ||
      map.config().truncation_voxels != config_.truncation_voxels) {
    throw Error("tsdf", "map",
                "a map of " + std::to_string(config_.voxel_size) +
                    " m voxels and a truncation of " + std::to_string(config_.truncation_voxels) +
                    " voxels, as the integrator's; it has " +
                    std::to_string(map.config().voxel_size) + " m and " +
                    std::to_string(map.config().truncation_voxels));
  }
  IntegrationStats stats;
  depth_in_metres(frame, depth_m_);  // checks the frame (intrinsics, pose)
  const Image& depth = depth_m_;
  stats.noise_per_depth2 = estimate_noise_per_depth2(depth);
  band_pixels(depth, frame.intrinsics, config_, stats.noise_per_depth2, band_pixels_);
  if (config_.integrator == TsdfIntegrator::kAlongRay) {
    integrate_along_rays(map, frame, depth, stats);  // fills touched_
  } else {
    const BandGeometry band{frame.intrinsics, config_, band_pixels_.data()};
    touched_block_keys(depth.cols(), depth.rows(), band, frame.T_world_camera, row_keys_, keys_,
                       stats.pixels_used);
    map.find_or_allocate(keys_, config_.max_new_blocks_per_frame, config_.max_memory_bytes,
                         stats.blocks_allocated, touched_);
    stats.voxels_updated = update_blocks(map, touched_, depth, frame, stats.noise_per_depth2);
  }
  stats.blocks_touched = touched_.size();
  if (config_.carve_free_space) carve_free_blocks(map, frame, depth, touched_, stats);
  return stats;
}

bool TsdfFrameIntegrator::fuses_color_of(const DepthFrame& frame, const Image& depth) const {
  return config_.fuse_color && !frame.color.empty() && frame.color.same_size(depth) &&
         frame.color.format() == PixelFormat::RGB8;
}

std::size_t TsdfFrameIntegrator::update_blocks(TsdfMap& map,
                                               const std::vector<std::uint32_t>& touched,
                                               const Image& depth, const DepthFrame& frame,
                                               float noise_per_depth2) {
  // One task per block; a voxel's new state depends only on its old state and the frame, so the
  // order of blocks does not matter.
  const std::uint64_t generation = map.begin_change();
  const bool color = fuses_color_of(frame, depth);
  if (config_.subpixel_depth)
    depth_slopes(band_pixels_, depth.cols(), depth.rows(), kSlopeFootprints / frame.intrinsics.fx,
                 depth_slopes_);
  const BlockUpdate update{band_pixels_.data(),
                           depth.cols(),
                           depth.rows(),
                           config_.subpixel_depth ? depth_slopes_.data() : nullptr,
                           color ? &frame.color : nullptr,
                           frame.intrinsics,
                           frame.T_world_camera.inverse(),
                           config_,
                           kBehindNoiseMultiple * noise_per_depth2};
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, touched.size()), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& range, std::size_t sum) {
        for (std::size_t t = range.begin(); t != range.end(); ++t) {
          TsdfBlock& block = map.block_for_update(touched[t]);
          const std::size_t updated = update_block(block, update);
          if (updated > 0) block.modified = generation;
          sum += updated;
        }
        return sum;
      },
      std::plus<>());
}

}  // namespace meshflow
