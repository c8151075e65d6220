// TsdfIntegrator::kAlongRay: each (merged) pixel ray walks the voxels of its band.
//
// Phases, each parallel: (1) per tile of 8 x 8 pixels, pixels whose points fall in one voxel
// merge into one ray; (2) each ray walks its segment through the voxel grid and
// lists the blocks it crosses; the blocks are found or allocated as for the projective
// integrator; (3) one task per block applies the rays crossing it in pixel order, so the map
// does not depend on the number of threads.

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
#include "nodes/fusion/tsdf_volume.h"
#include "runtime/error.h"
#include "runtime/parallel.h"
#include "runtime/radix_sort.h"

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
  s.from = s.point - s.direction * (std::min(truncation, range) * inv_voxel);
  s.to = s.point + s.direction * s.band;
  return s;
}

// Calls visit(voxel) for every voxel whose cell (the unit cube centred on its sample point)
// the segment from -> to (voxel units) crosses, in order (Amanatides & Woo's traversal).
template <class Visit>
void walk_voxels(const Eigen::Vector3f& from, const Eigen::Vector3f& to, Visit&& visit) {
  const Eigen::Vector3f a = from.array() + 0.5f, b = to.array() + 0.5f;  // cells [i, i + 1)
  Eigen::Vector3i cell(floor_to_int(a.x()), floor_to_int(a.y()), floor_to_int(a.z()));
  const Eigen::Vector3i last(floor_to_int(b.x()), floor_to_int(b.y()), floor_to_int(b.z()));
  const Eigen::Vector3f d = b - a;
  Eigen::Vector3i step;
  Eigen::Vector3f next, delta;  // segment parameter of the next boundary per axis, per cell
  constexpr float kNever = std::numeric_limits<float>::infinity();
  for (int i = 0; i < 3; ++i) {
    step[i] = d[i] > 0.0f ? 1 : (d[i] < 0.0f ? -1 : 0);
    if (step[i] == 0) {
      next[i] = delta[i] = kNever;
      continue;
    }
    const float boundary = static_cast<float>(cell[i] + (step[i] > 0 ? 1 : 0));
    next[i] = (boundary - a[i]) / d[i];
    delta[i] = static_cast<float>(step[i]) / d[i];
  }
  // Rounding can miss `last` by a cell: the walk stops after the cells a straight line needs.
  const int steps = (last - cell).cwiseAbs().sum();
  for (int s = 0;; ++s) {
    visit(cell);
    if (s == steps) break;
    int axis = 0;
    if (next[1] < next[axis]) axis = 1;
    if (next[2] < next[axis]) axis = 2;
    cell[axis] += step[axis];
    next[axis] += delta[axis];
  }
}

// The part of the segment from -> to (voxel units) inside the cells of the block whose first
// voxel is `origin` (with a little margin: cells outside are skipped by the caller), or false
// when it misses them (the slab method).
bool clip_to_block(const Eigen::Vector3f& from, const Eigen::Vector3f& to,
                   const Eigen::Vector3i& origin, Eigen::Vector3f& clipped_from,
                   Eigen::Vector3f& clipped_to) {
  constexpr float kMargin = 1e-3f;
  const Eigen::Vector3f lo = origin.cast<float>().array() - (0.5f + kMargin);
  const Eigen::Vector3f hi = lo.array() + (static_cast<float>(kTsdfBlockSide) + 2.0f * kMargin);
  const Eigen::Vector3f d = to - from;
  float t0 = 0.0f, t1 = 1.0f;
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0.0f) {
      if (from[i] < lo[i] || from[i] > hi[i]) return false;
      continue;
    }
    float a = (lo[i] - from[i]) / d[i], b = (hi[i] - from[i]) / d[i];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  if (t0 > t1) return false;
  clipped_from = from + t0 * d;
  clipped_to = from + t1 * d;
  return true;
}

// Pixels are merged in tiles of kTile x kTile: those whose points fall in one voxel become one
// ray (voxblox merges over the whole image; tiles keep it parallel and deterministic).
constexpr int kTile = 8;

// The rays of the tiles in tile row `tile_row` (tiles left to right, each tile's rays in the
// order of their first pixel), appended to `out`; adds the valid pixels to `pixels`.
void rays_of_tile_row(int tile_row, const Image& depth, const float* band_pixels,
                      const PinholeIntrinsics& k, const Eigen::Isometry3f& T_world_camera,
                      const Image* color, TsdfWeighting weighting, float inv_voxel,
                      std::vector<MergedRay>& out, std::size_t& pixels) {
  const int width = depth.cols(), v0 = tile_row * kTile, v1 = std::min(depth.rows(), v0 + kTile);
  for (int u0 = 0; u0 < width; u0 += kTile) {
    const std::size_t first = out.size();
    const int u1 = std::min(width, u0 + kTile);
    for (int v = v0; v < v1; ++v) {
      const float* row =
          band_pixels + 2 * static_cast<std::size_t>(v) * static_cast<std::size_t>(width);
      const float y = (static_cast<float>(v) - k.cy) / k.fy;
      for (int u = u0; u < u1; ++u) {
        const float d = row[2 * u];
        if (!(d > 0.0f)) continue;
        ++pixels;
        const Eigen::Vector3f point =
            T_world_camera * Eigen::Vector3f((static_cast<float>(u) - k.cx) / k.fx * d, y * d, d);
        const Eigen::Vector3f q = point * inv_voxel;
        const Eigen::Vector3i voxel(floor_to_int(q.x() + 0.5f), floor_to_int(q.y() + 0.5f),
                                    floor_to_int(q.z() + 0.5f));
        std::size_t r = first;
        while (r < out.size() && out[r].voxel != voxel) ++r;
        if (r == out.size()) {
          out.emplace_back();
          out.back().voxel = voxel;
        }
        MergedRay& ray = out[r];
        ray.point_sum += point;
        ray.weight += observation_weight(weighting, d);
        ray.band = std::max(ray.band, row[2 * u + 1]);
        ++ray.pixels;
        if (color != nullptr) {
          const Rgb8 c = color->at<Rgb8>(v, u);
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

// The (block, ray) pairs of every ray's segment into `pairs`, rays in fixed slices (parallel,
// into `per_slice`); throws when a ray reaches outside the volume's range.
void blocks_crossed(const std::vector<RaySegment>& segments,
                    std::vector<std::vector<RayBlock>>& per_slice, std::vector<RayBlock>& pairs) {
  const std::size_t slices = (segments.size() + kRaysPerTask - 1) / kRaysPerTask;
  per_slice.resize(slices);
  tbb::parallel_for(std::size_t{0}, slices, [&](std::size_t slice) {
    per_slice[slice].clear();
    const std::size_t end = std::min(segments.size(), (slice + 1) * kRaysPerTask);
    for (std::size_t r = slice * kRaysPerTask; r < end; ++r) {
      const RaySegment& s = segments[r];
      VoxelKey previous = ~VoxelKey{0};  // never a packed key
      walk_voxels(s.from, s.to, [&](const Eigen::Vector3i& voxel) {
        const Eigen::Vector3i block = tsdf_block_of_voxel(voxel);
        if (!tsdf_block_in_range(block)) {
          throw Error("tsdf", "ray " + std::to_string(r),
                      "reaches outside the volume's range (pose or depth far too large)");
        }
        const VoxelKey key = pack_key(block);
        if (key == previous) return;
        previous = key;
        per_slice[slice].push_back({key, static_cast<std::uint32_t>(r)});
      });
    }
  });
  concatenate_parts(per_slice, pairs);
}

// Blends one ray's distance (metres, clipped to the truncation) and colour into a voxel.
void blend(TsdfVoxel& voxel, float sdf_metres, float truncation, const MergedRay& ray, bool color,
           float max_weight) {
  const float w = ray.weight;
  const float total = voxel.weight + w;
  const float inv_total = 1.0f / total;
  voxel.distance =
      (voxel.distance * voxel.weight + std::min(sdf_metres, truncation) * w) * inv_total;
  if (color) {
    const float inv_pixels = 1.0f / static_cast<float>(ray.pixels);
    auto mix = [&](std::uint8_t old, float sum) {
      return static_cast<std::uint8_t>(
          (static_cast<float>(old) * voxel.weight + sum * inv_pixels * w) * inv_total + 0.5f);
    };
    voxel.color = Rgb8{mix(voxel.color.r, ray.color_sum[0]), mix(voxel.color.g, ray.color_sum[1]),
                       mix(voxel.color.b, ray.color_sum[2])};
  }
  voxel.weight = std::min(total, max_weight);
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
  const std::vector<RaySegment>& segments = x.segments;
  blocks_crossed(segments, x.slice_pairs, x.pairs);
  const std::vector<RayBlock>& pairs = x.pairs;
  std::vector<VoxelKey>& keys = keys_;
  keys.resize(pairs.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) keys[i] = pairs[i].block;
  radix_sort_unique(keys);
  map.find_or_allocate(keys, config_.max_new_blocks_per_frame, config_.max_memory_bytes,
                       stats.blocks_allocated, touched_);
  const std::vector<std::uint32_t>& blocks = touched_;

  // (position of the block among the keys, ray): sorted, the rays of each block in pixel order.
  std::vector<std::uint64_t>& block_rays = x.block_rays;
  block_rays.resize(pairs.size());
  tbb::parallel_for(std::size_t{0}, pairs.size(), [&](std::size_t i) {
    const auto at = std::lower_bound(keys.begin(), keys.end(), pairs[i].block) - keys.begin();
    block_rays[i] = (static_cast<std::uint64_t>(at) << 32) | pairs[i].ray;
  });
  radix_sort(block_rays);
  std::vector<std::size_t>& starts = x.starts;
  starts.assign(keys.size() + 1, block_rays.size());  // every key has a ray
  for (std::size_t i = 0; i < block_rays.size(); ++i) {
    const std::size_t b = block_rays[i] >> 32;
    if (i == 0 || (block_rays[i - 1] >> 32) != b) starts[b] = i;
  }

  const std::uint64_t generation = map.begin_change();
  // Applies block b's rays in pixel order; returns the voxels it updated.
  const auto apply_rays = [&](std::size_t b) {
    TsdfBlock& block = map.block_for_update(blocks[b]);
    const Eigen::Vector3i origin = block.coords * kTsdfBlockSide;
    std::size_t count = 0;
    for (std::size_t i = starts[b]; i < starts[b + 1]; ++i) {
      const std::size_t r = block_rays[i] & 0xffffffffu;
      const MergedRay& ray = rays[r];
      const RaySegment& s = segments[r];
      Eigen::Vector3f from, to;
      if (!clip_to_block(s.from, s.to, origin, from, to)) continue;
      walk_voxels(from, to, [&](const Eigen::Vector3i& voxel) {
        const Eigen::Vector3i local = voxel - origin;
        if ((local.array() < 0).any() || (local.array() >= kTsdfBlockSide).any()) return;
        const float sdf = (s.point - voxel.cast<float>()).dot(s.direction);  // voxel units
        if (sdf < -s.band) return;  // beyond the band behind the surface: unknown
        TsdfVoxel& v = block.voxels[static_cast<std::size_t>(
            local.x() + kTsdfBlockSide * (local.y() + kTsdfBlockSide * local.z()))];
        blend(v, sdf * config_.voxel_size, truncation, ray, color, config_.max_weight);
        ++count;
      });
    }
    if (count > 0) block.modified = generation;
    return count;
  };
  stats.voxels_updated += tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, keys.size()), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& range, std::size_t sum) {
        for (std::size_t b = range.begin(); b != range.end(); ++b) sum += apply_rays(b);
        return sum;
      },
      std::plus<>());
}

}  // namespace meshflow
