#pragma once
// A binary PLY point file written in batches: for clouds too large to hold (the synthetic city of
// tens of millions of points, chunk files of the out-of-core path).

#include <cstdint>
#include <memory>
#include <string>

#include "nodes/io/atomic_file.h"
#include "runtime/point_cloud.h"

namespace meshflow::io {

/// Writes "element vertex `count`" with float x y z, and nx ny nz / uchar red green blue when
/// asked, then rows appended batch by batch. Atomic (AtomicOutputFile): the file appears on
/// finish() with exactly `count` rows, or not at all. Not thread-safe. Memory O(1) besides the
/// stream buffer.
class PlyPointWriter {
 public:
  /// Opens `path` (its temporary file) and writes the header. Throws meshflow::Error naming
  /// the file and the system's reason.
  PlyPointWriter(const std::string& path, std::uint64_t count, bool normals, bool colors);

  /// Appends every point of `batch`, which must carry normals / colours as declared. Throws
  /// meshflow::Error when a batch lacks them or would exceed `count`. O(batch).
  void append(const PointCloud& batch);

  /// Commits the file. Throws meshflow::Error naming the file when fewer than `count` rows were
  /// appended (the declared count would lie) or the write failed.
  void finish();

  /// Rows appended so far.
  std::uint64_t written() const { return written_; }

 private:
  std::string path_;
  std::uint64_t count_;
  bool normals_, colors_;
  std::uint64_t written_ = 0;
  AtomicOutputFile file_;
};

}  // namespace meshflow::io
