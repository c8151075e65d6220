#include "nodes/chunk/mesh_spill.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "runtime/error.h"

namespace meshflow::chunk {
namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

File open_spill(const std::string& path, const char* mode) {
  File f(std::fopen(path.c_str(), mode));
  if (!f) throw Error(path, "", std::string("cannot open mesh spill: ") + std::strerror(errno));
  return f;
}

template <typename T>
void put_array(std::FILE* f, const std::string& path, const std::vector<T>& values) {
  const std::uint64_t n = values.size();
  if (std::fwrite(&n, sizeof n, 1, f) != 1 ||
      (n > 0 && std::fwrite(values.data(), sizeof(T), values.size(), f) != values.size()))
    throw Error(path, "", std::string("mesh spill write failed: ") + std::strerror(errno));
}

template <typename T>
void get_array(std::FILE* f, const std::string& path, std::vector<T>& values) {
  std::uint64_t n = 0;
  if (std::fread(&n, sizeof n, 1, f) != 1) throw Error(path, "", "mesh spill is short");
  values.resize(n);
  if (n > 0 && std::fread(values.data(), sizeof(T), values.size(), f) != values.size())
    throw Error(path, "", "mesh spill is short");
}

}  // namespace

void write_mesh_spill(const std::string& path, const SpilledMesh& spilled) {
  const File f = open_spill(path, "wb");
  put_array(f.get(), path, spilled.mesh.vertices);
  put_array(f.get(), path, spilled.mesh.normals);
  put_array(f.get(), path, spilled.mesh.colors);
  put_array(f.get(), path, spilled.mesh.triangles);
  put_array(f.get(), path, spilled.flags);
  put_array(f.get(), path, spilled.vertex_piece);
  if (std::fflush(f.get()) != 0)
    throw Error(path, "", std::string("mesh spill write failed: ") + std::strerror(errno));
}

SpilledMesh read_mesh_spill(const std::string& path) {
  const File f = open_spill(path, "rb");
  SpilledMesh s;
  get_array(f.get(), path, s.mesh.vertices);
  get_array(f.get(), path, s.mesh.normals);
  get_array(f.get(), path, s.mesh.colors);
  get_array(f.get(), path, s.mesh.triangles);
  get_array(f.get(), path, s.flags);
  get_array(f.get(), path, s.vertex_piece);
  return s;
}

}  // namespace meshflow::chunk
