#include "tools/mpi/mpi_tiles.h"

#include <algorithm>
#include <exception>
#include <functional>
#include <string>
#include <utility>

#include "graph/tile_levels.h"
#include "runtime/error.h"
#include "tools/mpi/mpi_bytes.h"

namespace meshflow::cli {
namespace {

using PositionedRecord = std::pair<std::uint64_t, chunk::TileRecord>;

void put_record(io::ByteWriter& w, const chunk::TileRecord& r) {
  put(w, r.chunk);
  put_string(w, r.file);
  w.u64(r.vertices);
  w.u64(r.triangles);
  put(w, r.min);
  put(w, r.max);
  w.u64(r.levels.size());
  for (const chunk::TileLevel& l : r.levels) {
    put_string(w, l.file);
    w.u64(l.triangles);
    w.u64(l.bytes);
    put(w, l.geometric_error);
  }
}

chunk::TileRecord get_record(io::ByteReader& r) {
  chunk::TileRecord t;
  t.chunk = get<Eigen::Vector3i>(r, "tile chunk");
  t.file = get_string(r, "tile file");
  t.vertices = r.u64("tile vertices");
  t.triangles = r.u64("tile triangles");
  t.min = get<Eigen::Vector3f>(r, "tile min");
  t.max = get<Eigen::Vector3f>(r, "tile max");
  const std::uint64_t levels = r.u64("tile levels");
  for (std::uint64_t i = 0; i < levels; ++i) {
    chunk::TileLevel l;
    l.file = get_string(r, "level file");
    l.triangles = r.u64("level triangles");
    l.bytes = r.u64("level bytes");
    l.geometric_error = get<double>(r, "level geometric error");
    t.levels.push_back(std::move(l));
  }
  return t;
}

// One rank's tiles: its records by position, its error and its timing.
struct RankTiles {
  std::vector<PositionedRecord> records;
  std::string error;
  chunk::RankTimes times;
};

std::vector<unsigned char> encode(const RankTiles& m) {
  io::ByteWriter w;
  w.u64(m.records.size());
  for (const auto& [position, record] : m.records) {
    w.u64(position);
    put_record(w, record);
  }
  put_string(w, m.error);
  put_rank_times(w, m.times);
  return std::move(w.out);
}

RankTiles decode(const std::vector<unsigned char>& message, int from) {
  const std::string source = "tiles written by rank " + std::to_string(from);
  io::ByteReader r(source, message);
  RankTiles m;
  const std::uint64_t records = r.u64("tiles");
  for (std::uint64_t i = 0; i < records; ++i) {
    const std::uint64_t position = r.u64("tile position");
    m.records.emplace_back(position, get_record(r));
  }
  m.error = get_string(r, "tiles error");
  m.times = get_rank_times(r);
  return m;
}

// Writes the tiles read(0), ..., read(n - 1), none empty, at `positions` (n of them) with their
// levels (chunk::write_tiles_in_flight()): their records by position. Throws meshflow::Error.
std::vector<PositionedRecord> write_read_tiles(
    const std::string& dir, const std::vector<std::uint64_t>& positions,
    const std::function<chunk::MeshTile(std::size_t)>& read, const Eigen::Vector3d& origin,
    std::size_t in_flight) {
  chunk::create_tile_directory(dir);
  std::vector<chunk::TileRecord> records = chunk::write_tiles_in_flight(
      dir, positions.size(), read, origin, progressive_levels(), in_flight);
  if (records.size() != positions.size())
    throw Error(dir, "tiles", "an empty tile was handed out to be written");
  std::vector<PositionedRecord> positioned;
  positioned.reserve(records.size());
  for (std::size_t i = 0; i < records.size(); ++i)
    positioned.emplace_back(positions[i], std::move(records[i]));
  return positioned;
}

// This rank's tiles, read back from the output's finished rows one at a time.
RankTiles write_own_tiles(const TileJob& job) {
  RankTiles mine;
  try {
    io::PlyMeshFile file(job.output, job.layout, job.vertices, job.triangles, job.origin,
                         io::PlyMeshFile::Role::kJoin);
    std::vector<std::array<std::uint64_t, 3>> rows;  // the non-empty ones, by position
    for (const auto& row : job.rows)
      if (row[2] > 0) rows.push_back(row);  // as write_tiles_in_flight() skips an empty tile
    std::sort(rows.begin(), rows.end());
    std::vector<std::uint64_t> positions;
    for (const auto& row : rows) positions.push_back(row[0]);
    mine.records = write_read_tiles(
        job.dir, positions,
        [&](std::size_t i) {
          const auto& [position, first, count] = rows[i];
          return chunk::read_tile(file, job.files->at(position).index, first, count);
        },
        job.origin, job.in_flight);
    file.close();
  } catch (const std::exception& e) {
    mine.error = e.what();
  }
  return mine;
}

// Hears rank 0's verdict (every rank): "" to go on, else why no rank writes tiles.
std::string hear_verdict(const std::string& verdict) {
  std::vector<unsigned char> heard(verdict.begin(), verdict.end());
  broadcast_bytes(heard);
  return std::string(heard.begin(), heard.end());
}

// After every rank wrote `mine` (phase "tiles" running): ranks other than 0 send rank 0 their
// records, error and timing (`chunks`: theirs); rank 0 (phase "index", serial) joins every
// rank's records in position order and writes the index.
TilesWritten join_tile_records(RankTiles mine, const std::string& dir, const chunk::ChunkGrid& grid,
                               const Eigen::Vector3d& origin, std::size_t chunks,
                               chunk::PhaseClock& clock, int rank, int ranks) {
  TilesWritten written;
  if (rank != 0) {
    clock.end();
    mine.times = {rank, chunks, chunk::peak_resident_bytes(), clock.phases()};
    send_bytes(encode(mine), 0);
    written.error = mine.error;
    return written;
  }
  clock.begin("index", true);  // every rank's records, then the index
  written.error = mine.error.empty() ? "" : "rank 0: " + mine.error;
  std::vector<PositionedRecord> records = std::move(mine.records);
  for (int from = 1; from < ranks; ++from) {
    RankTiles theirs = decode(receive_bytes(from), from);
    if (written.error.empty() && !theirs.error.empty())
      written.error = "rank " + std::to_string(from) + ": " + theirs.error;
    for (PositionedRecord& r : theirs.records) records.push_back(std::move(r));
    written.others.push_back(std::move(theirs.times));
  }
  if (!written.error.empty()) return written;
  std::sort(records.begin(), records.end(),
            [](const PositionedRecord& a, const PositionedRecord& b) { return a.first < b.first; });
  std::vector<chunk::TileRecord> index;
  index.reserve(records.size());
  for (PositionedRecord& r : records) index.push_back(std::move(r.second));
  try {
    chunk::write_tile_index(dir, grid, origin, index);
    written.tiles = index.size();
  } catch (const std::exception& e) {
    written.error = e.what();
  }
  return written;
}

// The tiles rank 0 hands one rank: each its position, chunk and mesh.
std::vector<unsigned char> encode_tiles(const std::vector<chunk::MeshTile>& tiles,
                                        const std::vector<std::size_t>& positions) {
  io::ByteWriter w;
  w.u64(positions.size());
  for (std::size_t i : positions) {
    w.u64(i);
    put(w, tiles[i].chunk);
    put_mesh(w, tiles[i].mesh);
  }
  return std::move(w.out);
}

// Reads what encode_tiles() sent: the tiles and their positions.
std::vector<chunk::MeshTile> decode_tiles(const std::vector<unsigned char>& message,
                                          std::vector<std::uint64_t>& positions) {
  io::ByteReader r("tiles sent by rank 0", message);
  const std::uint64_t count = r.u64("tiles");
  std::vector<chunk::MeshTile> tiles;
  for (std::uint64_t k = 0; k < count; ++k) {
    positions.push_back(r.u64("tile position"));
    chunk::MeshTile t;
    t.chunk = get<Eigen::Vector3i>(r, "tile chunk");
    t.mesh = get_mesh(r);
    tiles.push_back(std::move(t));
  }
  return tiles;
}

// Writes `tiles` (at `positions`), this rank's share, on this rank.
RankTiles write_given_tiles(const std::vector<chunk::MeshTile>& tiles,
                            const std::vector<std::uint64_t>& positions, const std::string& dir,
                            const Eigen::Vector3d& origin, std::size_t in_flight) {
  RankTiles mine;
  try {
    mine.records = write_read_tiles(
        dir, positions, [&](std::size_t i) { return tiles[i]; }, origin, in_flight);
  } catch (const std::exception& e) {
    mine.error = e.what();
  }
  return mine;
}

}  // namespace

TilesWritten write_tiles_on_ranks(const TileJob& job, const std::string& verdict,
                                  chunk::PhaseClock& clock, int rank, int ranks) {
  if (rank != 0) clock.wait("finish");  // rank 0 gathers the seams and finishes them
  TilesWritten written;
  written.error = hear_verdict(verdict);
  if (!written.error.empty()) return written;  // no rank writes tiles
  clock.begin("tiles", false);
  return join_tile_records(write_own_tiles(job), job.dir, job.grid, job.origin, job.chunks, clock,
                           rank, ranks);
}

TilesWritten scatter_tiles_to_ranks(const ScatterJob& job, const TriangleMesh& mesh,
                                    const std::function<int(const Eigen::Vector3i&)>& owner,
                                    const std::string& verdict, chunk::PhaseClock& clock, int rank,
                                    int ranks) {
  if (rank != 0) clock.wait("finish");  // rank 0 gathers the parts and finishes the mesh
  TilesWritten written;
  written.error = hear_verdict(verdict);
  if (!written.error.empty()) return written;  // no rank writes tiles
  std::vector<chunk::MeshTile> tiles;
  std::vector<std::uint64_t> positions;
  if (rank == 0) {
    clock.begin("scatter", true);  // the tiles cut, every other rank's sent, rank 0's kept
    tiles = chunk::split_into_tiles(mesh, job.grid);
    std::vector<std::vector<std::size_t>> dealt(static_cast<std::size_t>(ranks));
    for (std::size_t i = 0; i < tiles.size(); ++i) {
      const int to = owner(tiles[i].chunk);
      dealt[to > 0 && to < ranks ? static_cast<std::size_t>(to) : 0].push_back(i);
    }
    for (int to = 1; to < ranks; ++to) {
      const std::vector<std::size_t>& theirs = dealt[static_cast<std::size_t>(to)];
      send_bytes(encode_tiles(tiles, theirs), to);
      for (std::size_t i : theirs) tiles[i] = chunk::MeshTile{};
    }
    std::vector<chunk::MeshTile> own;
    for (std::size_t i : dealt.front()) {
      own.push_back(std::move(tiles[i]));
      positions.push_back(i);
    }
    tiles = std::move(own);
  } else {
    tiles = decode_tiles(receive_bytes(0), positions);
  }
  clock.begin("tiles", false);
  RankTiles mine = write_given_tiles(tiles, positions, job.dir, job.origin, job.in_flight);
  tiles = {};
  return join_tile_records(std::move(mine), job.dir, job.grid, job.origin, job.chunks, clock, rank,
                           ranks);
}

}  // namespace meshflow::cli
