// TsdfIntegrator::kAlongRay: each (merged) pixel ray walks the voxels of its band.
//
// Phases, each parallel: (1) per tile of 8 x 8 pixels, pixels whose points fall in one voxel
// merge into one ray; (2) each ray walks its segment through the voxel grid once, keeping the
// voxels in its band (distance, place in the block) and listing the blocks it crosses with its
// run of voxels in each; the blocks are found or allocated as for the projective integrator, and
// the runs are bucketed by block (a stable counting sort: each block's runs stay in pixel order);
// (3) one task per block applies the runs crossing it in pixel order, so the map does not
// depend on the number of threads.

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdlib>
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

// What a ray's walk needs of the frame's settings.
struct WalkSettings {
  float inv_voxel, voxel_size, truncation;
  float least;  // the held band's floor (behind_voxels x voxel), metres
};

// A ray's segment in voxel units (lanes x, y, z, 0): from `truncation` in front of its mean
// point (not behind the camera) to its band behind it; the mean point with the band (voxel
// units), the unit direction from the camera with the ray's weight, and the held band.
struct RaySegment {
  ray_walk::Floats4 from, to, point_band, direction_weight;
  float held;  // metres behind the point: how far the ray updates voxels other rays observed
};

// The segment of `ray` seen from `camera`; its mean colour x weight and weight into `blend`.
RaySegment segment_of(const MergedRay& ray, const Eigen::Vector3f& camera,
                      const WalkSettings& settings, Eigen::Vector4f& blend) {
  const float inv_voxel = settings.inv_voxel;
  RaySegment s;
  const Eigen::Vector3f point = ray.point_sum / static_cast<float>(ray.pixels);
  const Eigen::Vector3f to_point = point - camera;
  const float range = to_point.norm();
  const Eigen::Vector3f direction = to_point / range;
  const Eigen::Vector3f scaled = point * inv_voxel;
  const float band = ray.band * inv_voxel;
  const Eigen::Vector3f from =
      scaled - direction * (std::min(settings.truncation, range) * inv_voxel);
  const Eigen::Vector3f to = scaled + direction * band;
  s.from = ray_walk::Floats4{from.x(), from.y(), from.z(), 0.0f};
  s.to = ray_walk::Floats4{to.x(), to.y(), to.z(), 0.0f};
  s.point_band = ray_walk::Floats4{scaled.x(), scaled.y(), scaled.z(), band};
  s.direction_weight = ray_walk::Floats4{direction.x(), direction.y(), direction.z(), ray.weight};
  s.held = std::max(settings.least, ray.held);
  const float inv_pixels = 1.0f / static_cast<float>(ray.pixels);
  for (int c = 0; c < 3; ++c) blend[c] = ray.color_sum[c] * inv_pixels * ray.weight;
  blend[3] = ray.weight;
  return s;
}

// Pixels are merged in tiles of kTile x kTile: those whose points fall in one voxel become one
// ray (voxblox merges over the whole image; tiles keep it parallel and deterministic).
constexpr int kTile = 8;

// The rays of the tiles in tile row `tile_row` (tiles left to right, each tile's rays in the
// order of their first pixel), appended to `out`; adds the valid pixels to `pixels`.
// noise_per_depth2: kBehindNoiseMultiple x the frame's noise estimate (1/m), for the held band.
MESHFLOW_AVX2_CLONES void rays_of_tile_row(int tile_row, const Image& depth,
                                           const float* band_pixels, const PinholeIntrinsics& k,
                                           const Eigen::Isometry3f& T_world_camera,
                                           const Image* color, TsdfWeighting weighting,
                                           float inv_voxel, float noise_per_depth2,
                                           std::vector<MergedRay>& out, std::size_t& pixels) {
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
        // The slot of the voxel's low bits (x mod 8, y mod 4, z mod 4): a tile's voxels lie on
        // a small patch of surface, so they rarely share a slot (a multiplicative hash of the
        // whole coordinates met another ray's slot at one lookup in five).
        std::uint32_t h = (static_cast<std::uint32_t>(cell[0]) & 7u) |
                          ((static_cast<std::uint32_t>(cell[1]) & 3u) << 3) |
                          ((static_cast<std::uint32_t>(cell[2]) & 3u) << 5);
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
        ray.held = std::max(ray.held, noise_per_depth2 * d * d);
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
  // Whether `key` was met recently; remembers it (its value left as it was). Branch-free.
  bool met(VoxelKey key) {
    const std::size_t s = slot(key);
    const bool hit = keys_[s] == key;
    keys_[s] = key;
    return hit;
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

// Walks each of `rays` (tile row `row`, seen from `camera`) once: its mean colour x weight and
// weight into `blends`, the voxels of its band into `voxels` (walk order; each ray's first in a
// block flagged), a (block, ray) pair per block it crosses with the first of its voxels there
// into `pairs` (ray by ray, blocks in walk order; counts left to count_runs()), and the blocks'
// keys into `keys`, less those met recently. Every voxel is written and counted only when kept
// (no branch at the band's end). Returns the first ray that reaches
// outside the volume's range (its lists left incomplete), or rays.size(). O(voxels walked).
MESHFLOW_AVX2_CLONES std::size_t walk_rays(const std::vector<MergedRay>& rays, std::uint32_t row,
                                           const Eigen::Vector3f& camera,
                                           const WalkSettings& settings,
                                           std::vector<Eigen::Vector4f>& blends,
                                           RayList<RayVoxel>& voxels, RayList<RayBlock>& pairs,
                                           RayList<VoxelKey>& keys) {
  using ray_walk::Floats4;
  using ray_walk::Ints4;
  RecentKeyValues recent;
  blends.resize(rays.size());
  const float voxel_size = settings.voxel_size, truncation = settings.truncation;
  for (std::size_t j = 0; j < rays.size(); ++j) {
    const RaySegment s = segment_of(rays[j], camera, settings, blends[j]);
    const float neg_band = -s.point_band[3], neg_held = -s.held;
    // The walk's end cells (as walk_voxels() finds them) in range, and its cells: one per step
    // of their L1 distance, and one. The voxels' list keeps kMaxRunVoxels readable past its
    // end (RayRun).
    const Ints4 first_cell = ray_walk::floor4(s.from + 0.5f),
                last_cell = ray_walk::floor4(s.to + 0.5f);
    const Ints4 first_block = first_cell >> 3, last_block = last_cell >> 3;
    if (!tsdf_block_in_range({first_block[0], first_block[1], first_block[2]}) ||
        !tsdf_block_in_range({last_block[0], last_block[1], last_block[2]}))
      return j;
    const Ints4 gap = last_cell - first_cell;
    const auto bound =
        static_cast<std::size_t>(std::abs(gap[0]) + std::abs(gap[1]) + std::abs(gap[2])) + 1;
    RayVoxel* const voxel_out = voxels.room(bound + kMaxRunVoxels);
    RayBlock* const pair_out = pairs.room(bound);
    VoxelKey* const key_out = keys.room(bound);
    const auto base = static_cast<std::uint32_t>(voxels.size());
    std::uint32_t kept = 0, run_first = 0;
    std::size_t new_pairs = 0, new_keys = 0;
    bool in_range = true;
    // The block of the last voxel (floor division by 8, as tsdf_block_of_voxel()); lane 3 of
    // the walk's voxels is 0.
    Ints4 previous{std::numeric_limits<int>::min(), 0, 0, 0};  // never a block
    walk_voxels(s.from, s.to, [&](const Ints4& voxel) {
      const Ints4 lanes = voxel >> 3;
      if (lanes[0] != previous[0] || lanes[1] != previous[1] || lanes[2] != previous[2]) {
        previous = lanes;  // a new block (a branch: a few per ray, cheaper than computing
                           // the pair and key at every voxel)
        const Eigen::Vector3i block(lanes[0], lanes[1], lanes[2]);
        in_range &= tsdf_block_in_range(block);
        const VoxelKey key = pack_key(in_range ? block : Eigen::Vector3i::Zero());
        run_first = base + kept;
        pair_out[new_pairs++] = {key, row, static_cast<std::uint32_t>(j), run_first, 0};
        key_out[new_keys] = key;
        new_keys += recent.met(key) ? 0 : 1;
      }
      // (point - voxel) . direction, summed as Eigen's dot product: x + (y + z).
      const Floats4 along =
          (s.point_band - __builtin_convertvector(voxel, Floats4)) * s.direction_weight;
      const float sdf = along[0] + (along[1] + along[2]);  // voxel units
      const float metres = sdf * voxel_size;
      const Ints4 local = voxel & (kTsdfBlockSide - 1);
      voxel_out[kept] = {std::min(metres, truncation),
                         static_cast<std::uint16_t>(
                             local[0] + kTsdfBlockSide * (local[1] + kTsdfBlockSide * local[2])),
                         static_cast<std::uint8_t>(metres < neg_held ? 1 : 0),
                         static_cast<std::uint8_t>(base + kept == run_first ? 1 : 0)};
      kept += sdf < neg_band ? 0 : 1;  // beyond the band behind the surface: unknown (written,
                                       // not kept: no branch at the band's end)
    });
    if (!in_range) return j;
    voxels.commit(kept);
    pairs.commit(new_pairs);
    keys.commit(new_keys);
  }
  return rays.size();
}

// Each pair's count: its voxels up to the next pair's first (the row's pairs hold consecutive
// runs of its `voxels` voxels).
void count_runs(RayList<RayBlock>& pairs, std::size_t voxels) {
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const std::size_t end = i + 1 < pairs.size() ? pairs[i + 1].first : voxels;
    pairs[i].count = static_cast<std::uint32_t>(end - pairs[i].first);
  }
}

// The lists' entries in list order, into `out` (resized), the copies in parallel.
template <typename T>
void join_lists(const std::vector<RayList<T>>& lists, std::vector<T>& out) {
  std::vector<std::size_t> offsets(lists.size());
  for (std::size_t i = 0; i < lists.size(); ++i) offsets[i] = lists[i].size();
  out.resize(exclusive_scan_in_place(offsets));
  tbb::parallel_for(std::size_t{0}, lists.size(), [&](std::size_t i) {
    std::copy(lists[i].data(), lists[i].data() + lists[i].size(),
              out.begin() + static_cast<std::ptrdiff_t>(offsets[i]));
  });
}

// Every ray of the frame: per row of tiles (in parallel), its pixels merged into rays
// (x.tile_row_rays), each walked once into its colour and weight (x.row_blends), the voxels of
// its band (x.row_voxels) and the (block, ray) pairs of the blocks it crosses (x.row_pairs,
// x.row_keys); then the pairs joined in ray order into x.pairs and the blocks' keys, sorted and
// unique, into `keys`. noise_per_depth2: as rays_of_tile_row(). Adds the valid pixels to
// `pixels_used`; throws when a ray reaches outside the volume's range.
void rays_and_blocks(const Image& depth, const float* band_pixels, const DepthFrame& frame,
                     const Image* color, const TsdfConfig& config, float noise_per_depth2,
                     RayScratch& x, std::vector<VoxelKey>& keys, std::size_t& pixels_used) {
  const int tile_rows = (depth.rows() + kTile - 1) / kTile;
  const auto rows = static_cast<std::size_t>(tile_rows);
  x.tile_row_rays.resize(rows);
  x.row_blends.resize(rows);
  x.row_voxels.resize(rows);
  x.row_pairs.resize(rows);
  x.row_keys.resize(rows);
  std::vector<std::size_t> row_pixels(rows, 0);
  const Eigen::Vector3f camera = frame.T_world_camera.translation();
  const WalkSettings settings{1.0f / config.voxel_size, config.voxel_size, config.truncation(),
                              config.behind_voxels * config.voxel_size};
  tbb::parallel_for(0, tile_rows, [&](int t) {
    const auto r = static_cast<std::size_t>(t);
    std::vector<MergedRay>& rays = x.tile_row_rays[r];
    rays.clear();
    rays_of_tile_row(t, depth, band_pixels, frame.intrinsics, frame.T_world_camera, color,
                     config.weighting, settings.inv_voxel, noise_per_depth2, rays, row_pixels[r]);
    x.row_voxels[r].clear();
    x.row_pairs[r].clear();
    x.row_keys[r].clear();
    const std::size_t bad =
        walk_rays(rays, static_cast<std::uint32_t>(r), camera, settings, x.row_blends[r],
                  x.row_voxels[r], x.row_pairs[r], x.row_keys[r]);
    if (bad < rays.size())
      throw Error("tsdf", "ray " + std::to_string(bad) + " of tile row " + std::to_string(r),
                  "reaches outside the volume's range (pose or depth far too large)");
    if (x.row_voxels[r].size() > std::numeric_limits<std::uint32_t>::max() - kMaxRunVoxels)
      throw Error("tsdf", "tile row " + std::to_string(r), "fewer than 2^32 voxels walked");
    count_runs(x.row_pairs[r], x.row_voxels[r].size());
  });
  for (std::size_t pixels : row_pixels) pixels_used += pixels;
  join_lists(x.row_pairs, x.pairs);
  join_lists(x.row_keys, keys);
  radix_sort_unique(keys);
}

// The pairs' non-empty runs bucketed by block into x.block_runs (each block's in ray order) and
// x.starts (per position in `keys`, sorted: where its runs begin; one more entry for the end).
void runs_by_block(RayScratch& x, const std::vector<VoxelKey>& keys) {
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
      pairs.size(), keys.size(),
      [&](std::size_t i) {  // empty runs past the last bucket: left out
        return pairs[i].count > 0 ? std::size_t{x.pair_blocks[i]} : keys.size();
      },
      [&](std::size_t i) {
        const RayBlock& p = pairs[i];
        return RayRun{x.row_voxels[p.row].data() + p.first, x.row_blends[p.row].data() + p.ray,
                      p.count};
      },
      x.block_runs, x.starts);
}

// What every ray blends the same way.
struct BlendSettings {
  float max_weight;
  bool color;
};

// Blends a ray's distance (metres, clipped to the truncation) with weight w into a voxel, and,
// when kColor, its colour (`ray_color`: mean RGB x w, then a lane not used), each channel as the
// scalar uint8((old x weight + mean x w) / total + 0.5) would be; the byte after the colour
// (padding) keeps its value.
template <bool kColor>
[[gnu::always_inline]] inline void blend(TsdfVoxel& voxel, float distance, float w,
                                         const ray_walk::Floats4& ray_color, float max_weight) {
  const float weight = voxel.weight;
  const float total = weight + w;
  const float inv_total = 1.0f / total;
  voxel.distance = (voxel.distance * weight + distance * w) * inv_total;
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

// A block's runs, joined: their voxels in order (each run's first flagged) and their rays'
// colour x weight and weight. Per thread; capacity reused.
struct JoinedRuns {
  std::vector<RayVoxel> voxels;
  std::vector<ray_walk::Floats4> blends;
};

// Applies runs[0 .. count) (non-empty, in pixel order) to the voxels of `block`: each run's voxels
// take its ray's distance and weight, except observed voxels (weight > 0) beyond the ray's held
// band, which keep their state. The runs are first joined into `joined` (each copied as
// kMaxRunVoxels voxels, the next written over the excess), so that one loop without an exit per
// run blends them; returns the voxels updated.
template <bool kColor>
[[gnu::always_inline]] inline std::size_t apply_runs_to(TsdfBlock& block, const RayRun* runs,
                                                        std::size_t count, float max_weight,
                                                        JoinedRuns& joined) {
  std::size_t total = 0;
  for (std::size_t i = 0; i < count; ++i) total += runs[i].count;
  if (joined.voxels.size() < total + kMaxRunVoxels) joined.voxels.resize(total + kMaxRunVoxels);
  if (joined.blends.size() < count) joined.blends.resize(count);
  RayVoxel* const flat = joined.voxels.data();
  ray_walk::Floats4* const blends = joined.blends.data();
  std::size_t at = 0;
  for (std::size_t i = 0; i < count; ++i) {
    if (i + 4 < count) {
      __builtin_prefetch(runs[i + 4].voxels);
      __builtin_prefetch(runs[i + 4].blend);
    }
    std::memcpy(flat + at, runs[i].voxels, kMaxRunVoxels * sizeof(RayVoxel));
    at += runs[i].count;
    blends[i] = ray_walk::load4(runs[i].blend->data());  // RGB x w, w
  }
  TsdfVoxel* const voxels = block.voxels.data();
  std::size_t updated = 0;
  std::size_t run = std::numeric_limits<std::size_t>::max();  // the first voxel starts run 0
  for (std::size_t k = 0; k < total; ++k) {
    const RayVoxel v = flat[k];
    run += v.first;
    const ray_walk::Floats4 ray = blends[run];
    TsdfVoxel& voxel = voxels[v.index];
    if (v.held != 0 && voxel.weight > 0.0f) continue;  // observed, past the held band: kept
    blend<kColor>(voxel, v.distance, ray[3], ray, max_weight);
    ++updated;
  }
  return updated;
}

// apply_runs_to() with or without colour.
MESHFLOW_AVX2_CLONES std::size_t apply_runs(TsdfBlock& block, const RayRun* runs, std::size_t count,
                                            const BlendSettings& settings, JoinedRuns& joined) {
  return settings.color ? apply_runs_to<true>(block, runs, count, settings.max_weight, joined)
                        : apply_runs_to<false>(block, runs, count, settings.max_weight, joined);
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
  rays_and_blocks(depth, band_pixels_.data(), frame, color ? &frame.color : nullptr, config_,
                  kBehindNoiseMultiple * stats.noise_per_depth2, x, keys, stats.pixels_used);
  map.find_or_allocate(keys, config_.max_new_blocks_per_frame, config_.max_memory_bytes,
                       stats.blocks_allocated, touched_);
  runs_by_block(x, keys);

  const BlendSettings settings{config_.max_weight, color};
  const std::uint64_t generation = map.begin_change();
  tbb::enumerable_thread_specific<JoinedRuns> joined;
  // Applies block b's runs in pixel order, the next block's voxels requested meanwhile; returns
  // the voxels it updated.
  const auto apply_runs_of = [&](std::size_t b) {
    if (b + 1 < touched_.size()) prefetch_block(map.block_for_update(touched_[b + 1]));
    TsdfBlock& block = map.block_for_update(touched_[b]);
    const std::size_t count = apply_runs(block, x.block_runs.data() + x.starts[b],
                                         x.starts[b + 1] - x.starts[b], settings, joined.local());
    if (count > 0) block.modified = generation;
    return count;
  };
  stats.voxels_updated += tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, keys.size()), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& range, std::size_t sum) {
        for (std::size_t b = range.begin(); b != range.end(); ++b) sum += apply_runs_of(b);
        return sum;
      },
      std::plus<>());
}

}  // namespace meshflow
