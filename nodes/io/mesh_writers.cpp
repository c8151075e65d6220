#include "nodes/io/mesh_writers.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <vector>

#include "nodes/io/atomic_file.h"
#include "nodes/io/glb_writer.h"
#include "nodes/io/parse_util.h"
#include "nodes/io/ply_mesh_rows.h"
#include "runtime/default_init.h"
#include "runtime/error.h"

namespace meshflow::io {
namespace {
// "PREFIXx y z" of a vertex in world coordinates: as the float it is (9 digits) without an
// origin, else vertex + origin in double precision (12 digits: millimetres at 1e8 m).
std::string world_position_text(const char* prefix, const Eigen::Vector3f& v,
                                const Eigen::Vector3d& origin) {
  char text[128];
  if (origin.isZero()) {
    std::snprintf(text, sizeof text, "%s%.9g %.9g %.9g", prefix, v.x(), v.y(), v.z());
  } else {
    const Eigen::Vector3d w = v.cast<double>() + origin;
    std::snprintf(text, sizeof text, "%s%.12g %.12g %.12g", prefix, w.x(), w.y(), w.z());
  }
  return text;
}
}  // namespace

void write_ply(const std::string& path, const TriangleMesh& mesh, PlyEncoding encoding,
               const Eigen::Vector3d& origin, const std::vector<VertexScalar>& scalars) {
  for (const VertexScalar& scalar : scalars) {
    const bool word =
        !scalar.name.empty() && std::all_of(scalar.name.begin(), scalar.name.end(), [](char c) {
          return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
        });
    if (!word) throw Error(path, scalar.name, "a vertex property name must be a PLY word");
    if (scalar.values.size() != mesh.vertices.size())
      throw Error(path, scalar.name,
                  std::to_string(scalar.values.size()) + " values for " +
                      std::to_string(mesh.vertices.size()) + " vertices");
  }
  AtomicOutputFile file(path);
  std::ostream& out = file.stream();
  const PlyMeshLayout layout = ply_mesh_layout(mesh, origin, scalars.size());
  const bool normals = layout.normals, colors = layout.colors, world = layout.world;
  out << ply_mesh_header(encoding, layout, mesh.vertices.size(), mesh.triangles.size(), scalars);
  if (encoding == PlyEncoding::kAscii) {
    char line[256];
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      const Eigen::Vector3d v = mesh.vertices[i].cast<double>() + origin;
      int n = std::snprintf(line, sizeof line, world ? "%.12g %.12g %.12g" : "%.9g %.9g %.9g",
                            v.x(), v.y(), v.z());
      if (normals) {
        const auto& nv = mesh.normals[i];
        n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), " %.7g %.7g %.7g",
                           nv.x(), nv.y(), nv.z());
      }
      if (colors) {
        const auto& c = mesh.colors[i];
        n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), " %d %d %d", c.r,
                           c.g, c.b);
      }
      out << line;
      for (const VertexScalar& scalar : scalars) {
        std::snprintf(line, sizeof line, " %.7g", static_cast<double>(scalar.values[i]));
        out << line;
      }
      out << '\n';
    }
    for (const Triangle& t : mesh.triangles)
      out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  } else {
    // Rows of fixed size, formatted in parallel into blocks of 4 MiB (row i of a block at
    // (i - first) x row bytes), each block written once filled: the file's bytes in order,
    // and a mesh of millions of triangles is not held a second time as its file.
    constexpr std::size_t kBlock = std::size_t{4} << 20;
    const std::size_t vertex_bytes = layout.vertex_bytes();
    UninitVector<char> buf(std::max({kBlock, vertex_bytes, PlyMeshLayout::kFaceBytes}));
    const auto write_rows = [&](std::size_t count, std::size_t row_bytes, const auto& put) {
      const std::size_t per_block = std::max<std::size_t>(1, kBlock / row_bytes);
      for (std::size_t first = 0; first < count; first += per_block) {
        const std::size_t last = std::min(count, first + per_block);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(first, last, 8192),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                            for (std::size_t i = r.begin(); i != r.end(); ++i)
                              put(buf.data() + (i - first) * row_bytes, i);
                          });
        out.write(buf.data(), static_cast<std::streamsize>((last - first) * row_bytes));
      }
    };
    write_rows(mesh.vertices.size(), vertex_bytes, [&](char* at, std::size_t i) {
      put_ply_vertex(at, mesh, i, origin, layout, scalars);
    });
    write_rows(mesh.triangles.size(), PlyMeshLayout::kFaceBytes,
               [&](char* at, std::size_t t) { put_ply_face(at, mesh.triangles[t]); });
  }
  file.commit();
}

void write_obj(const std::string& path, const TriangleMesh& mesh, const Eigen::Vector3d& origin) {
  AtomicOutputFile file(path);
  std::ostream& out = file.stream();
  const bool normals = mesh.normals.size() == mesh.vertices.size() && !mesh.normals.empty();
  const bool colors = mesh.colors.size() == mesh.vertices.size() && !mesh.colors.empty();
  out << "# written by meshflow\n";
  char line[160];
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    out << world_position_text("v ", mesh.vertices[i], origin);
    if (colors) {
      const Rgb8& c = mesh.colors[i];
      std::snprintf(line, sizeof line, " %.4g %.4g %.4g", c.r / 255.0, c.g / 255.0, c.b / 255.0);
      out << line;
    }
    out << '\n';
  }
  if (normals) {
    for (const auto& n : mesh.normals) {
      std::snprintf(line, sizeof line, "vn %.7g %.7g %.7g\n", n.x(), n.y(), n.z());
      out << line;
    }
  }
  for (const Triangle& t : mesh.triangles) {
    if (normals) {
      std::snprintf(line, sizeof line, "f %u//%u %u//%u %u//%u\n", t[0] + 1, t[0] + 1, t[1] + 1,
                    t[1] + 1, t[2] + 1, t[2] + 1);
    } else {
      std::snprintf(line, sizeof line, "f %u %u %u\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    out << line;
  }
  file.commit();
}

void write_stl(const std::string& path, const TriangleMesh& mesh, const Eigen::Vector3d& origin) {
  AtomicOutputFile file(path);
  if (mesh.triangles.size() > 0xFFFFFFFFull)
    throw Error(path, "", "STL holds at most 2^32 - 1 triangles");
  std::vector<char> buf(84 + 50 * mesh.triangles.size(), 0);
  char header[81];
  if (origin.isZero())
    std::snprintf(header, sizeof header, "binary STL written by meshflow");
  else  // float32 corners: local coordinates, the origin in the header's text
    std::snprintf(header, sizeof header, "meshflow; local frame, origin %.3f %.3f %.3f", origin.x(),
                  origin.y(), origin.z());
  std::memcpy(buf.data(), header, std::strlen(header));
  char* at = put_bytes(buf.data() + 80, static_cast<std::uint32_t>(mesh.triangles.size()));
  for (const Triangle& t : mesh.triangles) {
    const Eigen::Vector3f n = face_normal(mesh, t);
    for (int k = 0; k < 3; ++k) at = put_bytes(at, n[k]);
    for (std::uint32_t v : t)
      for (int k = 0; k < 3; ++k) at = put_bytes(at, mesh.vertices[v][k]);
    at = put_bytes(at, std::uint16_t{0});  // attribute byte count
  }
  file.stream().write(buf.data(), static_cast<std::streamsize>(buf.size()));
  file.commit();
}

void write_off(const std::string& path, const TriangleMesh& mesh, const Eigen::Vector3d& origin) {
  AtomicOutputFile file(path);
  std::ostream& out = file.stream();
  const bool colors = mesh.colors.size() == mesh.vertices.size() && !mesh.colors.empty();
  out << (colors ? "COFF" : "OFF") << "\n# written by meshflow\n"
      << mesh.vertices.size() << ' ' << mesh.triangles.size() << " 0\n";
  char line[128];
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    out << world_position_text("", mesh.vertices[i], origin);
    if (colors) {
      const Rgb8& c = mesh.colors[i];
      std::snprintf(line, sizeof line, " %d %d %d 255", c.r, c.g, c.b);
      out << line;
    }
    out << '\n';
  }
  for (const Triangle& t : mesh.triangles)
    out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  file.commit();
}

namespace {
constexpr const char* kMeshOutputFormats = "expected .ply .obj .stl .off or .glb";
}

void check_mesh_output_format(const std::string& path) {
  const std::string ext = lower_extension(path);
  bool known_format = false;
  for (const char* known : {".ply", ".obj", ".stl", ".off", ".glb"}) known_format |= ext == known;
  if (!known_format)
    throw Error(path, "", "unknown mesh format '" + ext + "' (" + kMeshOutputFormats + ")");
  check_output_writable(path);
}

void write_mesh(const std::string& path, const TriangleMesh& mesh, const Eigen::Vector3d& origin) {
  const std::string ext = lower_extension(path);
  if (ext == ".ply") return write_ply(path, mesh, PlyEncoding::kBinary, origin);
  if (ext == ".obj") return write_obj(path, mesh, origin);
  if (ext == ".stl") return write_stl(path, mesh, origin);
  if (ext == ".off") return write_off(path, mesh, origin);
  if (ext == ".glb") return write_glb(path, mesh, origin);
  check_mesh_output_format(path);  // throws
}

}  // namespace meshflow::io
