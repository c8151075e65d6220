// TsdfConfig::carve_free_space: existing blocks a frame sees through lose their surface.
//
// Candidates are the blocks the frame's band did not touch that hold surface and lie (at least
// partly) in the image, in front of the camera, with some measured pixel of their image
// rectangle deeper than their nearest voxel by a truncation (DepthBoundsPyramid bounds the
// depth over rectangles). In those, a voxel inside the image is carved when every pixel its
// cell can project to is measured and lies more than a truncation behind it (the pyramid's
// lower bound over the cell's rectangle, a pixel wider each side, clipped to the image): the
// projective update's free-space value, +truncation, blends into it, colour untouched (voxels
// seen free already, at +truncation, are left as they are). Depth edges and unmeasured pixels
// near a voxel stop its carving. Each block is decided from its own
// state and the frame alone, so the map does not depend on the number of threads.

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>

#include "nodes/fusion/tsdf_band.h"
#include "nodes/fusion/tsdf_projective_update.h"
#include "nodes/fusion/tsdf_volume.h"

namespace meshflow {
namespace {

// Half a cube's diagonal per unit of side.
const float kHalfDiagonal = 0.5f * std::sqrt(3.0f);

// Whether the block holds surface: an observed voxel at or behind a zero crossing.
bool holds_surface(const TsdfBlock& block) {
  for (const TsdfVoxel& v : block.voxels)
    if (v.weight > 0.0f && v.distance <= 0.0f) return true;
  return false;
}

// The pixels [u0, u1] x [v0, v1] that a sphere of `radius` around the camera-frame point `p`
// can project to (nearest-pixel rounding), clipped to the image; false when it comes within half
// its radius of the camera's plane (or behind it) or misses the image.
struct PixelRect {
  int u0, v0, u1, v1;
};
bool sphere_pixels(const Eigen::Vector3f& p, float radius, const BlockUpdate& frame,
                   PixelRect& rect) {
  const float near = p.z() - radius, far = p.z() + radius;
  if (!(near > 0.5f * radius)) return false;
  // The sphere's bounding box projects within the extremes of its corners' x / z and y / z.
  const PinholeIntrinsics& k = frame.intrinsics;
  const float x0 = p.x() - radius, x1 = p.x() + radius;
  const float y0 = p.y() - radius, y1 = p.y() + radius;
  // Pixel u covers image positions [u - 0.5, u + 0.5).
  const float u_lo = k.cx + k.fx * std::min(x0 / near, x0 / far) + 0.5f;
  const float u_hi = k.cx + k.fx * std::max(x1 / near, x1 / far) + 0.5f;
  const float v_lo = k.cy + k.fy * std::min(y0 / near, y0 / far) + 0.5f;
  const float v_hi = k.cy + k.fy * std::max(y1 / near, y1 / far) + 0.5f;
  const auto width = static_cast<float>(frame.width), height = static_cast<float>(frame.height);
  if (!(u_hi >= 0.0f && v_hi >= 0.0f && u_lo < width && v_lo < height)) return false;
  rect.u0 = static_cast<int>(std::max(u_lo, 0.0f));
  rect.v0 = static_cast<int>(std::max(v_lo, 0.0f));
  rect.u1 = static_cast<int>(std::min(u_hi, width - 1.0f));
  rect.v1 = static_cast<int>(std::min(v_hi, height - 1.0f));
  return true;
}

// Block coordinates lo..hi (inclusive) of a box around the camera's view up to `deepest`
// metres: the camera and its image corners at that depth span the frustum.
struct BlockBox {
  Eigen::Vector3i lo, hi;
};
BlockBox frustum_blocks(const DepthFrame& frame, float deepest, float voxel) {
  const PinholeIntrinsics& k = frame.intrinsics;
  Eigen::AlignedBox3f box(frame.T_world_camera.translation());
  for (const float u : {-0.5f, static_cast<float>(k.width) - 0.5f})
    for (const float v : {-0.5f, static_cast<float>(k.height) - 0.5f})
      box.extend(frame.T_world_camera *
                 (Eigen::Vector3f((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0f) * deepest));
  // A carved voxel's sample point lies in the box; one block more each way is margin.
  return {tsdf_block_of_voxel(cell_of(box.min(), voxel)) - Eigen::Vector3i::Ones(),
          tsdf_block_of_voxel(cell_of(box.max(), voxel)) + Eigen::Vector3i::Ones()};
}

// The weight a carved voxel at depth `voxel_depth` takes from a frame measuring
// `measured_depth` behind it: one observation; along rays, one per pixel whose ray crosses it
// (as the merged rays weigh their pixels).
float carving_weight(const BlockUpdate& frame, float measured_depth, float voxel_depth) {
  const float w = observation_weight(frame.config.weighting, measured_depth);
  if (frame.config.integrator != TsdfIntegrator::kAlongRay) return w;
  const float footprint = frame.config.voxel_size / voxel_depth;
  return w * std::max(1.0f, frame.intrinsics.fx * footprint * frame.intrinsics.fy * footprint);
}

// Carves the block's voxels that lie in the frame's observed free space; returns how many.
std::size_t carve_block(TsdfBlock& block, const BlockUpdate& frame,
                        const DepthBoundsPyramid& depth) {
  const float voxel = frame.config.voxel_size, truncation = frame.config.truncation();
  BlockProjection projection;
  project_block(block.coords * kTsdfBlockSide, frame, projection);
  // A voxel's cell projects within this many pixels of its centre, times 1 / (z - cell radius).
  const float cell_radius = kHalfDiagonal * voxel;
  const float spread = cell_radius * std::max(frame.intrinsics.fx, frame.intrinsics.fy);
  const auto width = static_cast<float>(frame.width), height = static_cast<float>(frame.height);
  std::size_t carved = 0;
  for (std::size_t i = 0; i < kTsdfBlockVoxels; ++i) {
    TsdfVoxel& v = block.voxels[i];
    if (v.weight > 0.0f && !(v.distance < truncation)) continue;  // seen free already
    const float pz = projection.z[i];
    if (!(pz > 2.0f * cell_radius)) continue;
    // As the projective update: the voxel's own position must fall inside the image; its
    // cell's rectangle (a pixel wider each side) is clipped to the image.
    const float uf = projection.u[i] + 0.5f, vf = projection.v[i] + 0.5f;
    if (!(uf >= 0.0f && vf >= 0.0f && uf < width && vf < height)) continue;
    const float r = spread / (pz - cell_radius) + 1.0f;
    const float behind = depth
                             .bounds_over(static_cast<int>(std::max(uf - r, 0.0f)),
                                          static_cast<int>(std::max(vf - r, 0.0f)),
                                          static_cast<int>(std::min(uf + r, width - 1.0f)),
                                          static_cast<int>(std::min(vf + r, height - 1.0f)))
                             .min;
    if (!(behind >= pz + truncation)) continue;
    const float w = carving_weight(frame, behind, pz);
    const float total = v.weight + w;
    v.distance = (v.distance * v.weight + truncation * w) / total;
    v.weight = std::min(total, frame.config.max_weight);
    ++carved;
  }
  return carved;
}

}  // namespace

void TsdfFrameIntegrator::carve_free_blocks(TsdfMap& map, const DepthFrame& frame,
                                            const Image& depth,
                                            const std::vector<std::uint32_t>& touched,
                                            IntegrationStats& stats) {
  depth_bounds_.build(band_pixels_.data(), 2, depth.cols(), depth.rows());
  const float deepest = depth_bounds_.whole_image().max;
  if (!(deepest > 0.0f)) return;  // nothing measured: nothing seen free
  const BlockBox frustum = frustum_blocks(frame, deepest, config_.voxel_size);
  touched_mark_.assign(map.block_count(), 0);
  for (std::uint32_t b : touched) touched_mark_[b] = 1;
  const BlockUpdate view{band_pixels_.data(),
                         depth.cols(),
                         depth.rows(),
                         nullptr,
                         nullptr,
                         frame.intrinsics,
                         frame.T_world_camera.inverse(),
                         config_,
                         0.0f};  // carving updates no voxel behind a surface
  const float voxel = config_.voxel_size, truncation = config_.truncation();
  const float block_radius = kHalfDiagonal * static_cast<float>(kTsdfBlockSide - 1) * voxel;
  const std::uint64_t generation = map.generation();   // the frame's (its band's update began it)
  using Counts = std::pair<std::size_t, std::size_t>;  // blocks carved, voxels carved
  const Counts counts = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, map.block_count()), Counts{0, 0},
      [&](const tbb::blocked_range<std::size_t>& range, Counts sum) {
        for (std::size_t b = range.begin(); b != range.end(); ++b) {
          if (touched_mark_[b]) continue;
          TsdfBlock& block = map.block_for_update(b);
          if ((block.coords.array() < frustum.lo.array()).any() ||
              (block.coords.array() > frustum.hi.array()).any())
            continue;
          const Eigen::Vector3f first =
              block.coords.cast<float>() * static_cast<float>(kTsdfBlockSide);
          const Eigen::Vector3f centre =
              view.T_camera_world *
              ((first.array() + 0.5f * (kTsdfBlockSide - 1)) * voxel).matrix();
          PixelRect rect{};
          if (!sphere_pixels(centre, block_radius, view, rect)) continue;
          // Some measured pixel must lie a truncation behind the block's nearest voxel.
          if (!(depth_bounds_.bounds_over(rect.u0, rect.v0, rect.u1, rect.v1).max >=
                centre.z() - block_radius + truncation) ||
              !holds_surface(block))
            continue;
          const std::size_t voxels = carve_block(block, view, depth_bounds_);
          if (voxels == 0) continue;
          block.modified = generation;
          ++sum.first;
          sum.second += voxels;
        }
        return sum;
      },
      [](Counts a, const Counts& b) {
        a.first += b.first;
        a.second += b.second;
        return a;
      });
  stats.blocks_carved += counts.first;
  stats.voxels_updated += counts.second;
}

}  // namespace meshflow
