#include "graph/chunk_output.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cstdint>
#include <cstring>

#include "graph/chunk_finish.h"
#include "nodes/chunk/mesh_stitch.h"
#include "nodes/chunk/mesh_tiles.h"
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

void SeamNeighbourhood::append(const SeamNeighbourhood& later) {
  const auto join = [](auto& to, const auto& from) {
    to.insert(to.end(), from.begin(), from.end());
  };
  any_feature = any_feature || later.any_feature;
  join(vertex_index, later.vertex_index);
  join(positions, later.positions);
  join(normals, later.normals);
  join(features, later.features);
  join(seam, later.seam);
  join(near, later.near);
  join(triangle_index, later.triangle_index);
  join(triangles, later.triangles);
}

void add_seam_neighbourhood(const TriangleMesh& part, const std::vector<std::uint8_t>& flags,
                            std::uint64_t first_vertex, std::uint64_t first_triangle,
                            float voxel_size, int chunk_cells, std::uint8_t feature_bit,
                            bool normals, SeamNeighbourhood& into) {
  const std::size_t n = part.vertices.size();
  if (flags.size() != n) return;  // finish_seams() needs every vertex's flags
  // finish_seams()'s selection, made per part: a triangle's vertices are the part's own or
  // seam vertices kept by an earlier part (the weld keeps a seam vertex's first copy), and a
  // vertex that is not a seam vertex is used by its own part's triangles only.
  const std::uint64_t first = first_vertex;
  std::vector<std::uint8_t> features(n);
  for (std::size_t v = 0; v < n; ++v) features[v] = (flags[v] & feature_bit) ? 1 : 0;
  into.any_feature =
      into.any_feature || std::find(features.begin(), features.end(), 1) != features.end();
  const std::vector<std::uint8_t> seam =
      seam_vertices(part.vertices, voxel_size, chunk_cells, features);
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
    into.triangle_index.push_back(first_triangle + i);
    into.triangles.push_back(t);
    for (const std::uint32_t v : t)
      if (own(v)) keep[v - first] = 1;
  }
  for (std::size_t v = 0; v < n; ++v) {
    if (!keep[v]) continue;
    into.vertex_index.push_back(first + v);
    into.positions.push_back(part.vertices[v]);
    if (normals) into.normals.push_back(part.normals[v]);
    into.features.push_back(features[v]);
    into.seam.push_back(seam[v]);
    into.near.push_back(near[v]);
  }
}

std::size_t finish_seam_rows(SeamNeighbourhood& neighbourhood, io::PlyMeshFile& file,
                             std::size_t* rewritten) {
  SeamNeighbourhood& nb = neighbourhood;
  std::size_t flips = 0, rows = 0;
  if (nb.any_feature && !nb.triangles.empty()) {
    const bool normals = !nb.normals.empty();
    // The neighbourhood as compact_vertices() numbers it: vertices in output order.
    TriangleMesh around;
    around.vertices = std::move(nb.positions);
    if (normals) around.normals = nb.normals;
    const auto local = [&](std::uint32_t v) {
      const auto it = std::lower_bound(nb.vertex_index.begin(), nb.vertex_index.end(), v);
      if (it == nb.vertex_index.end() || *it != v)
        throw Error("chunked output", "seams", "a seam triangle's vertex was not kept");
      return static_cast<std::uint32_t>(it - nb.vertex_index.begin());
    };
    around.triangles.reserve(nb.triangles.size());
    for (const Triangle& t : nb.triangles)
      around.triangles.push_back(Triangle{local(t[0]), local(t[1]), local(t[2])});
    flips = finish_seam_neighbourhood(around, nb.features, nb.seam);
    for (std::size_t i = 0; i < nb.triangles.size(); ++i) {
      const Triangle& t = around.triangles[i];
      const Triangle global{static_cast<std::uint32_t>(nb.vertex_index[t[0]]),
                            static_cast<std::uint32_t>(nb.vertex_index[t[1]]),
                            static_cast<std::uint32_t>(nb.vertex_index[t[2]])};
      if (global == nb.triangles[i]) continue;
      file.write_triangle(nb.triangle_index[i], global);
      ++rows;
    }
    if (normals)
      for (std::size_t v = 0; v < nb.vertex_index.size(); ++v) {
        if (!nb.near[v] || same_bits(around.normals[v], nb.normals[v])) continue;
        file.write_normal(nb.vertex_index[v], around.normals[v]);
        ++rows;
      }
  }
  if (rewritten) *rewritten = rows;
  return flips;
}

io::PlyMeshLayout streamed_layout(const WeldPlan& plan, const Eigen::Vector3d& origin) {
  io::PlyMeshLayout layout;
  layout.world = !origin.isZero();
  layout.normals = plan.normals && plan.vertices > 0;
  layout.colors = plan.colors && plan.vertices > 0;
  return layout;
}

StreamedChunkOutput::StreamedChunkOutput(const std::string& path, const WeldPlan& plan,
                                         const Eigen::Vector3d& origin, float voxel_size,
                                         int chunk_cells, std::uint8_t feature_bit)
    : file_(path, streamed_layout(plan, origin), plan.vertices, plan.triangles, origin),
      origin_(origin),
      normals_(streamed_layout(plan, origin).normals),
      flags_(plan.flags),
      voxel_size_(voxel_size),
      chunk_cells_(chunk_cells),
      feature_bit_(feature_bit) {}

void StreamedChunkOutput::add(const TriangleMesh& part, const std::vector<std::uint8_t>& flags,
                              const Eigen::Vector3i& chunk) {
  parts_.push_back(PartRows{chunk, triangles_, part.triangles.size()});
  file_.write_vertices(vertices_, part);
  file_.write_triangles(triangles_, part.triangles);
  if (flags_)
    add_seam_neighbourhood(part, flags, vertices_, triangles_, voxel_size_, chunk_cells_,
                           feature_bit_, normals_, near_);
  vertices_ += part.vertices.size();
  triangles_ += part.triangles.size();
}

std::size_t StreamedChunkOutput::finish_seams() {
  return finish_seam_rows(near_, file_, &rewritten_);
}

std::size_t StreamedChunkOutput::write_tiles(const std::string& dir, const CoarserLevels& levels,
                                             std::size_t in_flight) {
  create_tile_directory(dir);
  const std::vector<TileRecord> records = write_tiles_in_flight(
      dir, parts_.size(),
      [&](std::size_t i) {
        const PartRows& p = parts_[i];
        return read_tile(file_, p.chunk, p.first_triangle, p.triangles);
      },
      origin_, levels, in_flight);
  write_tile_index(dir, ChunkGrid{voxel_size_, chunk_cells_, 0}, origin_, records);
  return records.size();
}

}  // namespace meshflow::chunk
