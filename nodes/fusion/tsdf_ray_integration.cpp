// TsdfIntegrator::kAlongRay: each (merged) pixel ray walks the voxels of its band.
//
// Phases, each parallel: (1) per tile of 8 x 8 pixels, pixels whose points fall in one voxel
// merge into one ray; (2) each ray walks its segment through the voxel grid and lists the
// blocks it crosses; the blocks are found or allocated as for the projective integrator, and
// the (block, ray) pairs are bucketed by block (a stable counting sort: each block's rays stay
// in pixel order); (3) one task per block applies the rays crossing it in pixel order, so the
// map does not depend on the number of threads.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <functional>
#include <limits>
#include <string>

#include "nodes/fusion/tsdf_band.h"
#include "nodes/fusion/tsdf_ray_scratch.h"
#include "nodes/fusion/tsdf_ray_walk.h"
#include "nodes/fusion/tsdf_volume.h"
#include "runtime/error.h"
#include "runtime/parallel.h"
#include "runtime/radix_sort.h"
#include "runtime/simd.h"

namespace meshflow {
namespace {

RaySegment segment_of(const MergedRay& ray, const Eigen::Vector3f& camera, float inv_voxel,
                      float truncation) {
  RaySegment s;
  const Eigen::Vector3f point = ray.point_sum / static_cast<float>(ray.pixels);
  const Eigen::Vector3f to_point = point - camera;
  const float range = to_point.norm();
  const Eigen::Vector3f direction = to_point / range;
  const Eigen::Vector3f scaled = point * inv_voxel;
  const float band = ray.band * inv_voxel;
  const Eigen::Vector3f from = scaled - direction * (std::min(truncation, range) * inv_voxel);
  const Eigen::Vector3f to = scaled + direction * band;
  const Eigen::Vector3f span = to - from;
  s.from = Eigen::Vector4f(from.x(), from.y(), from.z(), 0.0f);
  s.to = Eigen::Vector4f(to.x(), to.y(), to.z(), 0.0f);
  s.span = Eigen::Vector4f(span.x(), span.y(), span.z(), 0.0f);
  s.point_band = Eigen::Vector4f(scaled.x(), scaled.y(), scaled.z(), band);
  s.direction_weight = Eigen::Vector4f(direction.x(), direction.y(), direction.z(), ray.weight);
  const float inv_pixels = 1.0f / static_cast<float>(ray.pixels);
  for (int c = 0; c < 3; ++c) s.color[c] = ray.color_sum[c] * inv_pixels * ray.weight;
  s.color[3] = 0.0f;
  return s;
}

// Pixels are merged in tiles of kTile x kTile: those whose points fall in one voxel become one
// ray (voxblox merges over the whole image; tiles keep it parallel and deterministic).
constexpr int kTile = 8;

// The rays of the tiles in tile row `tile_row` (tiles left to right, each tile's rays in the
// order of their first pixel), appended to `out`; adds the valid pixels to `pixels`.
MESHFLOW_AVX2_CLONES void rays_of_tile_row(int tile_row, const Image& depth,
                                           const float* band_pixels, const PinholeIntrinsics& k,
                                           const Eigen::Isometry3f& T_world_camera,
                                           const Image* color, TsdfWeighting weighting,
                                           float inv_voxel, std::vector<MergedRay>& out,
                                           std::size_t& pixels) {
  using ray_walk::Floats4;
  // The pose's columns: a point is ((c0 x + c1 y) + c2 z) + c3, as Eigen's product gives it.
  const Eigen::Matrix4f& m = T_world_camera.matrix();
  const Floats4 c0 = ray_walk::load4(m.data()), c1 = ray_walk::load4(m.data() + 4),
                c2 = ray_walk::load4(m.data() + 8), c3 = ray_walk::load4(m.data() + 12);
  // The tile's rays by voxel, in a table of twice a tile's pixels (short probes); a slot belongs
  // to the tile that stamped it. A tile's rays hold distinct voxels.
  struct Slot {
    Eigen::Vector3i voxel;
    std::uint32_t tile, ray;
  };
  constexpr std::uint32_t kSlots = 2 * kTile * kTile;
  std::array<Slot, kSlots> slots;
  for (Slot& slot : slots) slot.tile = 0;
  std::uint32_t tile = 0;
  const int width = depth.cols(), v0 = tile_row * kTile, v1 = std::min(depth.rows(), v0 + kTile);
  for (int u0 = 0; u0 < width; u0 += kTile) {
    ++tile;
    const int u1 = std::min(width, u0 + kTile);
    std::array<float, kTile> xs;  // (u - cx) / fx per column of the tile
    for (int u = u0; u < u1; ++u) xs[u - u0] = (static_cast<float>(u) - k.cx) / k.fx;
    for (int v = v0; v < v1; ++v) {
      const float* row =
          band_pixels + 2 * static_cast<std::size_t>(v) * static_cast<std::size_t>(width);
      const Rgb8* colors = color != nullptr ? color->ptr<Rgb8>(v) : nullptr;
      const float y = (static_cast<float>(v) - k.cy) / k.fy;
      for (int u = u0; u < u1; ++u) {
        const float d = row[2 * u];
        if (!(d > 0.0f)) continue;
        ++pixels;
        const Floats4 point = ((c0 * (xs[u - u0] * d) + c1 * (y * d)) + c2 * d) + c3;
        const ray_walk::Ints4 cell = ray_walk::floor4(point * inv_voxel + 0.5f);
        const Eigen::Vector3i voxel(cell[0], cell[1], cell[2]);
        std::uint32_t h = (static_cast<std::uint32_t>(cell[0]) * 0x9e3779b1u +
                           static_cast<std::uint32_t>(cell[1]) * 0x85ebca77u +
                           static_cast<std::uint32_t>(cell[2]) * 0xc2b2ae3du) >>
                          (32 - 7);
        static_assert(kSlots == 1u << 7, "the hash's bits");
        const auto other = [&](const Slot& slot) {
          return ((slot.voxel.x() ^ voxel.x()) | (slot.voxel.y() ^ voxel.y()) |
                  (slot.voxel.z() ^ voxel.z())) != 0;
        };
        while (slots[h].tile == tile && other(slots[h])) h = (h + 1) & (kSlots - 1);
        if (slots[h].tile != tile) {  // a new ray
          slots[h] = {voxel, tile, static_cast<std::uint32_t>(out.size())};
          out.emplace_back();
          out.back().voxel = voxel;
        }
        const std::size_t r = slots[h].ray;
        MergedRay& ray = out[r];
        ray.point_sum += Eigen::Vector3f(point[0], point[1], point[2]);
        ray.weight += observation_weight(weighting, d);
        ray.band = std::max(ray.band, row[2 * u + 1]);
        ++ray.pixels;
        if (colors != nullptr) {
          const Rgb8 c = colors[u];
          ray.color_sum[0] += c.r;
          ray.color_sum[1] += c.g;
          ray.color_sum[2] += c.b;
        }
      }
    }
  }
}

// A few keys a slice of rays met recently, each with a value, in slots picked by the key's hash:
// neighbouring rays cross the same few blocks, so most repeats hit.
class RecentKeyValues {
 public:
  // The value stored with `key`, or nullptr when it was not met recently.
  const std::uint32_t* find(VoxelKey key) const {
    const std::size_t s = slot(key);
    return keys_[s] == key ? &values_[s] : nullptr;
  }
  void put(VoxelKey key, std::uint32_t value) {
    const std::size_t s = slot(key);
    keys_[s] = key;
    values_[s] = value;
  }

 private:
  static constexpr int kSlotBits = 6;
  static std::size_t slot(VoxelKey key) {
    return static_cast<std::size_t>((key * 0x9e3779b97f4a7c15ull) >> (64 - kSlotBits));
  }
  std::array<VoxelKey, std::size_t{1} << kSlotBits> keys_ = [] {
    std::array<VoxelKey, std::size_t{1} << kSlotBits> a;
    a.fill(~VoxelKey{0});  // never a packed key
    return a;
  }();
  std::array<std::uint32_t, std::size_t{1} << kSlotBits> values_{};
};

[[noreturn, gnu::cold, gnu::noinline]] void throw_out_of_range(std::size_t ray) {
  throw Error("tsdf", "ray " + std::to_string(ray),
              "reaches outside the volume's range (pose or depth far too large)");
}

// The (block, ray) pairs of the `count` rays segments[0 ..) (numbered from `first`) into
// `pairs` (ray by ray, blocks in walk order) and their keys into `keys`, less those met
// recently; throws when a ray reaches outside the volume's range.
MESHFLOW_AVX2_CLONES void blocks_of_rays(const RaySegment* segments, std::uint32_t first,
                                         std::size_t count, std::vector<RayBlock>& pairs,
                                         std::vector<VoxelKey>& keys) {
  RecentKeyValues recent;
  for (std::size_t j = 0; j < count; ++j) {
    const RaySegment& s = segments[j];
    const auto ray = static_cast<std::uint32_t>(first + j);
    // The block of the last voxel (floor division by 8, as tsdf_block_of_voxel()); lane 3 of
    // the walk's voxels is 0.
    ray_walk::Ints4 previous{std::numeric_limits<int>::min(), 0, 0, 0};  // never a block
    walk_voxels(ray_walk::load4(s.from.data()), ray_walk::load4(s.to.data()),
                [&](const ray_walk::Ints4& voxel) {
                  const ray_walk::Ints4 lanes = voxel >> 3;
                  if (lanes[0] == previous[0] && lanes[1] == previous[1] && lanes[2] == previous[2])
                    return;
                  previous = lanes;
                  const Eigen::Vector3i block(lanes[0], lanes[1], lanes[2]);
                  if (!tsdf_block_in_range(block)) throw_out_of_range(ray);
                  const VoxelKey key = pack_key(block);
                  pairs.push_back({key, ray});
                  if (recent.find(key) == nullptr) {
                    recent.put(key, 0);
                    keys.push_back(key);
                  }
                });
  }
}

// Every ray of the frame: per row of tiles (in parallel), its pixels merged into rays
// (x.tile_row_rays), their segments into x.segments from row x kTile x width on (tile order:
// a ray's number is its row's first plus its place in the row) and the (block, ray) pairs of
// the blocks they cross (x.row_pairs, x.row_keys); then the pairs joined in ray order into
// x.pairs and the blocks' keys, sorted and unique, into `keys`. Adds the valid pixels to
// `pixels_used`; throws when a ray reaches outside the volume's range.
void rays_and_blocks(const Image& depth, const float* band_pixels, const DepthFrame& frame,
                     const Image* color, const TsdfConfig& config, RayScratch& x,
                     std::vector<VoxelKey>& keys, std::size_t& pixels_used) {
  const int tile_rows = (depth.rows() + kTile - 1) / kTile;
  const auto rows = static_cast<std::size_t>(tile_rows);
  const std::size_t stride =
      static_cast<std::size_t>(kTile) * static_cast<std::size_t>(depth.cols());
  if (rows * stride > std::numeric_limits<std::uint32_t>::max())
    throw Error("tsdf", "depth image", "at most 2^32 pixels");
  if (x.segment_capacity < rows * stride) {
    x.segments.reset(new RaySegment[rows * stride]);  // pages touched only where rays are
    x.segment_capacity = rows * stride;
  }
  x.tile_row_rays.resize(rows);
  x.row_pairs.resize(rows);
  x.row_keys.resize(rows);
  std::vector<std::size_t> row_pixels(rows, 0);
  const Eigen::Vector3f camera = frame.T_world_camera.translation();
  const float inv_voxel = 1.0f / config.voxel_size, truncation = config.truncation();
  tbb::parallel_for(0, tile_rows, [&](int t) {
    const auto r = static_cast<std::size_t>(t);
    std::vector<MergedRay>& rays = x.tile_row_rays[r];
    rays.clear();
    rays_of_tile_row(t, depth, band_pixels, frame.intrinsics, frame.T_world_camera, color,
                     config.weighting, inv_voxel, rays, row_pixels[r]);
    RaySegment* segments = x.segments.get() + r * stride;
    for (std::size_t j = 0; j < rays.size(); ++j)
      segments[j] = segment_of(rays[j], camera, inv_voxel, truncation);
    x.row_pairs[r].clear();
    x.row_keys[r].clear();
    blocks_of_rays(segments, static_cast<std::uint32_t>(r * stride), rays.size(), x.row_pairs[r],
                   x.row_keys[r]);
  });
  for (std::size_t pixels : row_pixels) pixels_used += pixels;
  concatenate_parts(x.row_pairs, x.pairs);
  concatenate_parts(x.row_keys, keys);
  radix_sort_unique(keys);
}

// The pairs' rays bucketed by block into x.block_rays (each block's in ray order) and x.starts
// (per position in `keys`, sorted: where its rays begin; one more entry for the end).
void rays_by_block(RayScratch& x, const std::vector<VoxelKey>& keys) {
  const std::vector<RayBlock>& pairs = x.pairs;
  x.pair_blocks.resize(pairs.size());
  const std::size_t chunks = (pairs.size() + kParallelBlock - 1) / kParallelBlock;
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t chunk) {
    RecentKeyValues recent;  // key -> position
    const std::size_t end = std::min(pairs.size(), (chunk + 1) * kParallelBlock);
    for (std::size_t i = chunk * kParallelBlock; i < end; ++i) {
      const VoxelKey key = pairs[i].block;
      const std::uint32_t* found = recent.find(key);
      if (found == nullptr) {
        const auto at = static_cast<std::uint32_t>(std::lower_bound(keys.begin(), keys.end(), key) -
                                                   keys.begin());
        recent.put(key, at);
        found = recent.find(key);
      }
      x.pair_blocks[i] = *found;
    }
  });
  counting_sort(
      pairs.size(), keys.size(), [&](std::size_t i) { return std::size_t{x.pair_blocks[i]}; },
      [&](std::size_t i) { return pairs[i].ray; }, x.block_rays, x.starts);
}

// What every ray blends the same way.
struct BlendSettings {
  float voxel_size, truncation, max_weight;
  bool color;
};

// Blends a ray's distance (metres, clipped to `truncation`) with weight w into a voxel, and, when
// kColor, its colour (`ray_color`: mean RGB x w, 0), each channel as the scalar
// uint8((old x weight + mean x w) / total + 0.5) would be; the byte after the colour (padding)
// keeps its value.
template <bool kColor>
[[gnu::always_inline]] inline void blend(TsdfVoxel& voxel, float sdf_metres, float truncation,
                                         float w, const ray_walk::Floats4& ray_color,
                                         float max_weight) {
  const float weight = voxel.weight;
  const float total = weight + w;
  const float inv_total = 1.0f / total;
  voxel.distance = (voxel.distance * weight + std::min(sdf_metres, truncation) * w) * inv_total;
  if (kColor) {
    // The four bytes r, g, b, padding widened to lanes and packed back by byte shuffles.
    using Bytes16 = std::uint8_t __attribute__((vector_size(16)));
    static_assert(sizeof(TsdfVoxel) >= offsetof(TsdfVoxel, color) + 4, "colour and padding");
    unsigned char* bytes = reinterpret_cast<unsigned char*>(&voxel) + offsetof(TsdfVoxel, color);
    Bytes16 packed{};
    std::memcpy(&packed, bytes, 4);
    const Bytes16 zero{};
    const auto wide = reinterpret_cast<ray_walk::Ints4>(__builtin_shufflevector(
        packed, zero, 0, 16, 16, 16, 1, 16, 16, 16, 2, 16, 16, 16, 3, 16, 16, 16));
    const ray_walk::Floats4 mixed =
        (__builtin_convertvector(wide, ray_walk::Floats4) * weight + ray_color) * inv_total + 0.5f;
    // Lanes 0..2 hold 0..255: their low bytes are uint8(lane); lane 3 keeps the padding byte.
    const auto lanes = reinterpret_cast<Bytes16>(__builtin_convertvector(mixed, ray_walk::Ints4));
    const Bytes16 out =
        __builtin_shufflevector(lanes, packed, 0, 4, 8, 19, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0);
    std::memcpy(bytes, &out, 4);
  }
  voxel.weight = std::min(total, max_weight);
}

// Applies rays[0 .. count) (indices into `segments`, in pixel order) to the voxels of `block`
// along each ray's segment inside it; returns the voxels updated.
template <bool kColor>
[[gnu::always_inline]] inline std::size_t apply_rays_to(TsdfBlock& block, const std::uint32_t* rays,
                                                        std::size_t count,
                                                        const RaySegment* segments,
                                                        const BlendSettings& settings) {
  using ray_walk::Floats4;
  using ray_walk::Ints4;
  const float voxel_size = settings.voxel_size, truncation = settings.truncation,
              max_weight = settings.max_weight;
  const Eigen::Vector3i origin = block.coords * kTsdfBlockSide;
  const Ints4 first_voxel{origin.x(), origin.y(), origin.z(), 0};
  TsdfVoxel* voxels = block.voxels.data();
  std::size_t updated = 0;
  for (std::size_t i = 0; i < count; ++i) {
    if (i + 4 < count) __builtin_prefetch(&segments[rays[i + 4]]);
    const RaySegment& s = segments[rays[i]];
    Floats4 from, to;
    if (!clip_to_block(ray_walk::load4(s.from.data()), ray_walk::load4(s.span.data()), origin, from,
                       to))
      continue;
    const Floats4 point_band = ray_walk::load4(s.point_band.data());
    const Floats4 direction_weight = ray_walk::load4(s.direction_weight.data());
    const Floats4 ray_color = ray_walk::load4(s.color.data());
    const float neg_band = -point_band[3], w = direction_weight[3];
    walk_voxels(from, to, [&](const Ints4& voxel) {
      const Ints4 local = voxel - first_voxel;
      if (((local[0] | local[1] | local[2]) & ~(kTsdfBlockSide - 1)) != 0) return;  // outside
      // (point - voxel) . direction, summed as Eigen's dot product: x + (y + z).
      const Floats4 along =
          (point_band - __builtin_convertvector(voxel, Floats4)) * direction_weight;
      const float sdf = along[0] + (along[1] + along[2]);  // voxel units
      if (sdf < neg_band) return;  // beyond the band behind the surface: unknown
      blend<kColor>(voxels[static_cast<std::size_t>(
                        local[0] + kTsdfBlockSide * (local[1] + kTsdfBlockSide * local[2]))],
                    sdf * voxel_size, truncation, w, ray_color, max_weight);
      ++updated;
    });
  }
  return updated;
}

// apply_rays_to() with or without colour.
MESHFLOW_AVX2_CLONES std::size_t apply_rays(TsdfBlock& block, const std::uint32_t* rays,
                                            std::size_t count, const RaySegment* segments,
                                            const BlendSettings& settings) {
  return settings.color ? apply_rays_to<true>(block, rays, count, segments, settings)
                        : apply_rays_to<false>(block, rays, count, segments, settings);
}

// Requests the voxels of `block` into the cache (read for writing).
void prefetch_block(const TsdfBlock& block) {
  const char* bytes = reinterpret_cast<const char*>(block.voxels.data());
  for (std::size_t offset = 0; offset < sizeof block.voxels; offset += 64)
    __builtin_prefetch(bytes + offset, 1);
}

}  // namespace

void TsdfFrameIntegrator::integrate_along_rays(TsdfMap& map, const DepthFrame& frame,
                                               const Image& depth, IntegrationStats& stats) {
  RayScratch& x = ray_scratch_;
  const bool color = fuses_color_of(frame, depth);
  std::vector<VoxelKey>& keys = keys_;
  rays_and_blocks(depth, band_pixels_.data(), frame, color ? &frame.color : nullptr, config_, x,
                  keys, stats.pixels_used);
  const float truncation = config_.truncation();
  map.find_or_allocate(keys, config_.max_new_blocks_per_frame, config_.max_memory_bytes,
                       stats.blocks_allocated, touched_);
  rays_by_block(x, keys);

  const BlendSettings settings{config_.voxel_size, truncation, config_.max_weight, color};
  const std::uint64_t generation = map.begin_change();
  // Applies block b's rays in pixel order, the next block's voxels requested meanwhile; returns
  // the voxels it updated.
  const auto apply_rays_of = [&](std::size_t b) {
    if (b + 1 < touched_.size()) prefetch_block(map.block_for_update(touched_[b + 1]));
    TsdfBlock& block = map.block_for_update(touched_[b]);
    const std::size_t count = apply_rays(block, x.block_rays.data() + x.starts[b],
                                         x.starts[b + 1] - x.starts[b], x.segments.get(), settings);
    if (count > 0) block.modified = generation;
    return count;
  };
  stats.voxels_updated += tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, keys.size()), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& range, std::size_t sum) {
        for (std::size_t b = range.begin(); b != range.end(); ++b) sum += apply_rays_of(b);
        return sum;
      },
      std::plus<>());
}

}  // namespace meshflow
