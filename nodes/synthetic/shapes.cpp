#include "nodes/synthetic/shapes.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace meshflow::synthetic {
namespace {

void add_noise(PointCloud& cloud, float sigma, std::uint32_t seed) {
  if (sigma <= 0.0f) return;
  std::mt19937 rng(seed);
  std::normal_distribution<float> gauss(0.0f, sigma);
  for (auto& p : cloud.positions) p += Eigen::Vector3f(gauss(rng), gauss(rng), gauss(rng));
}

// Regular grid of points on the rectangle origin + s*u + t*v, s in [0,1], t in [0,1].
void sample_rectangle(const Eigen::Vector3f& origin, const Eigen::Vector3f& u,
                      const Eigen::Vector3f& v, float spacing, PointCloud& out) {
  const int nu = std::max(1, static_cast<int>(std::ceil(u.norm() / spacing)));
  const int nv = std::max(1, static_cast<int>(std::ceil(v.norm() / spacing)));
  for (int j = 0; j <= nv; ++j) {
    for (int i = 0; i <= nu; ++i) {
      out.positions.push_back(origin + u * (static_cast<float>(i) / static_cast<float>(nu)) +
                              v * (static_cast<float>(j) / static_cast<float>(nv)));
    }
  }
}

}  // namespace

float signed_distance(const Box& box, const Eigen::Vector3f& p) {
  const Eigen::Vector3f q = (p - box.center).cwiseAbs() - box.half_size;
  const float outside = q.cwiseMax(0.0f).norm();
  const float inside = std::min(q.maxCoeff(), 0.0f);
  return outside + inside;
}

float surface_distance(const Sphere& s, const Eigen::Vector3f& p) {
  return std::abs((p - s.center).norm() - s.radius);
}

float surface_distance(const Box& b, const Eigen::Vector3f& p) {
  return std::abs(signed_distance(b, p));
}

float surface_distance(const StepPlane& s, const Eigen::Vector3f& p) {
  // Distance in the xz cross-section to the polyline (-inf,0)-(0,0)-(0,h)-(+inf,h).
  const float x = p.x(), z = p.z();
  const float lower = x <= 0.0f ? std::abs(z) : std::hypot(x, z);
  const float upper = x >= 0.0f ? std::abs(z - s.height) : std::hypot(x, z - s.height);
  const float wall = std::hypot(x, z < 0.0f ? z : (z > s.height ? z - s.height : 0.0f));
  return std::min({lower, upper, wall});
}

PointCloud sample_surface(const Sphere& s, float spacing, float noise_sigma, std::uint32_t seed) {
  PointCloud cloud;
  const double area = 4.0 * M_PI * s.radius * s.radius;
  const int n = std::max(16, static_cast<int>(area / (spacing * spacing)));
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {  // Fibonacci lattice: near-uniform spacing
    const double z = 1.0 - 2.0 * (i + 0.5) / n;
    const double r = std::sqrt(1.0 - z * z);
    const double phi = golden * i;
    cloud.positions.push_back(
        s.center +
        s.radius * Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z).cast<float>());
  }
  add_noise(cloud, noise_sigma, seed);
  return cloud;
}

PointCloud sample_surface(const Box& b, float spacing, float noise_sigma, std::uint32_t seed) {
  PointCloud cloud;
  const Eigen::Vector3f lo = b.center - b.half_size;
  const Eigen::Vector3f size = 2.0f * b.half_size;
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Vector3f u = Eigen::Vector3f::Unit((axis + 1) % 3) * size[(axis + 1) % 3];
    const Eigen::Vector3f v = Eigen::Vector3f::Unit((axis + 2) % 3) * size[(axis + 2) % 3];
    sample_rectangle(lo, u, v, spacing, cloud);
    sample_rectangle(lo + Eigen::Vector3f::Unit(axis) * size[axis], u, v, spacing, cloud);
  }
  add_noise(cloud, noise_sigma, seed);
  return cloud;
}

PointCloud sample_surface(const StepPlane& s, float spacing, float noise_sigma,
                          std::uint32_t seed) {
  PointCloud cloud;
  const float e = s.half_extent;
  sample_rectangle({-e, -e, 0.0f}, {e, 0, 0}, {0, 2 * e, 0}, spacing, cloud);
  sample_rectangle({0.0f, -e, s.height}, {e, 0, 0}, {0, 2 * e, 0}, spacing, cloud);
  sample_rectangle({0.0f, -e, 0.0f}, {0, 0, s.height}, {0, 2 * e, 0}, spacing, cloud);
  add_noise(cloud, noise_sigma, seed);
  return cloud;
}

}  // namespace meshflow::synthetic
