#include "test_support.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <tuple>
#include <vector>

#include "nodes/fusion/tsdf_map_file.h"
#include "nodes/normals/organized_normals.h"
#include "nodes/synthetic/closed_objects.h"

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

namespace {
std::uint32_t next(std::uint32_t& state) {
  state = state * 1664525u + 1013904223u;
  return state >> 8;
}
}  // namespace

std::string mutate(std::string text, std::uint32_t& state) {
  static const char* const kExtremes[] = {"-1",   "0",   "4294967295", "99999999999999999999",
                                          "1e39", "nan", "inf",        "-2147483648",
                                          "65536"};
  const std::uint32_t mutations = 1 + next(state) % 4;
  for (std::uint32_t m = 0; m < mutations && !text.empty(); ++m) {
    const std::size_t at = next(state) % text.size();
    switch (next(state) % 7) {
      case 0:
        text.resize(at);
        break;
      case 1:
        text[at] = static_cast<char>(text[at] ^ (1 << (next(state) % 8)));
        break;
      case 2:
        text[at] = static_cast<char>(next(state));
        break;
      case 3:
        text.insert(at, 1 + next(state) % 8, static_cast<char>(next(state)));
        break;
      case 4:
        text.erase(at, 1 + next(state) % 8);
        break;
      case 5: {
        const std::size_t from = text.find_first_of("0123456789", at);
        if (from == std::string::npos) break;
        const std::size_t to = text.find_first_not_of("0123456789.e+-", from);
        text.replace(from, (to == std::string::npos ? text.size() : to) - from,
                     kExtremes[next(state) % 9]);
        break;
      }
      default:
        text.insert(next(state) % (text.size() + 1), text.substr(at, 1 + next(state) % 16));
    }
  }
  return text;
}

std::string resealed_tsdf_map(std::string bytes) {
  reseal_tsdf_map(reinterpret_cast<std::uint8_t*>(bytes.data()), bytes.size());
  return bytes;
}

TriangleMesh tetrahedron() {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

WeldedTopology welded_topology(const TriangleMesh& mesh) {
  WeldedTopology w;
  const std::size_t n = mesh.vertices.size();
  // Weld: each vertex to the first at its position (positions sorted, then runs joined).
  std::vector<std::uint32_t> order(n), to(n);
  for (std::uint32_t v = 0; v < n; ++v) order[v] = to[v] = v;
  const auto key = [&](std::uint32_t v) {
    const Eigen::Vector3f& p = mesh.vertices[v];
    return std::make_tuple(p.x(), p.y(), p.z(), v);
  };
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
  for (std::size_t i = 0, j = 0; i < n; i = j) {
    for (j = i + 1; j < n && mesh.vertices[order[j]] == mesh.vertices[order[i]]; ++j)
      to[order[j]] = order[i];
    w.coincident_pairs += (j - i) * (j - i - 1) / 2;
  }
  std::vector<Triangle> welded;
  for (const Triangle& t : mesh.triangles) welded.push_back({to[t[0]], to[t[1]], to[t[2]]});
  TriangleMesh as_read;
  as_read.vertices = mesh.vertices;
  as_read.triangles = welded;
  w.non_manifold_edges = edge_statistics(as_read).non_manifold_edges;
  // Fans: the triangles around v joined where they share a corner other than v.
  std::vector<std::vector<std::uint32_t>> around(n);
  for (std::uint32_t t = 0; t < welded.size(); ++t)
    for (std::uint32_t c : welded[t]) around[c].push_back(t);
  for (std::uint32_t v = 0; v < n; ++v) {
    const std::vector<std::uint32_t>& tris = around[v];
    std::vector<std::uint32_t> fan(tris.size());
    for (std::uint32_t i = 0; i < fan.size(); ++i) fan[i] = i;
    const auto find = [&](std::uint32_t x) {
      while (fan[x] != x) x = fan[x];
      return x;
    };
    for (std::uint32_t i = 0; i < tris.size(); ++i)
      for (std::uint32_t j = 0; j < i; ++j)
        for (std::uint32_t x : welded[tris[i]])
          for (std::uint32_t y : welded[tris[j]])
            if (x != v && x == y) {
              const std::uint32_t a = find(i), b = find(j);
              fan[std::max(a, b)] = std::min(a, b);
            }
    std::size_t fans = 0;
    for (std::uint32_t i = 0; i < fan.size(); ++i) fans += find(i) == i;
    w.non_manifold_vertices += fans > 1;
  }
  return w;
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

TriangleMesh messy_mesh(std::uint32_t n, std::uint32_t seed) {
  TriangleMesh m = grid_mesh(n);
  std::mt19937 rng(seed);
  const auto random_below = [&](std::size_t bound) {
    return static_cast<std::uint32_t>(
        std::uniform_int_distribution<std::size_t>(0, bound - 1)(rng));
  };
  const std::size_t grid_triangles = m.triangles.size(), junk = grid_triangles / 4;
  for (std::size_t k = 0; k < junk; ++k) {
    const Triangle t = m.triangles[random_below(grid_triangles)];
    switch (random_below(4)) {
      case 0:  // a copy, rotated
        m.triangles.push_back({t[1], t[2], t[0]});
        break;
      case 1:  // a copy, reversed
        m.triangles.push_back({t[0], t[2], t[1]});
        break;
      case 2:  // a corner repeated
        m.triangles.push_back({t[0], t[0], t[2]});
        break;
      default: {  // one corner of t with two random vertices
        const auto count = static_cast<std::uint32_t>(m.vertices.size());
        m.triangles.push_back({t[random_below(3)], random_below(count), random_below(count)});
      }
    }
  }
  return m;
}

PointCloud camera_frame_cloud(const DepthFrame& frame) {
  DepthFrame camera = frame;
  camera.T_world_camera = Eigen::Isometry3f::Identity();
  return back_project(camera, depth_in_metres(camera));
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

std::string closed_object_test_name(int index) {
  std::string name = synthetic::closed_test_objects()[static_cast<std::size_t>(index)].name;
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

double max_abs_difference(const Image& a, const Image& b) {
  if (!a.same_size(b) || a.format() != b.format()) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  const auto channel_difference = [&worst](double x, double y) {
    worst = std::max(worst, std::abs(x - y));
  };
  for (int r = 0; r < a.rows(); ++r)
    for (int c = 0; c < a.cols(); ++c) switch (a.format()) {
        case PixelFormat::U8:
          channel_difference(a.at<std::uint8_t>(r, c), b.at<std::uint8_t>(r, c));
          break;
        case PixelFormat::U16:
          channel_difference(a.at<std::uint16_t>(r, c), b.at<std::uint16_t>(r, c));
          break;
        case PixelFormat::F32:
          channel_difference(a.at<float>(r, c), b.at<float>(r, c));
          break;
        case PixelFormat::RGB8: {
          const Rgb8 x = a.at<Rgb8>(r, c), y = b.at<Rgb8>(r, c);
          channel_difference(x.r, y.r);
          channel_difference(x.g, y.g);
          channel_difference(x.b, y.b);
          break;
        }
      }
  return worst;
}

}  // namespace meshflow::test
