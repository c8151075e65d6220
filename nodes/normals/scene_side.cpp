#include "nodes/normals/scene_side.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace meshflow {
namespace {

// One column of looks_like_height_field()'s grid.
struct HeightColumn {
  float low = std::numeric_limits<float>::infinity();
  float high = -std::numeric_limits<float>::infinity();
  std::uint32_t points = 0;
};

}  // namespace

bool looks_like_camera_view(const PointCloud& cloud) {
  if (!cloud.origin.isZero() || cloud.empty()) return false;
  const Eigen::AlignedBox3f box = finite_bounds(cloud);
  if (box.isEmpty() || box.contains(Eigen::Vector3f::Zero())) return false;
  const float cos_max = std::cos(75.0f * 3.14159265f / 180.0f);
  constexpr float kMaxRange = 25.0f;  // metres
  const std::size_t n = cloud.size();
  struct Counts {
    std::size_t finite = 0, in_view = 0;
    Eigen::Vector3d directions = Eigen::Vector3d::Zero();  // sum of unit directions
  };
  const Counts counts = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, 16384), Counts{},
      [&](const tbb::blocked_range<std::size_t>& r, Counts c) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const Eigen::Vector3f& p = cloud.positions[i];
          if (!p.allFinite()) continue;
          ++c.finite;
          const float length = p.norm();
          if (p.z() > 0.0f && p.z() >= cos_max * length && length <= kMaxRange) ++c.in_view;
          if (length > 0.0f) c.directions += (p / length).cast<double>();
        }
        return c;
      },
      [](Counts a, const Counts& b) {
        a.finite += b.finite;
        a.in_view += b.in_view;
        a.directions += b.directions;
        return a;
      });
  // The image is around the optical axis: the points' mean direction within 40 degrees of +z.
  const double mean_length = counts.directions.norm();
  return counts.finite > 0 && counts.in_view >= 0.99 * static_cast<double>(counts.finite) &&
         mean_length > 0.0 &&
         counts.directions.z() >= std::cos(40.0 * 3.14159265 / 180.0) * mean_length;
}

bool looks_like_height_field(const PointCloud& cloud) {
  const std::size_t finite = count_finite_points(cloud);
  if (finite < 64) return false;
  const Eigen::AlignedBox3f box = finite_bounds(cloud);
  const double width_x = static_cast<double>(box.sizes().x());
  const double width_y = static_cast<double>(box.sizes().y());
  if (!(width_x > 0.0) || !(width_y > 0.0)) return false;  // a vertical sheet or a line
  // Columns of about 16 points each for one layer over the bounds (fewer for thin strips).
  const double column = std::sqrt(16.0 * width_x * width_y / static_cast<double>(finite));
  const auto cells = [&](double width) {
    return static_cast<std::size_t>(std::clamp(std::ceil(width / column), 1.0, 65536.0));
  };
  const std::size_t columns_x = cells(width_x), columns_y = cells(width_y);
  const auto column_of = [&](const Eigen::Vector3f& p) {
    const auto at = [&](float v, float low, std::size_t count) {
      const double c = std::floor(static_cast<double>(v - low) / column);
      return static_cast<std::size_t>(std::clamp(c, 0.0, static_cast<double>(count - 1)));
    };
    return at(p.y(), box.min().y(), columns_y) * columns_x + at(p.x(), box.min().x(), columns_x);
  };

  // Per-thread grids, merged: min, max and counts do not depend on the order.
  const std::size_t total = columns_x * columns_y;
  tbb::enumerable_thread_specific<std::vector<HeightColumn>> partial(
      [&] { return std::vector<HeightColumn>(total); });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cloud.size(), 16384),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::vector<HeightColumn>& grid = partial.local();
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const Eigen::Vector3f& p = cloud.positions[i];
                        if (!p.allFinite()) continue;
                        HeightColumn& c = grid[column_of(p)];
                        c.low = std::min(c.low, p.z());
                        c.high = std::max(c.high, p.z());
                        ++c.points;
                      }
                    });
  std::vector<HeightColumn> grid(total);
  for (const std::vector<HeightColumn>& part : partial)
    for (std::size_t c = 0; c < total; ++c) {
      grid[c].low = std::min(grid[c].low, part[c].low);
      grid[c].high = std::max(grid[c].high, part[c].high);
      grid[c].points += part[c].points;
    }
  const double max_range = 3.0 * column;
  std::size_t in_thin_columns = 0;
  for (const HeightColumn& c : grid)
    if (c.points > 0 && static_cast<double>(c.high - c.low) <= max_range)
      in_thin_columns += c.points;
  return static_cast<double>(in_thin_columns) >= 0.8 * static_cast<double>(finite);
}

SceneKind classify_scene(const PointCloud& cloud, bool whole_scene) {
  if (cloud.z_up) return SceneKind::kMapFrame;
  if (!whole_scene) return SceneKind::kObject;
  if (looks_like_camera_view(cloud)) return SceneKind::kCameraView;
  if (looks_like_height_field(cloud)) return SceneKind::kHeightField;
  return SceneKind::kObject;
}

ComponentSide side_of_scene(SceneKind kind) {
  switch (kind) {
    case SceneKind::kMapFrame:
      return ComponentSide::kAlongAxis;
    case SceneKind::kHeightField:
      return ComponentSide::kAxisOrOutward;
    case SceneKind::kCameraView:
      return ComponentSide::kViewOrOutward;
    case SceneKind::kObject:
      break;
  }
  return ComponentSide::kOutward;
}

ComponentSide scene_side(const PointCloud& cloud, bool whole_scene) {
  return side_of_scene(classify_scene(cloud, whole_scene));
}

const char* scene_kind_name(SceneKind kind) {
  switch (kind) {
    case SceneKind::kMapFrame:
      return "map-frame";
    case SceneKind::kCameraView:
      return "camera-view";
    case SceneKind::kHeightField:
      return "height-field";
    case SceneKind::kObject:
      break;
  }
  return "object";
}

}  // namespace meshflow
