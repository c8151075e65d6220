#include "tools/mpi/mpi_tiles.h"

#include <algorithm>
#include <exception>
#include <utility>

#include "graph/tile_levels.h"
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

// This rank's tiles, read back from the output's finished rows one at a time.
RankTiles write_own_tiles(const TileJob& job) {
  RankTiles mine;
  try {
    chunk::create_tile_directory(job.dir);
    io::PlyMeshFile file(job.output, job.layout, job.vertices, job.triangles, job.origin,
                         io::PlyMeshFile::Role::kJoin);
    std::vector<std::array<std::uint64_t, 3>> rows;  // the non-empty ones, by position
    for (const auto& row : job.rows)
      if (row[2] > 0) rows.push_back(row);  // as write_tiles_in_flight() skips an empty tile
    std::sort(rows.begin(), rows.end());
    std::vector<chunk::TileRecord> records = chunk::write_tiles_in_flight(
        job.dir, rows.size(),
        [&](std::size_t i) {
          const auto& [position, first, count] = rows[i];
          return chunk::read_tile(file, job.files->at(position).index, first, count);
        },
        job.origin, progressive_levels(), job.in_flight);
    for (std::size_t i = 0; i < rows.size(); ++i)
      mine.records.emplace_back(rows[i][0], std::move(records[i]));
    file.close();
  } catch (const std::exception& e) {
    mine.error = e.what();
  }
  return mine;
}

}  // namespace

TilesWritten write_tiles_on_ranks(const TileJob& job, const std::string& verdict,
                                  chunk::PhaseClock& clock, int rank, int ranks) {
  TilesWritten written;
  if (rank != 0) clock.wait("finish");  // rank 0 gathers the seams and finishes them
  std::vector<unsigned char> heard(verdict.begin(), verdict.end());
  broadcast_bytes(heard);
  written.error.assign(heard.begin(), heard.end());
  if (!written.error.empty()) return written;  // no rank writes tiles
  clock.begin("tiles", false);
  RankTiles mine = write_own_tiles(job);
  if (rank != 0) {
    clock.end();
    mine.times = {rank, job.chunks, chunk::peak_resident_bytes(), clock.phases()};
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
    chunk::write_tile_index(job.dir, job.grid, job.origin, index);
    written.tiles = index.size();
  } catch (const std::exception& e) {
    written.error = e.what();
  }
  return written;
}

}  // namespace meshflow::cli
