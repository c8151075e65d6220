#pragma once
// Small meshes and checks shared by the optimisation tests.

#include <exception>
#include <functional>
#include <string>

#include "runtime/half_edge_mesh.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::test {

/// `mesh` without the triangles whose centroid satisfies `cut` (vertices kept as they are).
inline TriangleMesh without_faces(const TriangleMesh& mesh,
                                  const std::function<bool(const Eigen::Vector3f&)>& cut) {
  TriangleMesh out;
  out.vertices = mesh.vertices;
  for (const Triangle& t : mesh.triangles)
    if (!cut((mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3.0f))
      out.triangles.push_back(t);
  return out;
}

/// The sheet z = height(x) over x in [-1, 1], y in [0, 0.9], 21 x 10 vertices 10 cm apart,
/// two triangles per cell facing up.
inline TriangleMesh profile_sheet(const std::function<float(float)>& height) {
  TriangleMesh m;
  const int n = 10;
  for (int j = 0; j < n; ++j)
    for (int i = -n; i <= n; ++i) {
      const float x = static_cast<float>(i) * 0.1f;
      m.vertices.emplace_back(x, static_cast<float>(j) * 0.1f, height(x));
    }
  const auto w = static_cast<std::uint32_t>(2 * n + 1);
  for (std::uint32_t j = 0; j + 1 < static_cast<std::uint32_t>(n); ++j)
    for (std::uint32_t i = 0; i + 1 < w; ++i) {
      const std::uint32_t a = j * w + i;
      m.triangles.push_back({a, a + 1, a + w + 1});
      m.triangles.push_back({a, a + w + 1, a + w});
    }
  return m;
}

/// Two planes meeting at 90 degrees along x = 0: z = 0 for x <= 0 and z = x beyond.
inline TriangleMesh bent_sheet() {
  return profile_sheet([](float x) { return x > 0 ? x : 0.0f; });
}

/// "" when the mesh builds into a valid half-edge mesh, else the first problem found.
inline std::string half_edge_problem(const TriangleMesh& mesh) {
  try {
    return HalfEdgeMesh(mesh).check();
  } catch (const std::exception& e) {
    return e.what();
  }
}

}  // namespace meshflow::test
