#include "graph/tile_levels.h"

#include <cmath>
#include <string>

#include "nodes/compress/compressed_mesh.h"
#include "nodes/compress/progressive_mesh.h"

namespace meshflow {

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
  const std::vector<unsigned char> bytes = compress::compress_progressive(tile, coding);
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
    levels.push_back(std::move(mesh));
  }
  return levels;
}

chunk::CoarserLevels progressive_levels(const TileLevelConfig& config) {
  return [config](const TriangleMesh& tile) { return progressive_tile_levels(tile, config); };
}

}  // namespace meshflow
