#include "nodes/chunk/mesh_stitch.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "runtime/voxel_key.h"

namespace meshflow::chunk {

std::uint64_t lattice_edge_key(const Eigen::Vector3f& p, float voxel_size) {
  constexpr std::uint64_t kNone = std::numeric_limits<std::uint64_t>::max();
  const Eigen::Vector3d g = p.cast<double>() / static_cast<double>(voxel_size);
  int edge_axis = -1;
  Eigen::Vector3i lower;
  for (int a = 0; a < 3; ++a) {
    const double nearest = std::round(g[a]);
    const double off = std::abs(g[a] - nearest);
    if (!(std::abs(nearest) < kMaxCellIndex)) return kNone;
    if (off < 1e-4) {
      lower[a] = static_cast<int>(nearest);
    } else if (off > 5e-4 && edge_axis < 0) {
      edge_axis = a;
      lower[a] = static_cast<int>(std::floor(g[a]));
    } else {
      return kNone;
    }
  }
  if (edge_axis < 0) return kNone;
  return pack_key(lower) * 3 + static_cast<std::uint64_t>(edge_axis);
}

void MeshStitcher::add(const TriangleMesh& mesh, const std::vector<std::uint8_t>& vertex_flags) {
  const auto base = static_cast<std::uint32_t>(joined_.vertices.size());
  normals_ = normals_ && mesh.normals.size() == mesh.vertices.size();
  colors_ = colors_ && mesh.colors.size() == mesh.vertices.size();
  joined_.vertices.insert(joined_.vertices.end(), mesh.vertices.begin(), mesh.vertices.end());
  if (normals_)
    joined_.normals.insert(joined_.normals.end(), mesh.normals.begin(), mesh.normals.end());
  if (colors_) joined_.colors.insert(joined_.colors.end(), mesh.colors.begin(), mesh.colors.end());
  flags_given_ = flags_given_ && vertex_flags.size() == mesh.vertices.size();
  if (flags_given_) flags_.insert(flags_.end(), vertex_flags.begin(), vertex_flags.end());
  for (const Eigen::Vector3f& v : mesh.vertices) keys_.push_back(lattice_edge_key(v, voxel_size_));
  for (const Triangle& t : mesh.triangles)
    joined_.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

TriangleMesh MeshStitcher::stitch(std::size_t* merged, std::vector<std::uint8_t>* vertex_flags) {
  const std::size_t n = joined_.vertices.size();
  // Order the vertices by (key, index): the first copy of each key is the representative.
  std::vector<std::uint32_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = static_cast<std::uint32_t>(i);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return keys_[a] != keys_[b] ? keys_[a] < keys_[b] : a < b;
  });
  constexpr std::uint64_t kNone = std::numeric_limits<std::uint64_t>::max();
  std::vector<std::uint32_t> representative(n);
  std::size_t welded = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t v = order[i];
    const bool same = i > 0 && keys_[v] != kNone && keys_[order[i - 1]] == keys_[v];
    representative[v] = same ? representative[order[i - 1]] : v;
    welded += same ? 1 : 0;
  }
  if (merged) *merged = welded;
  // Keep representatives that a triangle uses, in their original order.
  std::vector<std::uint32_t> new_index(n, std::numeric_limits<std::uint32_t>::max());
  for (Triangle& t : joined_.triangles)
    for (std::uint32_t& v : t) {
      v = representative[v];
      new_index[v] = 0;
    }
  TriangleMesh out;
  std::vector<std::uint8_t> flags;
  const bool with_flags = flags_given_ && flags_.size() == n;
  std::uint32_t next = 0;
  for (std::size_t v = 0; v < n; ++v) {
    if (new_index[v] != 0) continue;
    new_index[v] = next++;
    out.vertices.push_back(joined_.vertices[v]);
    if (normals_ && !joined_.normals.empty()) out.normals.push_back(joined_.normals[v]);
    if (colors_ && !joined_.colors.empty()) out.colors.push_back(joined_.colors[v]);
    if (with_flags) flags.push_back(flags_[v]);
  }
  if (vertex_flags) *vertex_flags = std::move(flags);
  out.triangles.reserve(joined_.triangles.size());
  for (const Triangle& t : joined_.triangles)
    out.triangles.push_back({new_index[t[0]], new_index[t[1]], new_index[t[2]]});
  joined_ = TriangleMesh{};
  keys_.clear();
  flags_.clear();
  return out;
}

}  // namespace meshflow::chunk
