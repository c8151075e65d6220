#include "nodes/io/ply_point_writer.h"

#include <cstring>
#include <vector>

#include "runtime/error.h"

namespace meshflow::io {

PlyPointWriter::PlyPointWriter(const std::string& path, std::uint64_t count, bool normals,
                               bool colors)
    : path_(path), count_(count), normals_(normals), colors_(colors), file_(path) {
  std::ostream& out = file_.stream();
  out << "ply\nformat binary_little_endian 1.0\ncomment written by meshflow\nelement vertex "
      << count << "\nproperty float x\nproperty float y\nproperty float z\n";
  if (normals) out << "property float nx\nproperty float ny\nproperty float nz\n";
  if (colors) out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out << "end_header\n";
}

void PlyPointWriter::append(const PointCloud& batch) {
  const std::size_t n = batch.size();
  if ((normals_ && batch.normals.size() != n) || (colors_ && batch.colors.size() != n)) {
    throw Error(path_, "point batch", "lacks the normals or colours the header declares");
  }
  if (n > count_ - written_) {
    throw Error(path_, "point batch",
                "more points than the " + std::to_string(count_) + " the header declares");
  }
  static_assert(sizeof(float) == 4, "PLY float is 4 bytes");
  const std::size_t row = 12 + (normals_ ? 12 : 0) + (colors_ ? 3 : 0);
  std::vector<char> buffer(n * row);
  char* at = buffer.data();
  for (std::size_t i = 0; i < n; ++i) {  // little-endian host (checked by the build)
    std::memcpy(at, batch.positions[i].data(), 12);
    at += 12;
    if (normals_) {
      std::memcpy(at, batch.normals[i].data(), 12);
      at += 12;
    }
    if (colors_) {
      const Rgb8& c = batch.colors[i];
      *at++ = static_cast<char>(c.r);
      *at++ = static_cast<char>(c.g);
      *at++ = static_cast<char>(c.b);
    }
  }
  file_.stream().write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  written_ += n;
}

void PlyPointWriter::finish() {
  if (written_ != count_) {
    throw Error(path_, "vertex element",
                "only " + std::to_string(written_) + " of the " + std::to_string(count_) +
                    " declared points were written");
  }
  file_.commit();
}

}  // namespace meshflow::io
