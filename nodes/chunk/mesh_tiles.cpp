#include "nodes/chunk/mesh_tiles.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/parallel_reduce.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <system_error>

#include "nodes/io/atomic_file.h"
#include "nodes/io/glb_writer.h"
#include "nodes/search/mesh_distance_index.h"
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

// The largest distance of `from`'s vertices to the surface `to` indexes (max: the same at any
// split). A vertex needs a full search only when it is farther than the largest distance so far
// (Taha and Hanbury's early break): exact, and most vertices stop at their first triangle.
float farthest(const TriangleMesh& from, const MeshDistanceIndex& to) {
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, from.vertices.size()), 0.0f,
      [&](const tbb::blocked_range<std::size_t>& range, float most) {
        for (std::size_t v = range.begin(); v < range.end(); ++v)
          most = std::max(most, to.closest(from.vertices[v], most).distance);
        return most;
      },
      [](float a, float b) { return std::max(a, b); });
}

// level_error() with `fine`'s index built once for all its levels.
double level_error(const TriangleMesh& fine, const MeshDistanceIndex& fine_index,
                   const TriangleMesh& coarse) {
  if (fine.triangles.empty() || coarse.triangles.empty())
    return std::numeric_limits<double>::infinity();
  return std::max(static_cast<double>(farthest(fine, MeshDistanceIndex(coarse))),
                  static_cast<double>(farthest(coarse, fine_index)));
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

std::string tile_level_file_name(const Eigen::Vector3i& chunk, std::size_t level) {
  std::string name = tile_file_name(chunk);
  name.resize(name.size() - 4);  // ".glb"
  return name + "_lod" + std::to_string(level) + ".glb";
}

double level_error(const TriangleMesh& fine, const TriangleMesh& coarse) {
  return level_error(fine, MeshDistanceIndex(fine), coarse);
}

void create_tile_directory(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw Error(dir, "",
                "cannot create the tiles' directory" + (ec ? ": " + ec.message() : std::string()));
}

TileRecord write_tile(const std::string& dir, const MeshTile& tile, const Eigen::Vector3d& origin,
                      const std::vector<TriangleMesh>& coarser) {
  TileRecord record;
  record.chunk = tile.chunk;
  record.file = tile_file_name(tile.chunk);
  if (tile.mesh.triangles.empty()) throw Error(dir, record.file, "a tile without triangles");
  record.vertices = tile.mesh.vertices.size();
  record.triangles = tile.mesh.triangles.size();
  Eigen::AlignedBox3f box;
  for (const Eigen::Vector3f& v : tile.mesh.vertices) box.extend(v);
  record.min = box.min();
  record.max = box.max();
  // The levels' files, coarse to fine, then their errors from the finest up, each at least the
  // next finer level's.
  const auto write = [&](const std::string& name, const TriangleMesh& mesh) {
    const std::string path = (std::filesystem::path(dir) / name).string();
    io::write_glb(path, mesh, origin);
    return TileLevel{name, mesh.triangles.size(), std::filesystem::file_size(path), 0.0};
  };
  for (std::size_t i = 0; i < coarser.size(); ++i) {
    const std::size_t finer =
        i + 1 < coarser.size() ? coarser[i + 1].triangles.size() : tile.mesh.triangles.size();
    if (coarser[i].triangles.empty() || coarser[i].triangles.size() >= finer)
      throw Error(dir, tile_level_file_name(tile.chunk, i),
                  "a coarser level must have fewer triangles than the next, and some");
    record.levels.push_back(write(tile_level_file_name(tile.chunk, i), coarser[i]));
  }
  record.levels.push_back(write(record.file, tile.mesh));
  double error = 0.0;
  const MeshDistanceIndex fine(tile.mesh);
  for (std::size_t i = coarser.size(); i-- > 0;) {
    error = std::max(error, level_error(tile.mesh, fine, coarser[i]));
    record.levels[i].geometric_error = error;
  }
  return record;
}

void write_tile_index(const std::string& dir, const ChunkGrid& grid, const Eigen::Vector3d& origin,
                      const std::vector<TileRecord>& records) {
  std::string index =
      "{\n  \"format\": \"meshflow-tiles-2\",\n  \"origin\": " + tiles_json_triple(origin) +
      ",\n  \"voxel\": " + tiles_json_number(grid.voxel_size) + ",\n  \"chunk_metres\": " +
      tiles_json_number(static_cast<double>(grid.voxel_size) * grid.chunk_cells) +
      ",\n  \"tiles\": [";
  for (std::size_t t = 0; t < records.size(); ++t) {
    const TileRecord& r = records[t];
    index += std::string(t == 0 ? "\n" : ",\n") + "    {\"chunk\": [" +
             std::to_string(r.chunk.x()) + ", " + std::to_string(r.chunk.y()) + ", " +
             std::to_string(r.chunk.z()) + "], \"file\": \"" + r.file +
             "\", \"vertices\": " + std::to_string(r.vertices) +
             ", \"triangles\": " + std::to_string(r.triangles) +
             ", \"min\": " + tiles_json_triple(r.min) + ", \"max\": " + tiles_json_triple(r.max) +
             ",\n     \"levels\": [";
    for (std::size_t l = 0; l < r.levels.size(); ++l) {
      const TileLevel& level = r.levels[l];
      index += std::string(l == 0 ? "" : ",\n                ") + "{\"file\": \"" + level.file +
               "\", \"triangles\": " + std::to_string(level.triangles) +
               ", \"bytes\": " + std::to_string(level.bytes) +
               ", \"geometric_error\": " + tiles_json_number(level.geometric_error) + "}";
    }
    index += "]}";
  }
  io::AtomicOutputFile out((std::filesystem::path(dir) / "tiles.json").string());
  out.stream() << index << (records.empty() ? "]\n}\n" : "\n  ]\n}\n");
  out.commit();
  write_tileset_json(dir, grid, origin, records);
}

void write_tileset_json(const std::string& dir, const ChunkGrid& grid,
                        const Eigen::Vector3d& origin, const std::vector<TileRecord>& records) {
  // 3D Tiles reads glTF y-up and turns it z-up, (x, y, z) -> (x, -z, y); the root's transform
  // (column-major) turns that back, so boxes below it are in the turned frame.
  const auto turned = [](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(p.x(), -p.z(), p.y());
  };
  const auto box = [&](const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
    const double pad = grid.voxel_size;
    const Eigen::Vector3d a = lo.cast<double>() + origin, b = hi.cast<double>() + origin;
    const Eigen::Vector3d c = turned((a + b) / 2.0);
    const Eigen::Vector3d h = turned((b - a) / 2.0).cwiseAbs() + Eigen::Vector3d::Constant(pad);
    char text[512];
    std::snprintf(text, sizeof text,
                  "{\"box\": [%.17g, %.17g, %.17g, %.17g, 0, 0, 0, %.17g, 0, 0, 0, %.17g]}", c.x(),
                  c.y(), c.z(), h.x(), h.y(), h.z());
    return std::string(text);
  };
  Eigen::AlignedBox3f all;
  double most = 0.0;
  for (const TileRecord& r : records) {
    all.extend(r.min);
    all.extend(r.max);
    for (const TileLevel& l : r.levels) most = std::max(most, l.geometric_error);
  }
  if (records.empty()) all.extend(Eigen::Vector3f::Zero());
  const double root_error = std::max(most, static_cast<double>(all.diagonal().norm()));
  std::string children;
  for (const TileRecord& r : records) {
    // The chain, finest innermost.
    std::string chain;
    for (std::size_t l = r.levels.size(); l-- > 0;) {
      const TileLevel& level = r.levels[l];
      std::string node = "{\"boundingVolume\": ";
      node += box(r.min, r.max);
      node += ", \"geometricError\": ";
      node += tiles_json_number(level.geometric_error);
      node += ", \"refine\": \"REPLACE\", \"content\": {\"uri\": \"";
      node += level.file;
      node += "\"}";
      if (!chain.empty()) {
        node += ", \"children\": [";
        node += chain;
        node += "]";
      }
      node += "}";
      chain = std::move(node);
    }
    children += std::string(children.empty() ? "\n    " : ",\n    ") + chain;
  }
  io::AtomicOutputFile out((std::filesystem::path(dir) / "tileset.json").string());
  out.stream() << "{\"asset\": {\"version\": \"1.1\", \"generator\": \"meshflow\"},\n"
               << " \"geometricError\": " << tiles_json_number(root_error) << ",\n"
               << " \"root\": {\"transform\": [1, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1],\n"
               << "  \"boundingVolume\": " << box(all.min(), all.max())
               << ", \"geometricError\": " << tiles_json_number(root_error)
               << ", \"refine\": \"REPLACE\",\n  \"children\": [" << children << "]}}\n";
  out.commit();
}

std::vector<TileRecord> write_tiles_in_flight(const std::string& dir, std::size_t count,
                                              const std::function<MeshTile(std::size_t)>& read,
                                              const Eigen::Vector3d& origin,
                                              const CoarserLevels& levels, std::size_t in_flight) {
  std::vector<TileRecord> records;
  std::size_t next = 0;
  using Tile = std::shared_ptr<MeshTile>;
  using Record = std::shared_ptr<TileRecord>;  // null: an empty tile
  tbb::parallel_pipeline(
      std::max<std::size_t>(in_flight, 1),
      tbb::make_filter<void, Tile>(tbb::filter_mode::serial_in_order,
                                   [&](tbb::flow_control& fc) -> Tile {
                                     if (next == count) {
                                       fc.stop();
                                       return nullptr;
                                     }
                                     return std::make_shared<MeshTile>(read(next++));
                                   }) &
          tbb::make_filter<Tile, Record>(
              tbb::filter_mode::parallel,
              [&](const Tile& tile) -> Record {
                if (tile->mesh.triangles.empty()) return nullptr;
                return std::make_shared<TileRecord>(write_tile(
                    dir, *tile, origin, levels ? levels(tile->mesh) : std::vector<TriangleMesh>{}));
              }) &
          tbb::make_filter<Record, void>(tbb::filter_mode::serial_in_order,
                                         [&](const Record& record) {
                                           if (record) records.push_back(std::move(*record));
                                         }));
  return records;
}

void write_tiles(const std::string& dir, const std::vector<MeshTile>& tiles, const ChunkGrid& grid,
                 const Eigen::Vector3d& origin, const CoarserLevels& levels) {
  create_tile_directory(dir);
  std::vector<TileRecord> records(tiles.size());
  std::vector<std::uint8_t> written(tiles.size(), 0);
  tbb::parallel_for(std::size_t{0}, tiles.size(), [&](std::size_t i) {
    if (tiles[i].mesh.triangles.empty()) return;
    records[i] = write_tile(dir, tiles[i], origin,
                            levels ? levels(tiles[i].mesh) : std::vector<TriangleMesh>{});
    written[i] = 1;
  });
  std::vector<TileRecord> index;
  for (std::size_t i = 0; i < tiles.size(); ++i)
    if (written[i]) index.push_back(std::move(records[i]));
  write_tile_index(dir, grid, origin, index);
}

}  // namespace meshflow::chunk
