#include "runtime/point_cloud.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

namespace meshflow {
namespace {
template <typename T>
void gather(const std::vector<T>& in, const std::vector<std::uint32_t>& indices,
            std::vector<T>& out) {
  if (in.empty()) return;
  out.resize(indices.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, indices.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) out[i] = in[indices[i]];
                    });
}
}  // namespace

PointCloud select_points(const PointCloud& cloud, const std::vector<std::uint32_t>& indices) {
  PointCloud out;
  gather(cloud.positions, indices, out.positions);
  gather(cloud.normals, indices, out.normals);
  gather(cloud.colors, indices, out.colors);
  gather(cloud.intensities, indices, out.intensities);
  copy_frame_description(cloud, out);
  return out;
}

void copy_frame_description(const PointCloud& from, PointCloud& to) {
  to.sensor_origin = from.sensor_origin;
  to.origin = from.origin;
  to.has_sensor_origin = from.has_sensor_origin;
  to.z_up = from.z_up;
}

std::size_t count_finite_points(const PointCloud& cloud) {
  std::size_t n = 0;
  for (const auto& p : cloud.positions) n += p.allFinite() ? 1 : 0;
  return n;
}

Eigen::AlignedBox3f finite_bounds(const PointCloud& cloud) {
  // Blocks joined in order, the earlier box first: the serial loop's result, bit for bit.
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, cloud.positions.size(), 16384), Eigen::AlignedBox3f(),
      [&](const tbb::blocked_range<std::size_t>& r, Eigen::AlignedBox3f box) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const Eigen::Vector3f& p = cloud.positions[i];
          if (p.allFinite()) box.extend(p);
        }
        return box;
      },
      [](Eigen::AlignedBox3f a, const Eigen::AlignedBox3f& b) { return a.extend(b); });
}

}  // namespace meshflow
