#include "graph/chunk_output.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cstdint>
#include <cstring>

#include "graph/chunk_finish.h"
#include "nodes/chunk/mesh_stitch.h"
#include "runtime/error.h"

namespace meshflow::chunk {
namespace {

// Whether a and b are the same floats bit for bit (a normal the file already holds: -0 and +0
// differ, as the written bytes would).
bool same_bits(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  std::array<std::uint32_t, 3> x{}, y{};
  std::memcpy(x.data(), a.data(), sizeof x);
  std::memcpy(y.data(), b.data(), sizeof y);
  return x == y;
}

}  // namespace

StreamedChunkOutput::StreamedChunkOutput(const std::string& path, std::uint64_t vertices,
                                         std::uint64_t triangles, const io::PlyMeshLayout& layout,
                                         bool flags, const Eigen::Vector3d& origin,
                                         float voxel_size, int chunk_cells,
                                         std::uint8_t feature_bit)
    : file_(path, layout, vertices, triangles, origin),
      normals_(layout.normals),
      flags_(flags),
      voxel_size_(voxel_size),
      chunk_cells_(chunk_cells),
      feature_bit_(feature_bit) {}

StreamedChunkOutput::StreamedChunkOutput(const std::string& path, const WeldPlan& plan,
                                         const Eigen::Vector3d& origin, float voxel_size,
                                         int chunk_cells, std::uint8_t feature_bit)
    : StreamedChunkOutput(
          path, plan.vertices, plan.triangles,
          [&] {
            io::PlyMeshLayout layout;
            layout.world = !origin.isZero();
            layout.normals = plan.normals && plan.vertices > 0;
            layout.colors = plan.colors && plan.vertices > 0;
            return layout;
          }(),
          plan.flags, origin, voxel_size, chunk_cells, feature_bit) {}

void StreamedChunkOutput::add(const TriangleMesh& part, const std::vector<std::uint8_t>& flags) {
  const std::uint64_t first = vertices_, first_triangle = triangles_;
  file_.write_vertices(first, part);
  file_.write_triangles(first_triangle, part.triangles);
  vertices_ += part.vertices.size();
  triangles_ += part.triangles.size();
  const std::size_t n = part.vertices.size();
  if (!flags_ || flags.size() != n) return;  // finish_seams() needs every vertex's flags
  // finish_seams()'s selection, made per part: a triangle's vertices are the part's own or
  // seam vertices kept by an earlier part (the weld keeps a seam vertex's first copy), and a
  // vertex that is not a seam vertex is used by its own part's triangles only.
  std::vector<std::uint8_t> features(n);
  for (std::size_t v = 0; v < n; ++v) features[v] = (flags[v] & feature_bit_) ? 1 : 0;
  any_feature_ = any_feature_ || std::find(features.begin(), features.end(), 1) != features.end();
  const std::vector<std::uint8_t> seam =
      seam_vertices(part.vertices, voxel_size_, chunk_cells_, features);
  const auto own = [&](std::uint32_t v) { return v >= first; };
  const auto at_seam = [&](std::uint32_t v) { return !own(v) || seam[v - first] != 0; };
  // Near a seam: a seam vertex (every kept one is used by some triangle, which touches the
  // seam) and every vertex of a triangle touching one.
  std::vector<std::uint8_t> near(seam);
  for (const Triangle& t : part.triangles)
    if (at_seam(t[0]) || at_seam(t[1]) || at_seam(t[2]))
      for (const std::uint32_t v : t)
        if (own(v)) near[v - first] = 1;
  const auto is_near = [&](std::uint32_t v) { return !own(v) || near[v - first] != 0; };
  std::vector<std::uint8_t> keep(near);
  for (std::size_t i = 0; i < part.triangles.size(); ++i) {
    const Triangle& t = part.triangles[i];
    if (!is_near(t[0]) && !is_near(t[1]) && !is_near(t[2])) continue;
    triangle_index_.push_back(first_triangle + i);
    triangles_near_.push_back(t);
    for (const std::uint32_t v : t)
      if (own(v)) keep[v - first] = 1;
  }
  for (std::size_t v = 0; v < n; ++v) {
    if (!keep[v]) continue;
    vertex_index_.push_back(first + v);
    positions_.push_back(part.vertices[v]);
    if (normals_) vertex_normals_.push_back(part.normals[v]);
    features_.push_back(features[v]);
    seam_.push_back(seam[v]);
    near_.push_back(near[v]);
  }
}

std::size_t StreamedChunkOutput::finish() {
  std::size_t flips = 0;
  if (flags_ && any_feature_ && !triangles_near_.empty()) {
    // The neighbourhood as compact_vertices() numbers it: vertices in output order.
    TriangleMesh around;
    around.vertices = std::move(positions_);
    if (normals_) around.normals = vertex_normals_;
    const auto local = [&](std::uint32_t v) {
      const auto it = std::lower_bound(vertex_index_.begin(), vertex_index_.end(), v);
      if (it == vertex_index_.end() || *it != v)
        throw Error("chunked output", "seams", "a seam triangle's vertex was not kept");
      return static_cast<std::uint32_t>(it - vertex_index_.begin());
    };
    around.triangles.reserve(triangles_near_.size());
    for (const Triangle& t : triangles_near_)
      around.triangles.push_back(Triangle{local(t[0]), local(t[1]), local(t[2])});
    flips = finish_seam_neighbourhood(around, features_, seam_);
    for (std::size_t i = 0; i < triangles_near_.size(); ++i) {
      const Triangle& t = around.triangles[i];
      const Triangle global{static_cast<std::uint32_t>(vertex_index_[t[0]]),
                            static_cast<std::uint32_t>(vertex_index_[t[1]]),
                            static_cast<std::uint32_t>(vertex_index_[t[2]])};
      if (global == triangles_near_[i]) continue;
      file_.write_triangle(triangle_index_[i], global);
      ++rewritten_;
    }
    if (normals_)
      for (std::size_t v = 0; v < vertex_index_.size(); ++v) {
        if (!near_[v] || same_bits(around.normals[v], vertex_normals_[v])) continue;
        file_.write_normal(vertex_index_[v], around.normals[v]);
        ++rewritten_;
      }
  }
  file_.commit();
  return flips;
}

}  // namespace meshflow::chunk
