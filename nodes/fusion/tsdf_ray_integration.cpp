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
  s.direction = to_point / range;
  s.point = point * inv_voxel;
  s.band = ray.band * inv_voxel;
  const Eigen::Vector3f from = s.point - s.direction * (std::min(truncation, range) * inv_voxel);
  const Eigen::Vector3f to = s.point + s.direction * s.band;
  const Eigen::Vector3f span = to - from;
  s.from = Eigen::Vector4f(from.x(), from.y(), from.z(), 0.0f);
  s.to = Eigen::Vector4f(to.x(), to.y(), to.z(), 0.0f);
  s.span = Eigen::Vector4f(span.x(), span.y(), span.z(), 0.0f);
  s.weight = ray.weight;
  const float inv_pixels = 1.0f / static_cast<float>(ray.pixels);
  for (int c = 0; c < 3; ++c) s.color[c] = ray.color_sum[c] * inv_pixels * ray.weight;
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

// Every ray of the frame in tile order into `rays` (tile rows in parallel into `row_rays`,
// then joined).
void merged_rays(const Image& depth, const float* band_pixels, const DepthFrame& frame,
                 const Image* color, const TsdfConfig& config,
                 std::vector<std::vector<MergedRay>>& row_rays, std::vector<MergedRay>& rays,
                 std::size_t& pixels_used) {
  const int tile_rows = (depth.rows() + kTile - 1) / kTile;
  const auto rows = static_cast<std::size_t>(tile_rows);
  row_rays.resize(rows);
  std::vector<std::size_t> row_pixels(rows, 0);
  const float inv_voxel = 1.0f / config.voxel_size;
  tbb::parallel_for(0, tile_rows, [&](int t) {
    const auto r = static_cast<std::size_t>(t);
    row_rays[r].clear();
    rays_of_tile_row(t, depth, band_pixels, frame.intrinsics, frame.T_world_camera, color,
                     config.weighting, inv_voxel, row_rays[r], row_pixels[r]);
  });
  for (std::size_t pixels : row_pixels) pixels_used += pixels;
  concatenate_parts(row_rays, rays);
}

constexpr std::size_t kRaysPerTask = 2048;

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

// The (block, ray) pairs of rays [begin, end) into `pairs` (ray by ray, blocks in walk order)
// and their keys into `keys`, less those the slice met recently; throws when a ray reaches
// outside the volume's range.
MESHFLOW_AVX2_CLONES void blocks_of_rays(const std::vector<RaySegment>& segments, std::size_t begin,
                                         std::size_t end, std::vector<RayBlock>& pairs,
                                         std::vector<VoxelKey>& keys) {
  RecentKeyValues recent;
  for (std::size_t r = begin; r < end; ++r) {
    const RaySegment& s = segments[r];
    Eigen::Vector3i previous(std::numeric_limits<int>::min(), 0, 0);  // never a block
    walk_voxels(ray_walk::load4(s.from.data()), ray_walk::load4(s.to.data()),
                [&](const ray_walk::Ints4& voxel) {
                  const Eigen::Vector3i block =
                      tsdf_block_of_voxel(Eigen::Vector3i(voxel[0], voxel[1], voxel[2]));
                  if (block == previous) return;
                  previous = block;
                  if (!tsdf_block_in_range(block)) throw_out_of_range(r);
                  const VoxelKey key = pack_key(block);
                  pairs.push_back({key, static_cast<std::uint32_t>(r)});
                  if (recent.find(key) == nullptr) {
                    recent.put(key, 0);
                    keys.push_back(key);
                  }
                });
  }
}

// The (block, ray) pairs of every ray's segment into x.pairs (in ray order) and the keys of the
// blocks crossed, sorted and unique, into `keys`: rays in fixed slices (parallel, into
// x.slice_pairs and x.slice_keys); throws when a ray reaches outside the volume's range.
void blocks_crossed(RayScratch& x, std::vector<VoxelKey>& keys) {
  const std::vector<RaySegment>& segments = x.segments;
  const std::size_t slices = (segments.size() + kRaysPerTask - 1) / kRaysPerTask;
  x.slice_pairs.resize(slices);
  x.slice_keys.resize(slices);
  tbb::parallel_for(std::size_t{0}, slices, [&](std::size_t slice) {
    x.slice_pairs[slice].clear();
    x.slice_keys[slice].clear();
    blocks_of_rays(segments, slice * kRaysPerTask,
                   std::min(segments.size(), (slice + 1) * kRaysPerTask), x.slice_pairs[slice],
                   x.slice_keys[slice]);
  });
  concatenate_parts(x.slice_pairs, x.pairs);
  concatenate_parts(x.slice_keys, keys);
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

// Blends a ray's distance (metres, clipped to the truncation) with weight w into a voxel, and
// its colour when `color`: (mean RGB x w, 0), each channel as the scalar
// uint8((old x weight + mean x w) / total + 0.5) would be.
void blend(TsdfVoxel& voxel, float sdf_metres, float truncation, float w,
           const ray_walk::Floats4& ray_color, bool color, float max_weight) {
  const float total = voxel.weight + w;
  const float inv_total = 1.0f / total;
  voxel.distance =
      (voxel.distance * voxel.weight + std::min(sdf_metres, truncation) * w) * inv_total;
  if (color) {
    using Bytes4 = std::uint8_t __attribute__((vector_size(4)));
    Bytes4 rgb{voxel.color.r, voxel.color.g, voxel.color.b, 0};
    const ray_walk::Floats4 mixed =
        (__builtin_convertvector(rgb, ray_walk::Floats4) * voxel.weight + ray_color) * inv_total +
        0.5f;
    rgb = __builtin_convertvector(__builtin_convertvector(mixed, ray_walk::Ints4), Bytes4);
    voxel.color = Rgb8{rgb[0], rgb[1], rgb[2]};
  }
  voxel.weight = std::min(total, max_weight);
}

// What every ray blends the same way.
struct BlendSettings {
  float voxel_size, truncation, max_weight;
  bool color;
};

// Applies rays[0 .. count) (indices into `segments`, in pixel order) to the voxels of `block`
// along each ray's segment inside it; returns the voxels updated.
MESHFLOW_AVX2_CLONES std::size_t apply_rays(TsdfBlock& block, const std::uint32_t* rays,
                                            std::size_t count,
                                            const std::vector<RaySegment>& segments,
                                            const BlendSettings& settings) {
  const Eigen::Vector3i origin = block.coords * kTsdfBlockSide;
  const ray_walk::Ints4 first_voxel{origin.x(), origin.y(), origin.z(), 0};
  std::size_t updated = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const RaySegment& s = segments[rays[i]];
    ray_walk::Floats4 from, to;
    if (!clip_to_block(ray_walk::load4(s.from.data()), ray_walk::load4(s.span.data()), origin, from,
                       to))
      continue;
    const ray_walk::Floats4 point{s.point.x(), s.point.y(), s.point.z(), 0.0f};
    const ray_walk::Floats4 direction{s.direction.x(), s.direction.y(), s.direction.z(), 0.0f};
    const ray_walk::Floats4 ray_color{s.color[0], s.color[1], s.color[2], 0.0f};
    walk_voxels(from, to, [&](const ray_walk::Ints4& voxel) {
      const ray_walk::Ints4 local = voxel - first_voxel;
      if (((local[0] | local[1] | local[2]) & ~(kTsdfBlockSide - 1)) != 0) return;  // outside
      // (point - voxel) . direction, summed as Eigen's dot product: x + (y + z).
      const ray_walk::Floats4 along =
          (point - __builtin_convertvector(voxel, ray_walk::Floats4)) * direction;
      const float sdf = along[0] + (along[1] + along[2]);  // voxel units
      if (sdf < -s.band) return;  // beyond the band behind the surface: unknown
      blend(block.voxels[static_cast<std::size_t>(
                local[0] + kTsdfBlockSide * (local[1] + kTsdfBlockSide * local[2]))],
            sdf * settings.voxel_size, settings.truncation, s.weight, ray_color, settings.color,
            settings.max_weight);
      ++updated;
    });
  }
  return updated;
}

}  // namespace

void TsdfFrameIntegrator::integrate_along_rays(TsdfMap& map, const DepthFrame& frame,
                                               const Image& depth, IntegrationStats& stats) {
  RayScratch& x = ray_scratch_;
  const bool color = fuses_color_of(frame, depth);
  merged_rays(depth, band_pixels_.data(), frame, color ? &frame.color : nullptr, config_,
              x.tile_row_rays, x.rays, stats.pixels_used);
  const std::vector<MergedRay>& rays = x.rays;
  const Eigen::Vector3f camera = frame.T_world_camera.translation();
  const float inv_voxel = 1.0f / config_.voxel_size, truncation = config_.truncation();
  x.segments.resize(rays.size());
  tbb::parallel_for(std::size_t{0}, rays.size(), [&](std::size_t r) {
    x.segments[r] = segment_of(rays[r], camera, inv_voxel, truncation);
  });
  std::vector<VoxelKey>& keys = keys_;
  blocks_crossed(x, keys);
  map.find_or_allocate(keys, config_.max_new_blocks_per_frame, config_.max_memory_bytes,
                       stats.blocks_allocated, touched_);
  rays_by_block(x, keys);

  const BlendSettings settings{config_.voxel_size, truncation, config_.max_weight, color};
  const std::uint64_t generation = map.begin_change();
  // Applies block b's rays in pixel order; returns the voxels it updated.
  const auto apply_rays_of = [&](std::size_t b) {
    TsdfBlock& block = map.block_for_update(touched_[b]);
    const std::size_t count = apply_rays(block, x.block_rays.data() + x.starts[b],
                                         x.starts[b + 1] - x.starts[b], x.segments, settings);
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
