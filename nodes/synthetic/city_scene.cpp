#include "nodes/synthetic/city_scene.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "nodes/synthetic/hashed_noise.h"
#include "runtime/error.h"

namespace meshflow::synthetic {
namespace {

std::uint64_t mix(std::uint64_t x) {  // SplitMix64 finaliser
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Uniform in [0, 1) from a key.
float uniform(std::uint64_t key) {
  return static_cast<float>(mix(key) >> 40) * (1.0f / 16777216.0f);
}

std::uint64_t key_of(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  return mix(mix(mix(a) ^ b) ^ c);
}

constexpr int kWallQuadrature = 256;  // samples along a wall for its visible area
constexpr std::uint64_t kMaxBatch = 1u << 20;

}  // namespace

CityScene::CityScene(const CitySceneConfig& config) : config_(config) {
  if (!(config.size > 0.0f) || !(config.block > 0.0f) || !(config.relief >= 0.0f) ||
      !std::isfinite(config.size) || !std::isfinite(config.block) ||
      !std::isfinite(config.relief)) {
    throw Error("city scene", "config", "size and block must be positive, relief non-negative");
  }
  const int blocks = std::max(1, static_cast<int>(std::lround(config.size / config.block)));
  const float pitch = config.size / static_cast<float>(blocks);
  const float half = 0.5f * config.size;
  for (int j = 0; j < blocks; ++j) {
    for (int i = 0; i < blocks; ++i) {
      const Eigen::Vector2f lo(-half + static_cast<float>(i) * pitch,
                               -half + static_cast<float>(j) * pitch);
      const Eigen::Vector2f hi = lo + Eigen::Vector2f::Constant(pitch);
      const std::uint64_t k =
          key_of(config.seed, static_cast<std::uint64_t>(i), static_cast<std::uint64_t>(j));
      // Footprint 40-76 % of the pitch per axis (streets of at least 12 %), height 8-40 m.
      const float hx = pitch * (0.20f + 0.18f * uniform(k + 1));
      const float hy = pitch * (0.20f + 0.18f * uniform(k + 2));
      const float height = 8.0f + 32.0f * uniform(k + 3);
      const Eigen::Vector2f c = 0.5f * (lo + hi);
      float lowest = terrain_height(c.x(), c.y());
      for (int a = 0; a <= 8; ++a) {
        for (int b = 0; b <= 8; ++b) {
          lowest = std::min(lowest, terrain_height(c.x() - hx + 2.0f * hx * a / 8.0f,
                                                   c.y() - hy + 2.0f * hy * b / 8.0f));
        }
      }
      const float bottom = lowest - 2.0f;  // buried: every wall meets the ground
      const float top = terrain_height(c.x(), c.y()) + height;
      Box box;
      box.center = Eigen::Vector3f(c.x(), c.y(), 0.5f * (bottom + top));
      box.half_size = Eigen::Vector3f(hx, hy, 0.5f * (top - bottom));
      const int building = static_cast<int>(buildings_.size());
      buildings_.push_back(box);

      Patch terrain{Patch::kTerrain, building, 0, lo, hi, 0.0};
      terrain.area = static_cast<double>(pitch) * pitch - 4.0 * hx * hy;
      patches_.push_back(terrain);
      for (int side = 0; side < 4; ++side) {
        Patch wall{Patch::kWall, building, side, lo, hi, wall_area(building, side)};
        patches_.push_back(wall);
      }
      Patch roof{Patch::kRoof, building, 0, lo, hi, 4.0 * hx * hy};
      patches_.push_back(roof);
    }
  }
  for (const Patch& p : patches_) area_ += p.area;
}

float CityScene::terrain_height(float x, float y) const {
  const float r = config_.relief;
  return r * (0.5f * std::sin(x / 37.0f + 0.3f) + 0.3f * std::cos(y / 53.0f) +
              0.2f * std::sin((x + y) / 29.0f));
}

Eigen::Vector3f CityScene::terrain_normal(float x, float y) const {
  const float r = config_.relief;
  const float c3 = 0.2f * std::cos((x + y) / 29.0f) / 29.0f;
  const float dx = r * (0.5f * std::cos(x / 37.0f + 0.3f) / 37.0f + c3);
  const float dy = r * (-0.3f * std::sin(y / 53.0f) / 53.0f + c3);
  return Eigen::Vector3f(-dx, -dy, 1.0f).normalized();
}

bool CityScene::in_footprint(float x, float y) const {
  // Each building lies inside its own block: find the block, test its box.
  const int blocks = std::max(1, static_cast<int>(std::lround(config_.size / config_.block)));
  const float pitch = config_.size / static_cast<float>(blocks);
  const int i = std::clamp(static_cast<int>((x + 0.5f * config_.size) / pitch), 0, blocks - 1);
  const int j = std::clamp(static_cast<int>((y + 0.5f * config_.size) / pitch), 0, blocks - 1);
  const Box& b = buildings_[static_cast<std::size_t>(j * blocks + i)];
  return std::abs(x - b.center.x()) < b.half_size.x() &&
         std::abs(y - b.center.y()) < b.half_size.y();
}

double CityScene::wall_area(int building, int side) const {
  const Box& b = buildings_[static_cast<std::size_t>(building)];
  const float top = b.center.z() + b.half_size.z();
  const bool along_y = side < 2;  // walls at x = const run along y
  const float sign = (side % 2 == 0) ? -1.0f : 1.0f;
  const float length = 2.0f * (along_y ? b.half_size.y() : b.half_size.x());
  double sum = 0.0;
  for (int q = 0; q < kWallQuadrature; ++q) {
    const float t = (static_cast<float>(q) + 0.5f) / kWallQuadrature;
    const float x = along_y ? b.center.x() + sign * b.half_size.x()
                            : b.center.x() - b.half_size.x() + t * length;
    const float y = along_y ? b.center.y() - b.half_size.y() + t * length
                            : b.center.y() + sign * b.half_size.y();
    sum += std::max(0.0f, top - terrain_height(x, y));
  }
  return sum / kWallQuadrature * length;
}

Eigen::AlignedBox3f CityScene::bounds() const {
  const float half = 0.5f * config_.size;
  float top = -config_.relief;
  for (const Box& b : buildings_) top = std::max(top, b.center.z() + b.half_size.z());
  return Eigen::AlignedBox3f(Eigen::Vector3f(-half, -half, -config_.relief),
                             Eigen::Vector3f(half, half, top));
}

float CityScene::surface_distance(const Eigen::Vector3f& p) const {
  float best = std::numeric_limits<float>::infinity();
  if (!in_footprint(p.x(), p.y())) {
    const Eigen::Vector3f n = terrain_normal(p.x(), p.y());
    best = std::abs(p.z() - terrain_height(p.x(), p.y())) * n.z();
  }
  for (const Box& b : buildings_) {
    // Only boxes within `best` can be nearer: skip the rest by their bounding distance.
    const Eigen::Vector3f d = ((p - b.center).cwiseAbs() - b.half_size).cwiseMax(0.0f);
    if (d.norm() >= best) continue;
    best = std::min(best, synthetic::surface_distance(b, p));
  }
  return best;
}

void CityScene::sample_patch(const Patch& patch, std::uint64_t index, std::uint64_t count,
                             float noise, PointCloud& out) const {
  const std::size_t base = out.positions.size();
  out.positions.resize(base + count);
  out.normals.resize(base + count);
  const Box* b =
      patch.building >= 0 ? &buildings_[static_cast<std::size_t>(patch.building)] : nullptr;
  const std::uint64_t patch_key =
      key_of(config_.seed, 0x5eedULL, static_cast<std::uint64_t>(&patch - patches_.data()));
  tbb::parallel_for(std::uint64_t{0}, count, [&](std::uint64_t s) {
    const std::uint64_t sample = index + s;
    Eigen::Vector3f p, n;
    for (std::uint64_t attempt = 0;; ++attempt) {  // rejection: hidden parts
      const std::uint64_t k = key_of(patch_key, sample, attempt);
      const float u = uniform(k), v = uniform(k + 1);
      if (patch.kind == Patch::kTerrain) {
        const float x = patch.lo.x() + u * (patch.hi.x() - patch.lo.x());
        const float y = patch.lo.y() + v * (patch.hi.y() - patch.lo.y());
        if (in_footprint(x, y)) continue;
        p = Eigen::Vector3f(x, y, terrain_height(x, y));
        n = terrain_normal(x, y);
        break;
      }
      const float top = b->center.z() + b->half_size.z();
      if (patch.kind == Patch::kRoof) {
        p = Eigen::Vector3f(b->center.x() + (2.0f * u - 1.0f) * b->half_size.x(),
                            b->center.y() + (2.0f * v - 1.0f) * b->half_size.y(), top);
        n = Eigen::Vector3f::UnitZ();
        break;
      }
      const int axis = patch.side < 2 ? 0 : 1;
      const float sign = (patch.side % 2 == 0) ? -1.0f : 1.0f;
      p = b->center;
      p[axis] += sign * b->half_size[axis];
      p[1 - axis] += (2.0f * u - 1.0f) * b->half_size[1 - axis];
      p.z() = b->center.z() - b->half_size.z() + v * 2.0f * b->half_size.z();
      if (p.z() < terrain_height(p.x(), p.y())) continue;
      n = Eigen::Vector3f::Zero();
      n[axis] = sign;
      break;
    }
    if (noise > 0.0f) p += n * (noise * hashed_gaussian(key_of(patch_key, sample, ~0ULL)));
    out.positions[base + s] = p;
    out.normals[base + s] = n;
  });
}

void CityScene::sample(std::uint64_t points, float noise_sigma,
                       const std::function<void(const PointCloud& batch)>& sink) const {
  // Largest-remainder apportionment: exactly `points` in all, each patch by its area.
  std::vector<std::uint64_t> counts(patches_.size());
  std::uint64_t assigned = 0;
  for (std::size_t i = 0; i < patches_.size(); ++i) {
    counts[i] = static_cast<std::uint64_t>(static_cast<double>(points) * patches_[i].area / area_);
    assigned += counts[i];
  }
  for (std::size_t i = 0; assigned < points; i = (i + 1) % patches_.size(), ++assigned) ++counts[i];

  PointCloud batch;
  for (std::size_t i = 0; i < patches_.size(); ++i) {
    for (std::uint64_t done = 0; done < counts[i];) {
      const std::uint64_t n = std::min(kMaxBatch, counts[i] - done);
      sample_patch(patches_[i], done, n, noise_sigma, batch);
      done += n;
      if (batch.size() >= kMaxBatch / 2) {
        sink(batch);
        batch.positions.clear();
        batch.normals.clear();
      }
    }
  }
  if (!batch.positions.empty()) sink(batch);
}

}  // namespace meshflow::synthetic
