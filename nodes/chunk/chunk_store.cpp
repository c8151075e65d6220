#include "nodes/chunk/chunk_store.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>

#include "nodes/io/byte_buffer.h"
#include "runtime/error.h"
#include "runtime/voxel_key.h"

namespace meshflow::chunk {
namespace {

std::string chunk_name(const Eigen::Vector3i& k) {
  return "chunk_" + std::to_string(k.x()) + "_" + std::to_string(k.y()) + "_" +
         std::to_string(k.z()) + ".bin";
}

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

}  // namespace

PointCloud read_chunk_file(const ChunkFile& chunk, const ChunkRows& rows) {
  const std::size_t row = rows.bytes();
  std::vector<unsigned char> bytes = io::read_file_bytes(chunk.path);
  for (const std::string& part : chunk.parts) {
    const std::vector<unsigned char> more = io::read_file_bytes(part);
    bytes.insert(bytes.end(), more.begin(), more.end());
  }
  if (bytes.size() != chunk.points * row) {
    throw Error(chunk.path, "chunk file",
                "expected " + std::to_string(chunk.points) + " points of " + std::to_string(row) +
                    " bytes" + (chunk.parts.empty() ? "" : " in its parts") + ", found " +
                    std::to_string(bytes.size()) + " bytes");
  }
  PointCloud cloud;
  cloud.origin = rows.origin;
  cloud.z_up = rows.z_up;
  const std::size_t n = chunk.points;
  cloud.positions.resize(n);
  if (rows.normals) cloud.normals.resize(n);
  if (rows.colors) cloud.colors.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned char* in = bytes.data() + i * row;
    std::memcpy(cloud.positions[i].data(), in, 12);
    if (rows.normals) std::memcpy(cloud.normals[i].data(), in + 12, 12);
    if (rows.colors) {
      cloud.colors[i] = Rgb8{in[row - 3], in[row - 2], in[row - 1]};
    }
  }
  return cloud;
}

ChunkWriter::ChunkWriter(const ChunkGrid& grid, std::string directory, long part,
                         std::size_t buffer_bytes)
    : grid_(grid),
      directory_(std::move(directory)),
      suffix_(part < 0 ? "" : ".p" + std::to_string(part)),
      buffer_bytes_(std::max<std::size_t>(buffer_bytes, 4096)) {}

void ChunkWriter::spill(Pending& chunk) {
  if (chunk.buffer.empty()) return;
  File f(std::fopen(chunk.file.path.c_str(), "ab"));
  if (!f ||
      std::fwrite(chunk.buffer.data(), 1, chunk.buffer.size(), f.get()) != chunk.buffer.size()) {
    throw Error(chunk.file.path, "chunk file",
                std::string("cannot write the points: ") + std::strerror(errno));
  }
  if (std::fflush(f.get()) != 0)
    throw Error(chunk.file.path, "chunk file",
                std::string("cannot write: ") + std::strerror(errno));
  chunk.buffer.clear();
}

void ChunkWriter::add(const PointCloud& batch) {
  const bool normals = batch.has_normals(), colors = batch.has_colors();
  ChunkRows& rows = written_.rows;
  if (!written_.has_rows) {
    written_.has_rows = true;
    rows.normals = normals;
    rows.colors = colors;
    rows.origin = batch.origin;
    rows.z_up = batch.z_up;
  } else if (normals != rows.normals || colors != rows.colors || batch.origin != rows.origin) {
    throw Error("chunks", "point batch",
                "a batch of the input differs from the first in its normals, colours or origin");
  }
  const std::size_t row = rows.bytes();
  std::vector<Eigen::Vector3i> seeing;
  std::vector<Pending*> targets;
  Eigen::Vector3i cached_lo(1, 0, 0), cached_hi(0, 0, 0);  // empty: no cache yet
  for (std::size_t i = 0; i < batch.size(); ++i) {
    const Eigen::Vector3f& p = batch.positions[i];
    if (!p.allFinite()) {
      ++written_.dropped;
      continue;
    }
    const Eigen::Vector3i cell = cell_of(p, grid_.voxel_size);
    if (!cell_index_in_range(cell)) {
      throw Error("chunks", "point " + std::to_string(written_.points_read + written_.dropped),
                  "lies outside the grid's range at a voxel of " +
                      std::to_string(grid_.voxel_size) + " m (about +-" +
                      std::to_string(kMaxCellIndex) + " cells from the origin)");
    }
    const Eigen::Vector3i lo =
        grid_.chunk_of_cell(cell - Eigen::Vector3i::Constant(grid_.overlap_cells));
    const Eigen::Vector3i hi =
        grid_.chunk_of_cell(cell + Eigen::Vector3i::Constant(grid_.overlap_cells));
    if (lo != cached_lo || hi != cached_hi) {  // most points share their neighbour's chunks
      cached_lo = lo;
      cached_hi = hi;
      grid_.chunks_seeing_cell(cell, seeing);
      targets.clear();
      for (const Eigen::Vector3i& k : seeing) {
        Pending& chunk = chunks_[pack_key(k)];
        if (chunk.file.path.empty()) {
          chunk.file.index = k;
          chunk.file.path = directory_ + "/" + chunk_name(k) + suffix_;
        }
        targets.push_back(&chunk);
      }
    }
    // Chunks whose own cells a point can put surface in: its cell's and the neighbours' (the
    // grid has cells around points, VoxelizeConfig::margin <= 1).
    const Eigen::Vector3i near_lo = grid_.chunk_of_cell(cell - Eigen::Vector3i::Ones());
    const Eigen::Vector3i near_hi = grid_.chunk_of_cell(cell + Eigen::Vector3i::Ones());
    for (Pending* chunk : targets) {
      const std::size_t at = chunk->buffer.size();
      chunk->buffer.resize(at + row);
      char* out = chunk->buffer.data() + at;
      std::memcpy(out, p.data(), 12);
      if (rows.normals) std::memcpy(out + 12, batch.normals[i].data(), 12);
      if (rows.colors) {
        const Rgb8& c = batch.colors[i];
        out[row - 3] = static_cast<char>(c.r);
        out[row - 2] = static_cast<char>(c.g);
        out[row - 1] = static_cast<char>(c.b);
      }
      ++chunk->file.points;
      const Eigen::Vector3i& k = chunk->file.index;
      if ((k.array() >= near_lo.array()).all() && (k.array() <= near_hi.array()).all())
        ++chunk->file.core_points;
      if (chunk->buffer.size() + row > buffer_bytes_) spill(*chunk);
    }
    written_.rows_written += targets.size();
    written_.bounds.extend(p);
    ++written_.points_read;
  }
}

WrittenPart ChunkWriter::finish() {
  for (auto& [key, chunk] : chunks_) {
    spill(chunk);
    chunk.buffer = std::vector<char>();
    written_.files.push_back(chunk.file);
  }
  chunks_.clear();
  return std::move(written_);
}

ChunkStore::ChunkStore(const ChunkGrid& grid, const std::string& parent, std::size_t buffer_bytes)
    : grid_(grid), buffer_bytes_(buffer_bytes) {
  if (!(grid.voxel_size > 0.0f) || grid.chunk_cells < 1 || grid.overlap_cells < 1)
    throw Error("chunks", "grid", "voxel size, chunk size and overlap must be positive");
  std::error_code ec;
  const std::filesystem::path base =
      parent.empty() ? std::filesystem::temp_directory_path(ec) : std::filesystem::path(parent);
  std::string pattern = (base / "meshflow-chunks-XXXXXX").string();
  if (ec || ::mkdtemp(pattern.data()) == nullptr) {
    throw Error(
        base.string(), "chunk directory",
        std::string("cannot create a directory for the chunk files: ") + std::strerror(errno));
  }
  directory_ = pattern;
  own_ = std::make_unique<ChunkWriter>(grid_, directory_, -1, buffer_bytes_);
}

ChunkStore::~ChunkStore() {
  std::error_code ec;
  std::filesystem::remove_all(directory_, ec);
}

void ChunkStore::add(const PointCloud& batch) { own_->add(batch); }

ChunkWriter ChunkStore::writer(long part) const {
  return ChunkWriter(grid_, directory_, std::max(part, 0L), buffer_bytes_);
}

std::vector<ChunkFile> ChunkStore::finish() {
  std::vector<WrittenPart> parts;
  parts.push_back(own_->finish());
  return finish(parts);
}

std::vector<ChunkFile> ChunkStore::finish(const std::vector<WrittenPart>& parts) {
  const bool z_up = rows_.z_up;
  bool first = true;
  std::map<std::uint64_t, ChunkFile> joined;  // by packed chunk index
  for (const WrittenPart& part : parts) {
    points_read_ += part.points_read;
    dropped_ += part.dropped;
    rows_written_ += part.rows_written;
    bounds_.extend(part.bounds);
    if (part.has_rows) {
      if (first) {
        rows_ = part.rows;
        first = false;
      } else if (part.rows.normals != rows_.normals || part.rows.colors != rows_.colors ||
                 part.rows.origin != rows_.origin) {
        throw Error("chunks", "parts",
                    "a part of the input differs from the first in its normals, colours or "
                    "origin");
      }
    }
    for (const ChunkFile& f : part.files) {
      ChunkFile& chunk = joined[pack_key(f.index)];
      if (chunk.path.empty()) {
        chunk = f;
        continue;
      }
      chunk.parts.push_back(f.path);
      chunk.parts.insert(chunk.parts.end(), f.parts.begin(), f.parts.end());
      chunk.points += f.points;
      chunk.core_points += f.core_points;
    }
  }
  rows_.z_up = rows_.z_up || z_up;
  std::vector<ChunkFile> files;
  for (auto& [key, chunk] : joined) {
    if (chunk.core_points == 0) {  // only far overlap: no surface of its own
      remove_chunk_file(chunk);
      continue;
    }
    files.push_back(std::move(chunk));
  }
  std::sort(files.begin(), files.end(), [](const ChunkFile& a, const ChunkFile& b) {
    return morton_code(a.index) < morton_code(b.index);
  });
  return files;
}

PointCloud ChunkStore::read(const ChunkFile& chunk) const { return read_chunk_file(chunk, rows_); }

void ChunkStore::remove(const ChunkFile& chunk) const { remove_chunk_file(chunk); }

void remove_chunk_file(const ChunkFile& chunk) {
  std::error_code ec;
  std::filesystem::remove(chunk.path, ec);
  for (const std::string& part : chunk.parts) std::filesystem::remove(part, ec);
}

}  // namespace meshflow::chunk
