#include "nodes/filter/spatial_order.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "runtime/radix_sort.h"

namespace meshflow {
namespace {

// Spreads the low 21 bits of v so that bit i moves to bit 3 i.
std::uint64_t spread_bits(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffff;
  v = (v | v << 16) & 0x1f0000ff0000ff;
  v = (v | v << 8) & 0x100f00f00f00f00f;
  v = (v | v << 4) & 0x10c30c30c30c30c3;
  v = (v | v << 2) & 0x1249249249249249;
  return v;
}

int bits_for(std::size_t n) {
  int bits = 1;
  while (bits < 32 && (std::size_t{1} << bits) < n) ++bits;
  return bits;
}

}  // namespace

std::vector<std::uint32_t> morton_order(const PointCloud& cloud) {
  const std::size_t n = cloud.size();
  const Eigen::AlignedBox3f box = finite_bounds(cloud);
  // The key holds the Morton code above the index: as many code bits per axis as fit.
  const int index_bits = bits_for(n);
  const int axis_bits = std::min(21, (64 - index_bits) / 3);
  const float cells = static_cast<float>((1u << axis_bits) - 1);
  const Eigen::Vector3f extent =
      box.isEmpty() ? Eigen::Vector3f(Eigen::Vector3f::Ones()) : Eigen::Vector3f(box.sizes());
  const Eigen::Vector3f scale = cells * extent.cwiseMax(1e-30f).cwiseInverse();
  const Eigen::Vector3f low = box.isEmpty() ? Eigen::Vector3f(Eigen::Vector3f::Zero()) : box.min();
  std::vector<std::uint64_t> keys(n);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, n, 8192), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const Eigen::Vector3f& p = cloud.positions[i];
          const Eigen::Vector3f q =
              p.allFinite()
                  ? Eigen::Vector3f((p - low).cwiseProduct(scale).cwiseMax(0.0f).cwiseMin(cells))
                  : Eigen::Vector3f::Zero();
          const std::uint64_t code = spread_bits(static_cast<std::uint64_t>(q.x())) |
                                     spread_bits(static_cast<std::uint64_t>(q.y())) << 1 |
                                     spread_bits(static_cast<std::uint64_t>(q.z())) << 2;
          keys[i] = code << index_bits | i;
        }
      });
  radix_sort(keys);
  std::vector<std::uint32_t> order(n);
  const std::uint64_t index_mask = (std::uint64_t{1} << index_bits) - 1;
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    order[i] = static_cast<std::uint32_t>(keys[i] & index_mask);
  });
  return order;
}

PointCloud in_morton_order(const PointCloud& cloud) {
  if (cloud.is_organized()) return cloud;
  return select_points(cloud, morton_order(cloud));
}

}  // namespace meshflow
