#include "nodes/filter/filter.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <cmath>

#include <Eigen/Eigenvalues>

#include "nodes/search/spatial_index.h"
#include "runtime/error.h"
#include "runtime/parallel.h"
#include "runtime/voxel_key.h"

namespace meshflow {

std::vector<std::uint32_t> finite_point_indices(const PointCloud& cloud) {
  return parallel_select_indices(cloud.size(),
                                 [&](std::size_t i) { return cloud.positions[i].allFinite(); });
}

std::vector<std::uint32_t> crop_indices(const PointCloud& cloud, const FilterConfig& config) {
  const bool use_range =
      cloud.has_sensor_origin && (config.min_range > 0.0f || config.max_range > 0.0f);
  const float min2 = config.min_range * config.min_range;
  const float max2 = config.max_range > 0.0f ? config.max_range * config.max_range
                                             : std::numeric_limits<float>::infinity();
  return parallel_select_indices(cloud.size(), [&](std::size_t i) {
    const Eigen::Vector3f& p = cloud.positions[i];
    if ((p.array() < config.crop_min.array()).any() ||
        (p.array() > config.crop_max.array()).any()) {
      return false;
    }
    if (use_range) {
      const float r2 = (p - cloud.sensor_origin).squaredNorm();
      if (r2 < min2 || r2 > max2) return false;
    }
    return true;
  });
}

Eigen::Vector3d principal_extents(const PointCloud& cloud) {
  struct Moments {
    double count = 0.0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d products = Eigen::Matrix3d::Zero();
  };
  const std::size_t n = cloud.size();
  const std::size_t blocks = (n + kParallelBlock - 1) / kParallelBlock;
  std::vector<Moments> partial(blocks);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    Moments& m = partial[b];
    const std::size_t end = std::min(n, (b + 1) * kParallelBlock);
    for (std::size_t i = b * kParallelBlock; i < end; ++i) {
      if (!cloud.positions[i].allFinite()) continue;
      const Eigen::Vector3d p = cloud.positions[i].cast<double>();
      m.count += 1.0;
      m.sum += p;
      m.products.noalias() += p * p.transpose();
    }
  });
  Moments all;
  for (const Moments& m : partial) {
    all.count += m.count;
    all.sum += m.sum;
    all.products += m.products;
  }
  if (all.count < 1.0) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d mean = all.sum / all.count;
  const Eigen::Matrix3d covariance = all.products / all.count - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(covariance);
  return solver.eigenvalues().cwiseMax(0.0).cwiseSqrt();
}

PointCloud voxel_grid_downsample(const PointCloud& cloud, float voxel_size) {
  const std::size_t n = cloud.size();
  // (cell key, point index) pairs are unique, so the sorted order is fully determined.
  std::vector<std::pair<VoxelKey, std::uint32_t>> keyed(n);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    const Eigen::Vector3i c = cell_of(cloud.positions[i], voxel_size);
    if (!cell_index_in_range(c)) {
      throw Error("voxel grid", "point " + std::to_string(i),
                  "coordinates too large for a voxel size of " + std::to_string(voxel_size) + " m");
    }
    keyed[i] = {pack_key(c), static_cast<std::uint32_t>(i)};
  });
  tbb::parallel_sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> starts;
  for (std::size_t i = 0; i < n; ++i) {
    if (i == 0 || keyed[i].first != keyed[i - 1].first)
      starts.push_back(static_cast<std::uint32_t>(i));
  }
  const std::size_t cells = starts.size();
  starts.push_back(static_cast<std::uint32_t>(n));

  PointCloud out;
  copy_frame_description(cloud, out);
  out.positions.resize(cells);
  if (cloud.has_normals()) out.normals.resize(cells);
  if (cloud.has_colors()) out.colors.resize(cells);
  if (cloud.has_intensities()) out.intensities.resize(cells);
  tbb::parallel_for(std::size_t{0}, cells, [&](std::size_t c) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), nsum = Eigen::Vector3d::Zero(),
                    csum = Eigen::Vector3d::Zero();
    double isum = 0.0;
    for (std::uint32_t k = starts[c]; k < starts[c + 1]; ++k) {
      const std::uint32_t i = keyed[k].second;
      sum += cloud.positions[i].cast<double>();
      if (cloud.has_normals()) nsum += cloud.normals[i].cast<double>();
      if (cloud.has_colors())
        csum += Eigen::Vector3d(cloud.colors[i].r, cloud.colors[i].g, cloud.colors[i].b);
      if (cloud.has_intensities()) isum += cloud.intensities[i];
    }
    const double count = starts[c + 1] - starts[c];
    out.positions[c] = (sum / count).cast<float>();
    if (cloud.has_normals()) out.normals[c] = nsum.normalized().cast<float>();
    if (cloud.has_colors()) {
      const Eigen::Vector3d m = csum / count;
      out.colors[c] = Rgb8{static_cast<std::uint8_t>(std::lround(m.x())),
                           static_cast<std::uint8_t>(std::lround(m.y())),
                           static_cast<std::uint8_t>(std::lround(m.z()))};
    }
    if (cloud.has_intensities()) out.intensities[c] = static_cast<float>(isum / count);
  });
  return out;
}

std::vector<std::uint32_t> statistical_inlier_indices(const PointCloud& cloud, int k,
                                                      float stddev_mul) {
  const std::size_t n = cloud.size();
  if (n == 0 || k <= 0) return parallel_select_indices(n, [](std::size_t) { return true; });
  const KdTreeIndex index(cloud.positions);
  const std::size_t kq = static_cast<std::size_t>(k) + 1;  // the point itself comes first
  std::vector<float> mean_distance(n);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<std::uint32_t> idx(kq);
        std::vector<float> d2(kq);
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const std::size_t found = index.knn(cloud.positions[i], kq, idx.data(), d2.data());
          double s = 0.0;
          for (std::size_t j = 1; j < found; ++j) s += std::sqrt(d2[j]);
          mean_distance[i] =
              found > 1 ? static_cast<float>(s / static_cast<double>(found - 1)) : 0.0f;
        }
      });
  // Serial sums: deterministic regardless of thread count.
  double sum = 0.0, sum2 = 0.0;
  for (float d : mean_distance) {
    sum += d;
    sum2 += static_cast<double>(d) * d;
  }
  const double mean = sum / static_cast<double>(n);
  const double stddev = std::sqrt(std::max(0.0, sum2 / static_cast<double>(n) - mean * mean));
  const double threshold = mean + stddev_mul * stddev;
  return parallel_select_indices(n, [&](std::size_t i) { return mean_distance[i] <= threshold; });
}

PointCloud filter_cloud(const PointCloud& cloud, const FilterConfig& config, FilterCounts* counts) {
  FilterCounts c;
  c.input = cloud.size();
  PointCloud out = select_points(cloud, finite_point_indices(cloud));
  c.non_finite = c.input - out.size();
  std::size_t before = out.size();
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const bool crop =
      (config.crop_min.array() > -kInf).any() || (config.crop_max.array() < kInf).any();
  if (crop || config.min_range > 0.0f || config.max_range > 0.0f) {
    out = select_points(out, crop_indices(out, config));
  }
  c.cropped = before - out.size();
  before = out.size();
  if (config.voxel_size > 0.0f) out = voxel_grid_downsample(out, config.voxel_size);
  c.merged = before - out.size();
  before = out.size();
  if (config.outlier_k > 0) {
    out = select_points(out,
                        statistical_inlier_indices(out, config.outlier_k, config.outlier_stddev));
  }
  c.outliers = before - out.size();
  c.output = out.size();
  if (counts != nullptr) *counts = c;
  return out;
}

}  // namespace meshflow
