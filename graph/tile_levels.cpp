#include "graph/tile_levels.h"

#include <cmath>
#include <string>

#include "nodes/compress/compressed_mesh.h"
#include "nodes/compress/progressive_mesh.h"

namespace meshflow {
namespace {

// Gives a level's locked vertices the tile's own position, normal and colour (the coder's are
// quantised): level vertex k is tile vertex `order[k]` (a level's vertices are a prefix of the
// decoded order).
void restore_locked(TriangleMesh& level, const TriangleMesh& tile,
                    const std::vector<std::uint8_t>& locked,
                    const std::vector<std::uint32_t>& order) {
  for (std::size_t k = 0; k < level.vertices.size(); ++k) {
    const std::uint32_t v = order[k];
    if (!locked[v]) continue;
    level.vertices[k] = tile.vertices[v];
    if (!level.normals.empty() && !tile.normals.empty()) level.normals[k] = tile.normals[v];
    if (!level.colors.empty() && !tile.colors.empty()) level.colors[k] = tile.colors[v];
  }
}

}  // namespace

std::vector<std::uint8_t> border_vertex_flags(const TriangleMesh& mesh) {
  TriangleMesh proper;  // the triangles the coder decimates (a repeated corner: none)
  proper.vertices = mesh.vertices;
  for (const Triangle& t : mesh.triangles)
    if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) proper.triangles.push_back(t);
  std::vector<std::uint8_t> flags(mesh.vertices.size(), 0);
  for (const BorderEdge& e : border_edges(proper)) flags[e.a] = flags[e.b] = 1;
  return flags;
}

std::vector<TriangleMesh> progressive_tile_levels(const TriangleMesh& tile,
                                                  const TileLevelConfig& config) {
  std::vector<TriangleMesh> levels;
  const std::size_t triangles = tile.triangles.size();
  const auto target = [&](std::size_t k) {  // the tile's triangles / ratio^k
    return static_cast<std::size_t>(static_cast<double>(triangles) / std::pow(config.ratio, k));
  };
  if (config.levels == 0 || config.ratio <= 1.0 || target(1) < config.min_triangles) return levels;
  compress::CompressConfig coding;
  coding.base_ratio = static_cast<float>(1.0 / std::pow(config.ratio, config.levels));
  const std::vector<std::uint8_t> locked =
      config.lock_border ? border_vertex_flags(tile) : std::vector<std::uint8_t>();
  compress::CompressReport report;
  const std::vector<unsigned char> bytes =
      compress::compress_progressive(tile, locked, coding, &report);
  const std::string source = "a tile's progressive levels";
  for (std::size_t k = config.levels; k >= 1; --k) {
    compress::ProgressiveLevel level;
    if (k == config.levels)
      level.splits = 0;  // the base mesh
    else
      level.triangles = target(k);
    TriangleMesh mesh = compress::decompress_progressive_level(bytes, source, level);
    if (mesh.triangles.size() < config.min_triangles) continue;
    if (!levels.empty() && mesh.triangles.size() <= levels.back().triangles.size()) continue;
    if (mesh.triangles.size() >= triangles) break;
    if (!locked.empty()) restore_locked(mesh, tile, locked, report.vertex_order);
    levels.push_back(std::move(mesh));
  }
  return levels;
}

chunk::CoarserLevels progressive_levels(const TileLevelConfig& config) {
  return [config](const TriangleMesh& tile) { return progressive_tile_levels(tile, config); };
}

}  // namespace meshflow
