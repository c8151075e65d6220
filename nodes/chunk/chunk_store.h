#pragma once
// Points spilled to one file per chunk in a single streaming pass over the input, so a cloud
// larger than memory can be reconstructed chunk by chunk (nodes/chunk/chunk_grid.h).

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "nodes/chunk/chunk_grid.h"
#include "runtime/point_cloud.h"

namespace meshflow::chunk {

/// One chunk's file and what went into it.
struct ChunkFile {
  Eigen::Vector3i index = Eigen::Vector3i::Zero();  ///< chunk index (ChunkGrid)
  /// Points in the chunk's own cells or one cell around them: those that can put surface in
  /// its cells (the rest of the overlap only informs normals and distances).
  std::uint64_t core_points = 0;
  std::uint64_t points = 0;  ///< all points of the file: core points and the overlap's
  std::string path;
  /// Further files holding the chunk's points, read after `path` in order: a partition by byte
  /// ranges writes one part per range (ChunkWriter), in the ranges' (the file's) order.
  std::vector<std::string> parts;
};

/// What each row of a chunk file holds besides x y z, and the frame its points are in.
struct ChunkRows {
  bool normals = false;                              ///< nx ny nz floats follow x y z
  bool colors = false;                               ///< r g b bytes end the row
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< PointCloud::origin of the input
  bool z_up = false;                                 ///< PointCloud::z_up of the input
  /// Bytes per row.
  std::size_t bytes() const { return 12 + (normals ? 12 : 0) + (colors ? 3 : 0); }
};

/// What one ChunkWriter spilled: its chunks (every chunk it wrote points to, by packed index)
/// and its counts; ChunkStore::finish() joins these of all writers.
struct WrittenPart {
  std::vector<ChunkFile> files;
  bool has_rows = false;  ///< it saw a batch (rows is meaningful)
  ChunkRows rows;
  Eigen::AlignedBox3f bounds;
  std::uint64_t points_read = 0, dropped = 0, rows_written = 0;
};

/// Spills point batches to one file per chunk under `directory`, the files named after the
/// chunk and `part` (".p<part>", or nothing for part < 0). Each point goes to every chunk that
/// sees its cell (ChunkGrid::chunks_seeing_cell), so a chunk's file holds all the points its
/// stages need; points keep their input order within a file. Buffers at most `buffer_bytes`
/// per chunk before appending to its file. Rows are raw little-endian floats (x y z, then nx ny
/// nz when the input has normals) and r g b bytes when it has colours. Writers of distinct
/// parts may run at once (threads, MPI ranks on a shared directory); one writer is not
/// thread-safe.
class ChunkWriter {
 public:
  /// A writer of part `part` (< 0: the only one) of `grid`'s chunk files under `directory`
  /// (which must exist), buffering up to `buffer_bytes` per chunk. Opens no file yet.
  ChunkWriter(const ChunkGrid& grid, std::string directory, long part,
              std::size_t buffer_bytes = std::size_t{1} << 18);

  /// Spills `batch` (local coordinates of `batch.origin`, which must equal the first batch's;
  /// finite points only, the others are counted and dropped). The first batch fixes whether
  /// rows carry normals and colours; a later batch that differs is a meshflow::Error. O(batch).
  void add(const PointCloud& batch);
  /// Writes every buffer out; returns what was written. Call once, after the last add().
  WrittenPart finish();

 private:
  struct Pending {
    ChunkFile file;
    std::vector<char> buffer;
  };
  void spill(Pending& chunk);

  ChunkGrid grid_;
  std::string directory_, suffix_;
  std::size_t buffer_bytes_;
  std::map<std::uint64_t, Pending> chunks_;  // by packed chunk index
  WrittenPart written_;
};

/// Reads a chunk's points written by ChunkWriter (its file, then its parts'; any process that
/// sees the files: MPI ranks on a shared directory). Throws meshflow::Error naming the file
/// when it is missing or short. Thread-safe. O(points).
PointCloud read_chunk_file(const ChunkFile& chunk, const ChunkRows& rows);

/// Deletes a chunk's files once read (disk space back early); a missing file is no error.
/// Thread-safe.
void remove_chunk_file(const ChunkFile& chunk);

/// The chunk files of one partition under a fresh directory: one ChunkWriter of its own (add())
/// or several writing parts at once (writer(), then finish(parts)). The directory and files are
/// removed by the destructor. Not thread-safe (distinct writers are).
class ChunkStore {
 public:
  /// Creates a directory "meshflow-chunks-XXXXXX" under `parent` (the system's temporary
  /// directory when empty). Throws meshflow::Error naming it and the system's reason.
  ChunkStore(const ChunkGrid& grid, const std::string& parent,
             std::size_t buffer_bytes = std::size_t{1} << 18);
  ~ChunkStore();
  ChunkStore(const ChunkStore&) = delete;
  ChunkStore& operator=(const ChunkStore&) = delete;

  /// Spills `batch` through the store's own writer (ChunkWriter::add). O(batch).
  void add(const PointCloud& batch);

  /// Writes every buffer out; returns the chunks with core points (ChunkFile), in
  /// Morton order (morton_code). Call once, after the last add().
  std::vector<ChunkFile> finish();

  /// A writer of part `part` (>= 0) into the store's directory: one per byte range of the
  /// input, each in its own thread or process.
  ChunkWriter writer(long part) const;
  /// Joins the parts' chunks (in the order of `parts`: the input's order) into the store:
  /// counts, rows (a part's rows that differ from the first part's are a meshflow::Error),
  /// and the chunks with core points, in Morton order, each with its parts' files in order;
  /// the files of chunks without core points are deleted. Call once, instead of finish().
  std::vector<ChunkFile> finish(const std::vector<WrittenPart>& parts);

  /// Reads a chunk's points back (with the origin of the input and normals / colours as
  /// spilled). Thread-safe for distinct chunks. Throws meshflow::Error on a short file.
  PointCloud read(const ChunkFile& chunk) const;
  /// Deletes a chunk's file once it has been read (disk space back early). Thread-safe.
  void remove(const ChunkFile& chunk) const;

  std::uint64_t points_read() const { return points_read_; }    ///< finite points added
  std::uint64_t points_dropped() const { return dropped_; }     ///< NaN / Inf points
  std::uint64_t rows_written() const { return rows_written_; }  ///< with overlap copies
  /// The rows' layout and the input's origin (PointCloud::origin), shared by every chunk.
  const ChunkRows& rows() const { return rows_; }
  /// Chunks are read with PointCloud::z_up set: the caller judged the whole input a height
  /// field (its estimated normals then face +z in every chunk, as in one process). O(1).
  void set_z_up() { rows_.z_up = true; }
  /// Bounds of the finite points read, local coordinates.
  const Eigen::AlignedBox3f& bounds() const { return bounds_; }
  /// The directory holding the chunk files.
  const std::string& directory() const { return directory_; }
  /// The partition the store was made with.
  const ChunkGrid& grid() const { return grid_; }

 private:
  ChunkGrid grid_;
  std::string directory_;
  std::size_t buffer_bytes_;
  std::unique_ptr<ChunkWriter> own_;  // add()'s writer
  ChunkRows rows_;
  Eigen::AlignedBox3f bounds_;
  std::uint64_t points_read_ = 0, dropped_ = 0, rows_written_ = 0;
};

}  // namespace meshflow::chunk
