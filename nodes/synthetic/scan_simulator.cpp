#include "nodes/synthetic/scan_simulator.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include <limits>
#include "nodes/synthetic/hashed_noise.h"

namespace meshflow::synthetic {
namespace {

constexpr float kNoHit = std::numeric_limits<float>::infinity();

// Ray/slab interval of an axis-aligned box: [t_near, t_far] (empty if t_near > t_far).
std::pair<float, float> slab(const Box& b, const Eigen::Vector3f& o, const Eigen::Vector3f& d) {
  float t0 = -kNoHit, t1 = kNoHit;
  for (int a = 0; a < 3; ++a) {
    const float lo = b.center[a] - b.half_size[a], hi = b.center[a] + b.half_size[a];
    if (std::abs(d[a]) < 1e-12f) {
      if (o[a] < lo || o[a] > hi) return {kNoHit, -kNoHit};
      continue;
    }
    float ta = (lo - o[a]) / d[a], tb = (hi - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return {t0, t1};
}

float hit_sphere(const Sphere& s, const Eigen::Vector3f& o, const Eigen::Vector3f& d) {
  const Eigen::Vector3f oc = o - s.center;
  const float b = oc.dot(d), c = oc.squaredNorm() - s.radius * s.radius;
  const float disc = b * b - c;
  if (disc < 0.0f) return kNoHit;
  const float t = -b - std::sqrt(disc);
  return t > 0.0f ? t : kNoHit;
}

}  // namespace

float cast_ray(const Scene& scene, const Eigen::Vector3f& o, const Eigen::Vector3f& d) {
  float t = slab(scene.room, o, d).second;  // exit through the room's walls
  if (!(t > 0.0f)) t = kNoHit;
  for (const Box& b : scene.boxes) {
    const auto [t0, t1] = slab(b, o, d);
    if (t0 <= t1 && t0 > 0.0f) t = std::min(t, t0);
  }
  for (const Sphere& s : scene.spheres) t = std::min(t, hit_sphere(s, o, d));
  return t;
}

Scene demo_room_scene() {
  Scene s;
  s.room = Box{{0.0f, 0.0f, 1.5f}, {4.0f, 3.0f, 1.5f}};
  s.boxes.push_back(Box{{1.8f, 0.8f, 0.375f}, {0.6f, 0.4f, 0.375f}});  // table-sized block
  s.boxes.push_back(Box{{-3.4f, -2.2f, 0.9f}, {0.5f, 0.6f, 0.9f}});    // cabinet in a corner
  s.spheres.push_back(Sphere{{-1.2f, 1.5f, 0.5f}, 0.5f});              // ball on the floor
  return s;
}

PointCloud simulate_scan(const Scene& scene, const ScanConfig& config) {
  const int na = config.azimuth_steps, ne = config.elevation_steps;
  const std::size_t rays = static_cast<std::size_t>(na) * static_cast<std::size_t>(ne);
  std::vector<Eigen::Vector3f> hits(rays);
  std::vector<std::uint8_t> hit(rays, 0);
  const float e0 = config.min_elevation_deg * static_cast<float>(M_PI) / 180.0f;
  const float e1 = config.max_elevation_deg * static_cast<float>(M_PI) / 180.0f;
  tbb::parallel_for(std::size_t{0}, rays, [&](std::size_t r) {
    const int i = static_cast<int>(r % static_cast<std::size_t>(na));
    const int j = static_cast<int>(r / static_cast<std::size_t>(na));
    const float az =
        2.0f * static_cast<float>(M_PI) * static_cast<float>(i) / static_cast<float>(na);
    const float el =
        ne > 1 ? e0 + (e1 - e0) * static_cast<float>(j) / static_cast<float>(ne - 1) : e0;
    const Eigen::Vector3f d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const Eigen::Vector3f& o = config.origin;
    float t = cast_ray(scene, o, d);
    if (!(t < kNoHit)) return;
    if (config.noise_sigma > 0.0f)
      t += config.noise_sigma * hashed_gaussian((std::uint64_t{config.seed} << 32) ^ r);
    hits[r] = o + t * d;
    hit[r] = 1;
  });
  PointCloud cloud;
  for (std::size_t r = 0; r < rays; ++r) {
    if (hit[r]) cloud.positions.push_back(hits[r]);
  }
  cloud.sensor_origin = config.origin;
  cloud.has_sensor_origin = true;
  return cloud;
}

float surface_distance(const Scene& scene, const Eigen::Vector3f& p) {
  float d = surface_distance(scene.room, p);
  for (const Box& b : scene.boxes) d = std::min(d, surface_distance(b, p));
  for (const Sphere& s : scene.spheres) d = std::min(d, surface_distance(s, p));
  return d;
}

}  // namespace meshflow::synthetic
