#include "nodes/chunk/mesh_stitch.h"

#include <tbb/parallel_for.h>

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

unsigned seam_plane_axes(std::uint64_t key, int chunk_cells) {
  if (key == std::numeric_limits<std::uint64_t>::max()) return 0;
  const auto axis = static_cast<int>(key % 3);
  const Eigen::Vector3i lower = unpack_key(key / 3);
  unsigned axes = 0;
  for (int a = 0; a < 3; ++a)
    if (a != axis && lower[a] % chunk_cells == 0) axes |= 1u << a;
  return axes;
}

bool on_chunk_seam(std::uint64_t key, int chunk_cells) {
  return chunk_cells > 0 && seam_plane_axes(key, chunk_cells) != 0;
}

std::vector<std::uint8_t> seam_vertices(const std::vector<Eigen::Vector3f>& vertices,
                                        float voxel_size, int chunk_cells,
                                        const std::vector<std::uint8_t>& apart) {
  std::vector<std::uint8_t> seam(vertices.size(), 0);
  const bool with_apart = apart.size() == vertices.size();
  tbb::parallel_for(std::size_t{0}, vertices.size(), [&](std::size_t v) {
    if (with_apart && apart[v] != 0) return;
    seam[v] = on_chunk_seam(lattice_edge_key(vertices[v], voxel_size), chunk_cells) ? 1 : 0;
  });
  return seam;
}

void MeshStitcher::add(TriangleMesh mesh, std::vector<std::uint8_t> vertex_flags) {
  seams_.push_back(summarize_seams(mesh, vertex_flags, voxel_size_, chunk_cells_, apart_flags_));
  meshes_.push_back(std::move(mesh));
  flags_.push_back(std::move(vertex_flags));
}

TriangleMesh MeshStitcher::stitch(std::size_t* merged, std::vector<std::uint8_t>* vertex_flags,
                                  std::size_t* turned) {
  std::vector<const ChunkSeams*> chunks;
  for (const ChunkSeams& s : seams_) chunks.push_back(&s);
  const WeldPlan plan = plan_weld(chunks);
  if (merged) *merged = plan.merged;
  if (turned) *turned = plan.turned;
  // Chunk by chunk into the reserved output, each chunk freed once welded: the mesh is held
  // about once.
  TriangleMesh joined;
  joined.vertices.reserve(plan.vertices);
  if (plan.normals) joined.normals.reserve(plan.vertices);
  if (plan.colors) joined.colors.reserve(plan.vertices);
  joined.triangles.reserve(plan.triangles);
  std::vector<std::uint8_t> kept_flags, part_flags;
  for (std::size_t c = 0; c < meshes_.size(); ++c) {
    append_welded(joined, weld_chunk(meshes_[c], flags_[c], seams_[c], plan, c, &part_flags));
    if (plan.flags) kept_flags.insert(kept_flags.end(), part_flags.begin(), part_flags.end());
    meshes_[c] = TriangleMesh{};
    flags_[c] = {};
    seams_[c] = ChunkSeams{};
  }
  meshes_ = {};
  flags_ = {};
  seams_ = {};
  if (vertex_flags) *vertex_flags = std::move(kept_flags);
  return joined;
}

}  // namespace meshflow::chunk
