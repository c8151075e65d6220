#include "nodes/search/mesh_distance_index.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "nodes/search/closest_point.h"
#include "runtime/error.h"

namespace meshflow {

MeshDistanceIndex::MeshDistanceIndex(const TriangleMesh& mesh) : mesh_(mesh) {
  if (mesh.triangles.empty()) return;
  Eigen::Vector3f box_lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector3f box_hi = -box_lo;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Eigen::Vector3f& v = mesh.vertices[i];
    if (!v.allFinite()) throw Error("mesh", "vertex " + std::to_string(i), "is not finite");
    box_lo = box_lo.cwiseMin(v);
    box_hi = box_hi.cwiseMax(v);
  }
  double extent = 0.0;
  for (const Triangle& t : mesh.triangles) {
    const Eigen::Vector3f a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
    extent += (a.cwiseMax(b).cwiseMax(c) - a.cwiseMin(b).cwiseMin(c)).maxCoeff();
  }
  const float diagonal = (box_hi - box_lo).norm();
  cell_ = std::max({2.0f * static_cast<float>(extent / static_cast<double>(mesh.triangles.size())),
                    diagonal / 1000.0f, 1e-6f});
  std::vector<std::pair<VoxelKey, std::uint32_t>> pairs;
  for (std::uint32_t i = 0; i < mesh.triangles.size(); ++i) {
    const Triangle& t = mesh.triangles[i];
    const Eigen::Vector3f a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
    const Eigen::Vector3i clo = cell_of(a.cwiseMin(b).cwiseMin(c), cell_);
    const Eigen::Vector3i chi = cell_of(a.cwiseMax(b).cwiseMax(c), cell_);
    for (int z = clo.z(); z <= chi.z(); ++z)
      for (int y = clo.y(); y <= chi.y(); ++y)
        for (int x = clo.x(); x <= chi.x(); ++x) pairs.emplace_back(pack_key({x, y, z}), i);
  }
  lo_ = cell_of(box_lo, cell_);
  hi_ = cell_of(box_hi, cell_);
  std::sort(pairs.begin(), pairs.end());
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (i == 0 || pairs[i].first != pairs[i - 1].first) {
      keys_.push_back(pairs[i].first);
      offsets_.push_back(static_cast<std::uint32_t>(i));
    }
    triangles_.push_back(pairs[i].second);
  }
  offsets_.push_back(static_cast<std::uint32_t>(pairs.size()));
}

MeshDistanceIndex::Hit MeshDistanceIndex::closest(const Eigen::Vector3f& p, float enough) const {
  Hit best;
  best.distance = std::numeric_limits<float>::infinity();
  if (keys_.empty()) return best;
  float best_sq = std::numeric_limits<float>::infinity();
  const float enough_sq = enough > 0.0f ? enough * enough : -1.0f;  // -1: exact
  const Eigen::Vector3i c = cell_of(p, cell_);
  auto visit = [&](int x, int y, int z) {
    if (best_sq <= enough_sq) return;  // close enough already
    const Eigen::Vector3i cell(x, y, z);
    if ((cell.array() < lo_.array()).any() || (cell.array() > hi_.array()).any()) return;
    const VoxelKey key = pack_key(cell);
    const auto it = std::lower_bound(keys_.begin(), keys_.end(), key);
    if (it == keys_.end() || *it != key) return;
    const auto k = static_cast<std::size_t>(it - keys_.begin());
    for (std::uint32_t j = offsets_[k]; j < offsets_[k + 1]; ++j) {
      const Triangle& t = mesh_.triangles[triangles_[j]];
      const Eigen::Vector3f q = closest_point_on_triangle(
          p, mesh_.vertices[t[0]], mesh_.vertices[t[1]], mesh_.vertices[t[2]]);
      const float d2 = (q - p).squaredNorm();
      if (d2 < best_sq || (d2 == best_sq && triangles_[j] < best.triangle)) {
        best_sq = d2;
        best.triangle = triangles_[j];
        best.point = q;
      }
    }
  };
  // Rings of Chebyshev radius r around p's cell, clipped to the grid's bounds and starting at
  // the first ring that reaches them; every cell outside ring r is at least r cells away, so
  // the search stops once the best distance is within that.
  const Eigen::Vector3i gap = (lo_ - c).cwiseMax(c - hi_).cwiseMax(0);
  const int max_r = std::max((c - lo_).cwiseAbs().maxCoeff(), (hi_ - c).cwiseAbs().maxCoeff());
  for (int r = gap.maxCoeff(); r <= max_r; ++r) {
    const int z0 = std::max(c.z() - r, lo_.z()), z1 = std::min(c.z() + r, hi_.z());
    const int y0 = std::max(c.y() - r, lo_.y()), y1 = std::min(c.y() + r, hi_.y());
    const int x0 = std::max(c.x() - r, lo_.x()), x1 = std::min(c.x() + r, hi_.x());
    for (int z = z0; z <= z1; ++z)
      for (int y = y0; y <= y1; ++y) {
        if (std::abs(z - c.z()) == r || std::abs(y - c.y()) == r) {
          for (int x = x0; x <= x1; ++x) visit(x, y, z);
        } else {
          visit(c.x() - r, y, z);
          if (r > 0) visit(c.x() + r, y, z);
        }
      }
    const float reach = static_cast<float>(r) * cell_;
    if (best_sq <= reach * reach || best_sq <= enough_sq) break;
  }
  best.distance = std::sqrt(best_sq);
  return best;
}

}  // namespace meshflow
