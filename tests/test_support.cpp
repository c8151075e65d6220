#include "test_support.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace meshflow::test {

std::string data_dir() {
  const char* env = std::getenv("MESHFLOW_DATA");
  if (env != nullptr && *env != '\0') return env;
  return std::string(MESHFLOW_SOURCE_DIR) + "/../shared/data";
}

std::string data_path(const std::string& relative) { return data_dir() + "/" + relative; }

bool has_data(const std::string& relative) { return std::filesystem::exists(data_path(relative)); }

std::string fixture(const std::string& relative) {
  return std::string(MESHFLOW_SOURCE_DIR) + "/tests/data/" + relative;
}

std::string temp_dir() {
  static std::atomic<int> counter{0};
  const auto dir =
      std::filesystem::temp_directory_path() /
      ("meshflow_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

void write_file(const std::string& path, const std::string& content) {
  std::ofstream out(path, std::ios::binary);
  out << content;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::string flip_bytes(std::string text, int count, std::uint32_t& state) {
  for (int k = 0; k < count; ++k) {
    state = state * 1664525u + 1013904223u;
    text[state % text.size()] = static_cast<char>(state >> 24);
  }
  return text;
}

TriangleMesh grid_mesh(std::uint32_t n) {
  TriangleMesh m;
  for (std::uint32_t j = 0; j < n; ++j)
    for (std::uint32_t i = 0; i < n; ++i)
      m.vertices.emplace_back(static_cast<float>(i), static_cast<float>(j), 0.0f);
  for (std::uint32_t j = 0; j + 1 < n; ++j)
    for (std::uint32_t i = 0; i + 1 < n; ++i) {
      const std::uint32_t a = j * n + i;
      m.triangles.push_back({a, a + 1, a + n + 1});
      m.triangles.push_back({a, a + n + 1, a + n});
    }
  return m;
}

ErrorStats vertex_errors(const TriangleMesh& mesh,
                         const std::function<float(const Eigen::Vector3f&)>& distance) {
  ErrorStats s;
  for (const auto& v : mesh.vertices) {
    const double d = distance(v);
    s.mean += d;
    s.max = std::max(s.max, d);
  }
  if (!mesh.vertices.empty()) s.mean /= static_cast<double>(mesh.vertices.size());
  return s;
}

}  // namespace meshflow::test
