#include "graph/chunk_finish.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "nodes/chunk/mesh_stitch.h"
#include "nodes/extract/feature_edge_flips.h"
#include "nodes/extract/rim_trim.h"
#include "runtime/parallel.h"

namespace meshflow::chunk {
namespace {

constexpr std::uint8_t kHeldBit = 1;     // a seam vertex
constexpr std::uint8_t kFeatureBit = 2;  // an extended marching cubes feature vertex

bool any_set(const std::vector<std::uint8_t>& bytes) {
  return std::any_of(bytes.begin(), bytes.end(), [](std::uint8_t b) { return b != 0; });
}

}  // namespace

TriangleMesh finish_chunk_mesh(const TriangleMesh& mesh, const std::vector<std::uint8_t>& beyond,
                               std::vector<std::uint8_t>& features, const ChunkFinishConfig& config,
                               ChunkFinishReport* report) {
  ChunkFinishReport r;
  const std::size_t n = mesh.vertices.size();
  const bool with_features = features.size() == n;
  TriangleMesh out = mesh;
  if (with_features && any_set(features)) {
    // Inside the chunk an edge between two fans has both its triangles here; a seam edge has
    // one, so it waits for finish_seams().
    r.flips = flip_edges_between_features(out, features);
    if (!out.normals.empty()) compute_vertex_normals(out);
  }
  const std::vector<std::uint8_t> none;
  std::vector<std::uint8_t> flags = seam_vertices(
      out.vertices, config.voxel_size, config.chunk_cells, with_features ? features : none);
  for (std::size_t v = 0; v < n; ++v)
    flags[v] =
        static_cast<std::uint8_t>(flags[v] | (with_features && features[v] ? kFeatureBit : 0));
  if (config.trim_rim && beyond.size() == n) {
    std::vector<std::uint8_t> peel(n);
    for (std::size_t v = 0; v < n; ++v) peel[v] = beyond[v] && !(flags[v] & kHeldBit) ? 1 : 0;
    std::vector<std::uint32_t> kept;
    out = trim_rim(out, peel, &r.rim_trimmed, &kept);
    std::vector<std::uint8_t> moved(kept.size());
    for (std::size_t v = 0; v < kept.size(); ++v) moved[v] = flags[kept[v]];
    flags = std::move(moved);
  }
  r.seam_vertices = static_cast<std::size_t>(
      std::count_if(flags.begin(), flags.end(), [](std::uint8_t f) { return f & kHeldBit; }));
  HeldVertices held{std::move(flags), kHeldBit, with_features ? kFeatureBit : std::uint8_t{0}};
  out = optimize_mesh(out, config.optimize, &r.optimize, held);
  if (with_features) {
    features.assign(held.flags.size(), 0);
    for (std::size_t v = 0; v < held.flags.size(); ++v)
      features[v] = (held.flags[v] & kFeatureBit) ? 1 : 0;
  }
  if (report != nullptr) *report = std::move(r);
  return out;
}

std::size_t finish_seams(TriangleMesh& mesh, const std::vector<std::uint8_t>& features,
                         float voxel_size, int chunk_cells) {
  const std::size_t n = mesh.vertices.size();
  if (features.size() != n || !any_set(features)) return 0;
  const std::vector<std::uint8_t> seam =
      seam_vertices(mesh.vertices, voxel_size, chunk_cells, features);
  // The seam vertices and their neighbours: their fans are whole in the sub-mesh below, so
  // the flips' valences and the normals are those of the whole mesh.
  const std::vector<std::uint32_t> at_seam =
      parallel_select_indices(mesh.triangles.size(), [&](std::size_t t) {
        const Triangle& tri = mesh.triangles[t];
        return seam[tri[0]] || seam[tri[1]] || seam[tri[2]];
      });
  std::vector<std::uint8_t> near(n, 0);
  for (const std::uint32_t t : at_seam)
    for (const std::uint32_t v : mesh.triangles[t]) near[v] = 1;
  const std::vector<std::uint32_t> around =
      parallel_select_indices(mesh.triangles.size(), [&](std::size_t t) {
        const Triangle& tri = mesh.triangles[t];
        return near[tri[0]] || near[tri[1]] || near[tri[2]];
      });
  std::vector<Triangle> triangles(around.size());
  for (std::size_t i = 0; i < around.size(); ++i) triangles[i] = mesh.triangles[around[i]];
  std::vector<std::uint32_t> original;
  TriangleMesh sub = compact_vertices(mesh, triangles, &original);
  std::vector<std::uint8_t> sub_features(original.size()), sub_seam(original.size());
  for (std::size_t v = 0; v < original.size(); ++v) {
    sub_features[v] = features[original[v]];
    sub_seam[v] = seam[original[v]];
  }
  const std::size_t flips = finish_seam_neighbourhood(sub, sub_features, sub_seam);
  for (std::size_t i = 0; i < around.size(); ++i)
    for (int k = 0; k < 3; ++k) mesh.triangles[around[i]][k] = original[sub.triangles[i][k]];
  if (!mesh.normals.empty() && mesh.normals.size() == n) {
    for (std::size_t v = 0; v < original.size(); ++v)
      if (near[original[v]]) mesh.normals[original[v]] = sub.normals[v];
  }
  return flips;
}

std::size_t finish_seam_neighbourhood(TriangleMesh& around,
                                      const std::vector<std::uint8_t>& features,
                                      const std::vector<std::uint8_t>& seam) {
  const std::size_t flips = flip_edges_between_features(around, features, &seam);
  if (!around.normals.empty()) compute_vertex_normals(around);
  return flips;
}

}  // namespace meshflow::chunk
