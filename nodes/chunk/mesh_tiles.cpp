#include "nodes/chunk/mesh_tiles.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <system_error>

#include "nodes/io/atomic_file.h"
#include "nodes/io/glb_writer.h"
#include "runtime/error.h"
#include "runtime/voxel_key.h"

namespace meshflow::chunk {
namespace {

// "[x, y, z]" with enough digits to read the float or double back exactly.
template <typename V>
std::string tiles_json_triple(const V& v) {
  char text[96];
  std::snprintf(text, sizeof text, "[%.17g, %.17g, %.17g]", static_cast<double>(v[0]),
                static_cast<double>(v[1]), static_cast<double>(v[2]));
  return text;
}

// A number with enough digits to read the float back exactly.
std::string tiles_json_number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

}  // namespace

std::vector<MeshTile> split_into_tiles(const TriangleMesh& mesh, const ChunkGrid& grid) {
  // Chunk of each triangle, then the tiles in Morton order of their chunk.
  std::map<std::uint64_t, std::vector<std::size_t>> by_chunk;
  std::map<std::uint64_t, Eigen::Vector3i> chunk_of_code;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    const Eigen::Vector3f centroid =
        (mesh.vertices[tri[0]] + mesh.vertices[tri[1]] + mesh.vertices[tri[2]]) / 3.0f;
    const Eigen::Vector3i chunk = grid.chunk_of_cell(cell_of(centroid, grid.voxel_size));
    const std::uint64_t code = morton_code(chunk);
    by_chunk[code].push_back(t);
    chunk_of_code.emplace(code, chunk);
  }
  std::vector<MeshTile> tiles;
  tiles.reserve(by_chunk.size());
  const bool normals = mesh.normals.size() == mesh.vertices.size();
  const bool colors = mesh.colors.size() == mesh.vertices.size();
  std::vector<std::uint32_t> renumbered(mesh.vertices.size(), UINT32_MAX);
  for (const auto& [code, triangles] : by_chunk) {
    MeshTile tile;
    tile.chunk = chunk_of_code.at(code);
    TriangleMesh& out = tile.mesh;
    std::vector<std::uint32_t> used;
    for (std::size_t t : triangles) {
      Triangle copy = mesh.triangles[t];
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = copy[k];
        if (renumbered[v] == UINT32_MAX) {
          renumbered[v] = static_cast<std::uint32_t>(out.vertices.size());
          used.push_back(v);
          out.vertices.push_back(mesh.vertices[v]);
          if (normals) out.normals.push_back(mesh.normals[v]);
          if (colors) out.colors.push_back(mesh.colors[v]);
        }
        copy[k] = renumbered[v];
      }
      out.triangles.push_back(copy);
    }
    for (std::uint32_t v : used) renumbered[v] = UINT32_MAX;
    tiles.push_back(std::move(tile));
  }
  return tiles;
}

std::string tile_file_name(const Eigen::Vector3i& chunk) {
  return "tile_" + std::to_string(chunk.x()) + "_" + std::to_string(chunk.y()) + "_" +
         std::to_string(chunk.z()) + ".glb";
}

MeshTile read_tile(const io::PlyMeshFile& file, const Eigen::Vector3i& chunk,
                   std::uint64_t first_triangle, std::uint64_t triangles) {
  MeshTile tile;
  tile.chunk = chunk;
  tile.mesh.triangles = file.read_triangles(first_triangle, triangles);
  // Vertex rows in order of first use, then read in ascending order.
  std::vector<std::uint64_t> used;
  std::map<std::uint32_t, std::uint32_t> renumbered;
  for (Triangle& t : tile.mesh.triangles)
    for (std::uint32_t& v : t) {
      const auto [it, added] = renumbered.emplace(v, static_cast<std::uint32_t>(renumbered.size()));
      if (added) used.push_back(v);
      v = it->second;
    }
  std::vector<std::uint64_t> rows(used);
  std::sort(rows.begin(), rows.end());
  const TriangleMesh read = file.read_vertices(rows);
  TriangleMesh& m = tile.mesh;
  m.vertices.resize(used.size());
  if (!read.normals.empty()) m.normals.resize(used.size());
  if (!read.colors.empty()) m.colors.resize(used.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::uint32_t to = renumbered.at(static_cast<std::uint32_t>(rows[i]));
    m.vertices[to] = read.vertices[i];
    if (!read.normals.empty()) m.normals[to] = read.normals[i];
    if (!read.colors.empty()) m.colors[to] = read.colors[i];
  }
  return tile;
}

TileWriter::TileWriter(std::string dir, const ChunkGrid& grid, const Eigen::Vector3d& origin)
    : dir_(std::move(dir)), origin_(origin) {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec || !std::filesystem::is_directory(dir_))
    throw Error(dir_, "",
                "cannot create the tiles' directory" + (ec ? ": " + ec.message() : std::string()));
  index_ = "{\n  \"format\": \"meshflow-tiles-1\",\n  \"origin\": " + tiles_json_triple(origin) +
           ",\n  \"voxel\": " + tiles_json_number(grid.voxel_size) + ",\n  \"chunk_metres\": " +
           tiles_json_number(static_cast<double>(grid.voxel_size) * grid.chunk_cells) +
           ",\n  \"tiles\": [";
}

void TileWriter::add(const MeshTile& tile) {
  if (tile.mesh.triangles.empty()) return;
  const std::string name = tile_file_name(tile.chunk);
  io::write_glb((std::filesystem::path(dir_) / name).string(), tile.mesh, origin_);
  Eigen::AlignedBox3f box;
  for (const Eigen::Vector3f& v : tile.mesh.vertices) box.extend(v);
  index_ += std::string(tiles_ == 0 ? "\n" : ",\n") + "    {\"chunk\": [" +
            std::to_string(tile.chunk.x()) + ", " + std::to_string(tile.chunk.y()) + ", " +
            std::to_string(tile.chunk.z()) + "], \"file\": \"" + name +
            "\", \"vertices\": " + std::to_string(tile.mesh.vertices.size()) +
            ", \"triangles\": " + std::to_string(tile.mesh.triangles.size()) +
            ", \"min\": " + tiles_json_triple(box.min()) +
            ", \"max\": " + tiles_json_triple(box.max()) + "}";
  ++tiles_;
}

std::size_t TileWriter::finish() {
  io::AtomicOutputFile out((std::filesystem::path(dir_) / "tiles.json").string());
  out.stream() << index_ << (tiles_ == 0 ? "]\n}\n" : "\n  ]\n}\n");
  out.commit();
  return tiles_;
}

void write_tiles(const std::string& dir, const std::vector<MeshTile>& tiles, const ChunkGrid& grid,
                 const Eigen::Vector3d& origin) {
  TileWriter writer(dir, grid, origin);
  for (const MeshTile& tile : tiles) writer.add(tile);
  writer.finish();
}

}  // namespace meshflow::chunk
