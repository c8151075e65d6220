#include "nodes/extract/rim_trim.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <vector>

#include "runtime/parallel.h"
#include "runtime/vertex_triangles.h"

namespace meshflow {

namespace {

// Whether vertex v lies farther from the data than allowed: `limit` metres, or twice the
// spacing of the nearest point where the data are sparser than that (far parts of a scan).
bool beyond_data(const Eigen::Vector3f& v, const std::vector<Eigen::Vector3f>& positions,
                 const SpatialIndex& points, float limit) {
  std::uint32_t nearest = 0;
  float d2 = 0.0f;
  if (points.knn(v, 1, &nearest, &d2) != 1) return false;
  if (d2 <= limit * limit) return false;
  std::uint32_t pair[2];
  float pair_d2[2];
  if (points.knn(positions[nearest], 2, pair, pair_d2) < 2) return true;
  return d2 > 4.0f * pair_d2[1];
}

// The peeling rounds of trim_rim(), every pass parallel; measure(v) tells whether vertex v lies
// beyond the data (called in parallel, at most once per vertex).
template <typename Measure>
TriangleMesh peel_rim(const TriangleMesh& mesh, const Measure& measure, std::size_t* removed,
                      std::vector<std::uint32_t>* kept_vertices = nullptr) {
  constexpr int kMaxRounds = 16;
  const VertexTriangles around = vertex_triangles(mesh);
  std::vector<std::uint8_t> alive(mesh.triangles.size(), 1);
  // Whether {a, b} is an edge of exactly one live triangle.
  const auto border_edge = [&](std::uint32_t a, std::uint32_t b) {
    int faces = 0;
    for (const std::uint32_t* t = around.begin(a); t != around.end(a); ++t) {
      const Triangle& tri = mesh.triangles[*t];
      if (alive[*t] && (tri[0] == b || tri[1] == b || tri[2] == b)) ++faces;
    }
    return faces == 1;
  };
  // Per vertex: claimed for measuring (once), and the verdict; per triangle: a next candidate.
  std::vector<std::atomic<std::uint8_t>> claimed(mesh.vertices.size());
  std::vector<std::uint8_t> far(mesh.vertices.size(), 0);
  std::vector<std::atomic<std::uint8_t>> next(mesh.triangles.size());
  // The border triangles: a scan of each triangle's edges over the incidence (no per-thread
  // vertex arrays, which cost more in page faults than the scan itself).
  std::vector<std::uint8_t> on_border(mesh.triangles.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.triangles.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t t = r.begin(); t != r.end(); ++t) {
                        const Triangle& tri = mesh.triangles[t];
                        for (int k = 0; k < 3 && !on_border[t]; ++k)
                          on_border[t] = border_edge(tri[k], tri[(k + 1) % 3]) ? 1 : 0;
                      }
                    });
  std::vector<std::uint32_t> candidates =
      parallel_select_indices(on_border.size(), [&](std::size_t t) { return on_border[t] != 0; });
  std::size_t total = 0;
  for (int round = 0; round < kMaxRounds && !candidates.empty(); ++round) {
    // Each candidate's corners on its border edges (bit k: corner k); each such corner not yet
    // measured is measured by the one thread that claims it.
    std::vector<std::uint8_t> rim_corners(candidates.size(), 0);
    tbb::parallel_for(std::size_t{0}, candidates.size(), [&](std::size_t i) {
      const Triangle& t = mesh.triangles[candidates[i]];
      std::uint8_t corners = 0;
      for (int k = 0; k < 3; ++k)
        if (border_edge(t[k], t[(k + 1) % 3])) corners |= (1 << k) | (1 << (k + 1) % 3);
      rim_corners[i] = corners;
      for (int k = 0; k < 3; ++k)
        if ((corners >> k & 1) && claimed[t[k]].exchange(1, std::memory_order_relaxed) == 0)
          far[t[k]] = measure(t[k]) ? 1 : 0;
    });
    // The candidates with a rim corner beyond the data go (in candidate order).
    const std::vector<std::uint32_t> hit =
        parallel_select_indices(candidates.size(), [&](std::size_t i) {
          const Triangle& t = mesh.triangles[candidates[i]];
          for (int k = 0; k < 3; ++k)
            if ((rim_corners[i] >> k & 1) && far[t[k]] == 1) return true;
          return false;
        });
    tbb::parallel_for(std::size_t{0}, hit.size(),
                      [&](std::size_t j) { alive[candidates[hit[j]]] = 0; });
    total += hit.size();
    // Next round: the live triangles next to the ones just removed, ascending.
    tbb::parallel_for(std::size_t{0}, hit.size(), [&](std::size_t j) {
      for (std::uint32_t v : mesh.triangles[candidates[hit[j]]])
        for (const std::uint32_t* n = around.begin(v); n != around.end(v); ++n)
          if (alive[*n]) next[*n].store(1, std::memory_order_relaxed);
    });
    candidates = parallel_select_indices(mesh.triangles.size(), [&](std::size_t t) {
      return next[t].load(std::memory_order_relaxed) != 0;
    });
    tbb::parallel_for(std::size_t{0}, candidates.size(), [&](std::size_t i) {
      next[candidates[i]].store(0, std::memory_order_relaxed);
    });
  }
  if (removed != nullptr) *removed = total;
  if (total == 0) {  // unchanged, unused vertices included
    if (kept_vertices != nullptr) {
      kept_vertices->resize(mesh.vertices.size());
      for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
        (*kept_vertices)[v] = static_cast<std::uint32_t>(v);
    }
    return mesh;
  }
  const std::vector<std::uint32_t> live =
      parallel_select_indices(alive.size(), [&](std::size_t t) { return alive[t] != 0; });
  std::vector<Triangle> kept(live.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, live.size(), 16384),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        kept[i] = mesh.triangles[live[i]];
                    });
  return compact_vertices(mesh, kept, kept_vertices);
}

}  // namespace

TriangleMesh trim_rim(const TriangleMesh& mesh, const std::vector<Eigen::Vector3f>& positions,
                      const SpatialIndex& points, float max_distance, std::size_t* removed,
                      std::vector<std::uint32_t>* kept) {
  return peel_rim(
      mesh,
      [&](std::uint32_t v) {
        return beyond_data(mesh.vertices[v], positions, points, max_distance);
      },
      removed, kept);
}

TriangleMesh trim_rim(const TriangleMesh& mesh, const std::vector<std::uint8_t>& beyond,
                      std::size_t* removed, std::vector<std::uint32_t>* kept) {
  return peel_rim(
      mesh, [&](std::uint32_t v) { return beyond[v] != 0; }, removed, kept);
}

std::vector<std::uint8_t> vertices_beyond_data(const std::vector<Eigen::Vector3f>& vertices,
                                               const std::vector<Eigen::Vector3f>& positions,
                                               const SpatialIndex& points, float max_distance) {
  std::vector<std::uint8_t> beyond(vertices.size());
  tbb::parallel_for(std::size_t{0}, vertices.size(), [&](std::size_t v) {
    beyond[v] = beyond_data(vertices[v], positions, points, max_distance) ? 1 : 0;
  });
  return beyond;
}

}  // namespace meshflow
