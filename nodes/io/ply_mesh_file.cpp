#include "nodes/io/ply_mesh_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "runtime/error.h"

namespace meshflow::io {
namespace {

constexpr std::size_t kBlockBytes = std::size_t{4} << 20;

// Encodes rows [0, count) with `put_row(at, i)` (each `row_bytes`) into blocks of about 4 MiB
// and hands each block to `write(first_row, bytes, size)`.
template <typename PutRow, typename Write>
void write_rows(std::size_t count, std::size_t row_bytes, PutRow put_row, Write write) {
  const std::size_t per_block = std::max<std::size_t>(1, kBlockBytes / row_bytes);
  std::vector<char> buf(std::min(count, per_block) * row_bytes);
  for (std::size_t first = 0; first < count; first += per_block) {
    const std::size_t end = std::min(count, first + per_block);
    char* at = buf.data();
    for (std::size_t i = first; i < end; ++i) at = put_row(at, i);
    write(first, buf.data(), static_cast<std::size_t>(at - buf.data()));
  }
}

}  // namespace

PlyMeshFile::PlyMeshFile(std::string path, const PlyMeshLayout& layout, std::uint64_t vertices,
                         std::uint64_t triangles, const Eigen::Vector3d& origin, Role role)
    : path_(std::move(path)),
      temp_path_(path_ + ".tmp"),
      layout_(layout),
      vertices_(vertices),
      triangles_(triangles),
      origin_(origin),
      role_(role) {
  layout_.scalars = 0;
  const std::string header = ply_mesh_header(PlyEncoding::kBinary, layout_, vertices, triangles);
  header_bytes_ = header.size();
  if (role_ == Role::kJoin) {
    fd_ = ::open(temp_path_.c_str(), O_RDWR | O_CLOEXEC);
    if (fd_ < 0)
      throw Error(path_, "", std::string("cannot open output file: ") + std::strerror(errno));
    return;
  }
  std::error_code ec;
  if (std::filesystem::is_directory(path_, ec))
    throw Error(path_, "", "cannot write the output: it is a directory");
  fd_ = ::open(temp_path_.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd_ < 0)
    throw Error(path_, "", std::string("cannot create output file: ") + std::strerror(errno));
  write_at(0, header.data(), header.size());
}

PlyMeshFile::~PlyMeshFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_ && role_ == Role::kCreate) {
    std::error_code ec;
    std::filesystem::remove(temp_path_, ec);
  }
}

void PlyMeshFile::write_at(std::uint64_t offset, const char* bytes, std::size_t count) {
  while (count > 0) {
    const ssize_t n = ::pwrite(fd_, bytes, count, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      throw Error(path_, "", std::string("write failed: ") + std::strerror(n < 0 ? errno : EIO));
    bytes += n;
    offset += static_cast<std::uint64_t>(n);
    count -= static_cast<std::size_t>(n);
  }
}

void PlyMeshFile::read_at(std::uint64_t offset, char* bytes, std::size_t count) const {
  while (count > 0) {
    const ssize_t n = ::pread(fd_, bytes, count, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      throw Error(
          path_, "",
          std::string("read back failed: ") + (n < 0 ? std::strerror(errno) : "short file"));
    bytes += n;
    offset += static_cast<std::uint64_t>(n);
    count -= static_cast<std::size_t>(n);
  }
}

std::vector<Triangle> PlyMeshFile::read_triangles(std::uint64_t first, std::uint64_t count) const {
  if (first + count > triangles_) throw Error(path_, "faces", "reading past the declared rows");
  constexpr std::size_t kRow = PlyMeshLayout::kFaceBytes;
  std::vector<char> bytes(count * kRow);
  read_at(header_bytes_ + vertices_ * layout_.vertex_bytes() + first * kRow, bytes.data(),
          bytes.size());
  std::vector<Triangle> triangles(count);
  for (std::size_t i = 0; i < count; ++i)
    std::memcpy(triangles[i].data(), bytes.data() + i * kRow + 1, sizeof(Triangle));
  return triangles;
}

TriangleMesh PlyMeshFile::read_vertices(const std::vector<std::uint64_t>& rows) const {
  TriangleMesh m;
  m.vertices.reserve(rows.size());
  if (layout_.normals) m.normals.reserve(rows.size());
  if (layout_.colors) m.colors.reserve(rows.size());
  const std::size_t row = layout_.vertex_bytes();
  std::vector<char> bytes;
  for (std::size_t i = 0; i < rows.size();) {
    std::size_t end = i + 1;
    while (end < rows.size() && rows[end] == rows[end - 1] + 1) ++end;
    if (rows[end - 1] >= vertices_)
      throw Error(path_, "vertices", "reading past the declared rows");
    bytes.resize((end - i) * row);
    read_at(header_bytes_ + rows[i] * row, bytes.data(), bytes.size());
    for (const char* at = bytes.data(); at < bytes.data() + bytes.size(); at += row) {
      const char* field = at;
      if (layout_.world) {
        double p[3];
        std::memcpy(p, field, sizeof p);
        m.vertices.emplace_back(static_cast<float>(p[0] - origin_.x()),
                                static_cast<float>(p[1] - origin_.y()),
                                static_cast<float>(p[2] - origin_.z()));
        field += sizeof p;
      } else {
        float p[3];
        std::memcpy(p, field, sizeof p);
        m.vertices.emplace_back(p[0], p[1], p[2]);
        field += sizeof p;
      }
      if (layout_.normals) {
        float n[3];
        std::memcpy(n, field, sizeof n);
        m.normals.emplace_back(n[0], n[1], n[2]);
        field += sizeof n;
      }
      if (layout_.colors)
        m.colors.push_back(Rgb8{static_cast<std::uint8_t>(field[0]),
                                static_cast<std::uint8_t>(field[1]),
                                static_cast<std::uint8_t>(field[2])});
    }
    i = end;
  }
  return m;
}

void PlyMeshFile::write_vertices(std::uint64_t first, const TriangleMesh& part) {
  const std::size_t count = part.vertices.size();
  if (first + count > vertices_)
    throw Error(path_, "vertices", "more rows than the " + std::to_string(vertices_) + " declared");
  const std::size_t row = layout_.vertex_bytes();
  write_rows(
      count, row,
      [&](char* at, std::size_t i) { return put_ply_vertex(at, part, i, origin_, layout_); },
      [&](std::size_t i, const char* bytes, std::size_t size) {
        write_at(header_bytes_ + (first + i) * row, bytes, size);
      });
  vertex_rows_written_ += count;
}

void PlyMeshFile::write_triangles(std::uint64_t first, const std::vector<Triangle>& triangles) {
  const std::size_t count = triangles.size();
  if (first + count > triangles_)
    throw Error(path_, "faces", "more rows than the " + std::to_string(triangles_) + " declared");
  const std::uint64_t faces = header_bytes_ + vertices_ * layout_.vertex_bytes();
  constexpr std::size_t kRow = PlyMeshLayout::kFaceBytes;
  write_rows(
      count, kRow, [&](char* at, std::size_t i) { return put_ply_face(at, triangles[i]); },
      [&](std::size_t i, const char* bytes, std::size_t size) {
        write_at(faces + (first + i) * kRow, bytes, size);
      });
  face_rows_written_ += count;
}

void PlyMeshFile::write_normal(std::uint64_t vertex, const Eigen::Vector3f& normal) {
  if (!layout_.normals || vertex >= vertices_)
    throw Error(path_, "normals", "no normal row " + std::to_string(vertex));
  char bytes[12];
  std::memcpy(bytes, normal.data(), sizeof bytes);
  write_at(header_bytes_ + vertex * layout_.vertex_bytes() + layout_.normal_offset(), bytes,
           sizeof bytes);
}

void PlyMeshFile::write_triangle(std::uint64_t index, const Triangle& triangle) {
  if (index >= triangles_) throw Error(path_, "faces", "no face row " + std::to_string(index));
  char bytes[PlyMeshLayout::kFaceBytes];
  put_ply_face(bytes, triangle);
  write_at(header_bytes_ + vertices_ * layout_.vertex_bytes() + index * sizeof bytes, bytes,
           sizeof bytes);
}

void PlyMeshFile::add_rows_written_elsewhere(std::uint64_t vertices, std::uint64_t triangles) {
  vertex_rows_written_ += vertices;
  face_rows_written_ += triangles;
}

void PlyMeshFile::sync() {
  if (fd_ >= 0 && ::fsync(fd_) != 0)
    throw Error(path_, "", std::string("write failed: ") + std::strerror(errno));
}

void PlyMeshFile::close() {
  if (role_ != Role::kJoin) throw Error(path_, "", "the file's creator commits it");
  const int fd = fd_;
  fd_ = -1;
  if (fd >= 0 && ::close(fd) != 0)
    throw Error(path_, "", std::string("write failed: ") + std::strerror(errno));
}

void PlyMeshFile::commit() {
  if (role_ != Role::kCreate) throw Error(path_, "", "a joined writer cannot commit");
  if (vertex_rows_written_ < vertices_ || face_rows_written_ < triangles_)
    throw Error(path_, "",
                "incomplete: " + std::to_string(vertex_rows_written_) + " of " +
                    std::to_string(vertices_) + " vertices and " +
                    std::to_string(face_rows_written_) + " of " + std::to_string(triangles_) +
                    " faces written");
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0)
    throw Error(path_, "", std::string("write failed: ") + std::strerror(errno));
  std::error_code ec;
  std::filesystem::rename(temp_path_, path_, ec);
  if (ec) throw Error(path_, "", "cannot rename temporary file: " + ec.message());
  committed_ = true;
}

}  // namespace meshflow::io
