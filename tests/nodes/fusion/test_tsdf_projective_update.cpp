#include "nodes/fusion/tsdf_projective_update.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <vector>

#include "nodes/fusion/tsdf_band.h"

namespace meshflow {
namespace {

// The projective rule one voxel at a time, as update_block() applied it before it blended eight
// voxels per vector (with the held band for observed voxels since): the oracle its vector code
// must match bit for bit.
std::size_t update_block_voxel_by_voxel(TsdfBlock& block, const BlockUpdate& frame) {
  const std::size_t width = static_cast<std::size_t>(frame.width);
  const float max_u = static_cast<float>(frame.width) - 0.5f;
  const float max_v = static_cast<float>(frame.height) - 0.5f;
  const float truncation = frame.config.truncation();
  BlockProjection projection;
  project_block(block.coords * kTsdfBlockSide, frame, projection);
  std::size_t count = 0;
  for (std::size_t i = 0; i < kTsdfBlockVoxels; ++i) {
    const float pz = projection.z[i];
    if (!(pz > 0.0f)) continue;
    const float uf = projection.u[i], vf = projection.v[i];
    if (!(uf > -0.5f && vf > -0.5f && uf < max_u && vf < max_v)) continue;
    const int u = static_cast<int>(uf + 0.5f), v = static_cast<int>(vf + 0.5f);
    const std::size_t pixel = static_cast<std::size_t>(v) * width + static_cast<std::size_t>(u);
    float d = frame.pixels[2 * pixel];
    if (!(d > 0.0f)) continue;
    const float least = frame.config.behind_voxels * frame.config.voxel_size;
    const float noise = frame.noise_band_per_depth2 * d * d;
    const float held = noise < least ? least : noise;
    if (frame.slopes != nullptr)
      d += frame.slopes[2 * pixel] * (uf - static_cast<float>(u)) +
           frame.slopes[2 * pixel + 1] * (vf - static_cast<float>(v));
    const float sdf = d - pz;
    if (sdf < -frame.pixels[2 * pixel + 1]) continue;
    TsdfVoxel& vox = block.voxels[i];
    if (vox.weight > 0.0f && sdf < -held) continue;  // observed: only the held band
    const float w = observation_weight(frame.config.weighting, d);
    const float total = vox.weight + w;
    const float inv_total = 1.0f / total;
    vox.distance = (vox.distance * vox.weight + std::min(sdf, truncation) * w) * inv_total;
    if (frame.color != nullptr) {
      const Rgb8 c = frame.color->at<Rgb8>(v, u);
      auto blend = [&](std::uint8_t old, std::uint8_t now) {
        return static_cast<std::uint8_t>(
            (static_cast<float>(old) * vox.weight + static_cast<float>(now) * w) * inv_total +
            0.5f);
      };
      vox.color = Rgb8{blend(vox.color.r, c.r), blend(vox.color.g, c.g), blend(vox.color.b, c.b)};
    }
    vox.weight = std::min(total, frame.config.max_weight);
    ++count;
  }
  return count;
}

bool voxel_same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Random frames (depth with holes, steep slopes, colour) seen by blocks all around the camera
// (behind it, across the image's edges, in front and behind the surface) whose voxels hold
// random earlier states: update_block() gives each voxel exactly the oracle's bits, with and
// without slopes and colour, under both weightings, and counts the same voxels.
TEST(TsdfProjectiveUpdate, BlendsEightVoxelsExactlyAsOneAtATime) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const int width = 64, height = 48;
  PinholeIntrinsics k;
  k.width = width;
  k.height = height;
  k.fx = k.fy = 50.0f;
  k.cx = 31.5f;
  k.cy = 23.5f;
  std::vector<float> pixels(2 * width * height), slopes(2 * width * height);
  Image color(height, width, PixelFormat::RGB8);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t p = static_cast<std::size_t>(v * width + u);
      const bool hole = unit(rng) < 0.1f;
      pixels[2 * p] = hole ? 0.0f : 0.3f + 0.4f * unit(rng) + 0.002f * static_cast<float>(u);
      pixels[2 * p + 1] = hole ? 0.0f : 0.02f + 0.02f * unit(rng);
      slopes[2 * p] = hole ? 0.0f : 0.02f * (unit(rng) - 0.5f);
      slopes[2 * p + 1] = hole ? 0.0f : 0.02f * (unit(rng) - 0.5f);
      color.at<Rgb8>(v, u) =
          Rgb8{static_cast<std::uint8_t>(rng() & 255), static_cast<std::uint8_t>(rng() & 255),
               static_cast<std::uint8_t>(rng() & 255)};
    }
  std::size_t updated = 0;
  for (const TsdfWeighting weighting : {TsdfWeighting::kConstant, TsdfWeighting::kInverseDepth})
    for (const bool with_slopes : {false, true})
      for (const bool with_color : {false, true}) {
        TsdfConfig config;
        config.voxel_size = 0.01f;
        config.weighting = weighting;
        config.max_weight = 5.0f;
        Eigen::Isometry3f T_world_camera = Eigen::Isometry3f::Identity();
        T_world_camera.rotate(Eigen::AngleAxisf(0.3f, Eigen::Vector3f(1, 2, 3).normalized()));
        T_world_camera.translation() = Eigen::Vector3f(0.013f, -0.021f, 0.007f);
        const BlockUpdate frame{pixels.data(),
                                width,
                                height,
                                with_slopes ? slopes.data() : nullptr,
                                with_color ? &color : nullptr,
                                k,
                                T_world_camera.inverse(),
                                config,
                                0.05f};  // held band max(2 cm, 0.05 depth^2): both win
        for (int z = -2; z <= 8; ++z)
          for (int y = -6; y <= 5; y += 2)
            for (int x = -7; x <= 6; x += 3) {
              TsdfBlock block;
              block.coords = Eigen::Vector3i(x, y, z);
              for (TsdfVoxel& vox : block.voxels) {
                const bool seen = unit(rng) < 0.7f;
                vox.weight = seen ? std::floor(1.0f + 6.0f * unit(rng)) : 0.0f;
                vox.distance = seen ? 0.04f * (unit(rng) - 0.5f) : 0.0f;
                vox.color = Rgb8{static_cast<std::uint8_t>(rng() & 255),
                                 static_cast<std::uint8_t>(rng() & 255),
                                 static_cast<std::uint8_t>(rng() & 255)};
              }
              TsdfBlock expected = block;
              const std::size_t want = update_block_voxel_by_voxel(expected, frame);
              ASSERT_EQ(update_block(block, frame), want);
              updated += want;
              for (std::size_t i = 0; i < kTsdfBlockVoxels; ++i) {
                const TsdfVoxel &a = block.voxels[i], &b = expected.voxels[i];
                ASSERT_TRUE(voxel_same_bits(a.distance, b.distance) &&
                            voxel_same_bits(a.weight, b.weight) && a.color == b.color)
                    << "block (" << x << ", " << y << ", " << z << ") voxel " << i;
              }
            }
      }
  EXPECT_GT(updated, 20000u);  // the blocks reach the band, not only empty space
}

}  // namespace
}  // namespace meshflow
