#include "nodes/eval/double_walls.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <queue>
#include <utility>
#include <vector>

#include "nodes/search/spatial_index.h"
#include "runtime/vertex_triangles.h"

namespace meshflow {
namespace {

// Vertices reachable from `source` within `limit` metres along the mesh's edges (Dijkstra,
// bounded), sorted by index for binary search.
void reachable_within(const TriangleMesh& mesh, const VertexTriangles& around, std::uint32_t source,
                      float limit, std::vector<std::uint32_t>& reached,
                      std::vector<std::pair<std::uint32_t, float>>& best) {
  using Item = std::pair<float, std::uint32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  best.clear();
  const auto known = [&best](std::uint32_t v) -> std::pair<std::uint32_t, float>* {
    for (auto& b : best)
      if (b.first == v) return &b;
    return nullptr;
  };
  best.emplace_back(source, 0.0f);
  queue.emplace(0.0f, source);
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > known(v)->second) continue;
    for (const std::uint32_t* t = around.begin(v); t != around.end(v); ++t) {
      for (std::uint32_t w : mesh.triangles[*t]) {
        if (w == v) continue;
        const float dw = d + (mesh.vertices[w] - mesh.vertices[v]).norm();
        if (dw > limit) continue;
        auto* entry = known(w);
        if (entry == nullptr) {
          best.emplace_back(w, dw);
        } else if (dw < entry->second) {
          entry->second = dw;
        } else {
          continue;
        }
        queue.emplace(dw, w);
      }
    }
  }
  reached.clear();
  for (const auto& b : best) reached.push_back(b.first);
  std::sort(reached.begin(), reached.end());
}

// Two sheets of one surface face the same way: normals within about 45 degrees.
constexpr float kSameSide = 0.7f;

}  // namespace

double double_wall_area_share(const TriangleMesh& mesh, float radius) {
  const std::size_t n = mesh.vertices.size();
  if (n == 0 || mesh.triangles.empty() || !(radius > 0.0f)) return 0.0;
  const VertexTriangles around = vertex_triangles(mesh);
  std::vector<double> area(n, 0.0);
  for (const Triangle& t : mesh.triangles) {
    const double a = 0.5 * static_cast<double>((mesh.vertices[t[1]] - mesh.vertices[t[0]])
                                                   .cross(mesh.vertices[t[2]] - mesh.vertices[t[0]])
                                                   .norm());
    for (std::uint32_t v : t) area[v] += a / 3.0;
  }
  TriangleMesh with_normals;
  with_normals.vertices = mesh.vertices;
  with_normals.triangles = mesh.triangles;
  compute_vertex_normals(with_normals);  // from the winding, whatever normals the file had
  const std::vector<Eigen::Vector3f>& normal = with_normals.normals;
  const KdTreeIndex index(mesh.vertices);
  std::vector<std::uint8_t> doubled(n, 0);
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, static_cast<std::uint32_t>(n), 256),
                    [&](const tbb::blocked_range<std::uint32_t>& r) {
                      std::vector<std::uint32_t> reached;
                      std::vector<std::pair<std::uint32_t, float>> best;
                      for (std::uint32_t v = r.begin(); v != r.end(); ++v) {
                        const std::vector<std::uint32_t> near =
                            index.radius_search(mesh.vertices[v], radius);
                        if (near.size() <= 1) continue;
                        reachable_within(mesh, around, v, 3.0f * radius, reached, best);
                        for (std::uint32_t w : near) {
                          if (normal[v].dot(normal[w]) < kSameSide) continue;
                          if (!std::binary_search(reached.begin(), reached.end(), w)) {
                            doubled[v] = 1;
                            break;
                          }
                        }
                      }
                    });
  double total = 0.0, twice = 0.0;  // summed in vertex order: deterministic
  for (std::size_t v = 0; v < n; ++v) {
    total += area[v];
    if (doubled[v]) twice += area[v];
  }
  return total > 0.0 ? twice / total : 0.0;
}

}  // namespace meshflow
