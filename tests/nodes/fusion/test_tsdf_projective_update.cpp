#include "nodes/fusion/tsdf_projective_update.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <utility>
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
      d += frame.slopes[4 * pixel + 2] * (uf - static_cast<float>(u)) +
           frame.slopes[4 * pixel + 3] * (vf - static_cast<float>(v));
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

// Updates `block` with update_block() and a copy with the oracle: same count, same bits.
// Returns the count.
std::size_t expect_oracle_update(TsdfBlock& block, const BlockUpdate& frame) {
  TsdfBlock expected = block;
  const std::size_t want = update_block_voxel_by_voxel(expected, frame);
  EXPECT_EQ(update_block(block, frame), want);
  for (std::size_t i = 0; i < kTsdfBlockVoxels; ++i) {
    const TsdfVoxel &a = block.voxels[i], &b = expected.voxels[i];
    EXPECT_TRUE(voxel_same_bits(a.distance, b.distance) && voxel_same_bits(a.weight, b.weight) &&
                a.color == b.color)
        << "block (" << block.coords.transpose() << ") voxel " << i;
  }
  return want;
}

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
  std::vector<float> pixels(2 * width * height), slopes(4 * width * height);
  Image color(height, width, PixelFormat::RGB8);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const std::size_t p = static_cast<std::size_t>(v * width + u);
      const bool hole = unit(rng) < 0.1f;
      pixels[2 * p] = hole ? 0.0f : 0.3f + 0.4f * unit(rng) + 0.002f * static_cast<float>(u);
      pixels[2 * p + 1] = hole ? 0.0f : 0.02f + 0.02f * unit(rng);
      slopes[4 * p] = pixels[2 * p];  // depth_slopes()' records: depth, band, du, dv
      slopes[4 * p + 1] = pixels[2 * p + 1];
      slopes[4 * p + 2] = hole ? 0.0f : 0.02f * (unit(rng) - 0.5f);
      slopes[4 * p + 3] = hole ? 0.0f : 0.02f * (unit(rng) - 0.5f);
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
              updated += expect_oracle_update(block, frame);
            }
      }
  EXPECT_GT(updated, 20000u);  // the blocks reach the band, not only empty space
}

// Images of one, two and six pixels with colour, every voxel of two blocks landing on them: the
// colour of the last pixel (read without passing the image's end) and of a one-pixel image
// blend as the oracle's.
TEST(TsdfProjectiveUpdate, FusesTheColourOfTheLastPixelAndOfOnePixelImages) {
  for (const auto& [width, height] : {std::pair{1, 1}, std::pair{2, 1}, std::pair{3, 2}}) {
    PinholeIntrinsics k;
    k.width = width;
    k.height = height;
    k.fx = k.fy = 0.5f;  // a block 0.4 m away spans a tenth of a pixel each side of the centre
    k.cx = 0.5f * static_cast<float>(width - 1);
    k.cy = 0.5f * static_cast<float>(height - 1);
    const auto n = static_cast<std::size_t>(width * height);
    std::vector<float> pixels(2 * n);
    Image color(height, width, PixelFormat::RGB8);
    for (std::size_t p = 0; p < n; ++p) {
      pixels[2 * p] = 0.45f;
      pixels[2 * p + 1] = 0.02f;
      const auto c = static_cast<std::uint8_t>(40 * p + 17);
      color.data()[3 * p] = c;
      color.data()[3 * p + 1] = static_cast<std::uint8_t>(c + 100);
      color.data()[3 * p + 2] = static_cast<std::uint8_t>(c + 200);
    }
    TsdfConfig config;
    config.voxel_size = 0.01f;
    const BlockUpdate frame{
        pixels.data(), width, height, nullptr, &color, k, Eigen::Isometry3f::Identity(),
        config,        0.0f};
    std::size_t updated = 0;
    for (const int x : {-1, 0}) {
      TsdfBlock block;
      block.coords = Eigen::Vector3i(x, -1, 5);  // z 0.40 .. 0.47 m: sdf -0.02 .. 0.05 m
      for (std::size_t i = 0; i < kTsdfBlockVoxels; ++i) {
        block.voxels[i].weight = static_cast<float>(i % 3);
        block.voxels[i].color = Rgb8{static_cast<std::uint8_t>(i), 9, 250};
      }
      updated += expect_oracle_update(block, frame);
    }
    EXPECT_EQ(updated, 2 * kTsdfBlockVoxels) << width << " x " << height;
  }
}

// depth_slopes() (eight pixels at a time) against the rule one pixel at a time, on rows that are
// no multiple of eight pixels, with holes and depth edges: each record is the pixel's depth and
// band and the oracle's slopes, bit for bit.
TEST(TsdfProjectiveUpdate, DepthSlopesMatchThePixelByPixelRule) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (const auto& size : {std::pair{1, 1}, std::pair{9, 2}, std::pair{37, 5}}) {
    const int width = size.first, height = size.second;  // (lambdas below capture them)
    std::vector<float> pixels(2 * static_cast<std::size_t>(width * height));
    for (std::size_t p = 0; p < pixels.size() / 2; ++p) {
      const float r = unit(rng);
      pixels[2 * p] = r < 0.15f ? 0.0f : (r < 0.3f ? 2.0f : 1.0f) + 0.01f * unit(rng);
      pixels[2 * p + 1] = 0.01f + 0.02f * unit(rng);
    }
    const float one_surface = 0.03f;
    std::vector<float> slopes;
    depth_slopes(pixels, width, height, one_surface, slopes);
    ASSERT_EQ(slopes.size(), 2 * pixels.size());
    const auto depth = [&](int u, int v) {
      const bool inside = u >= 0 && v >= 0 && u < width && v < height;
      return inside ? pixels[2 * static_cast<std::size_t>(v * width + u)] : 0.0f;
    };
    const auto slope = [&](float before, float d, float after) {
      const bool b = before > 0.0f && std::abs(before - d) <= one_surface * d;
      const bool a = after > 0.0f && std::abs(after - d) <= one_surface * d;
      return a && b ? 0.5f * (after - before) : a ? after - d : b ? d - before : 0.0f;
    };
    for (int v = 0; v < height; ++v)
      for (int u = 0; u < width; ++u) {
        const float d = depth(u, v);
        const std::size_t p = static_cast<std::size_t>(v * width + u);
        const float du = d > 0.0f ? slope(depth(u - 1, v), d, depth(u + 1, v)) : 0.0f;
        const float dv = d > 0.0f ? slope(depth(u, v - 1), d, depth(u, v + 1)) : 0.0f;
        EXPECT_TRUE(voxel_same_bits(slopes[4 * p], pixels[2 * p]) &&
                    voxel_same_bits(slopes[4 * p + 1], pixels[2 * p + 1]) &&
                    voxel_same_bits(slopes[4 * p + 2], du) &&
                    voxel_same_bits(slopes[4 * p + 3], dv))
            << "pixel (" << u << ", " << v << ")";
      }
  }
}

}  // namespace
}  // namespace meshflow
