#pragma once
// Helpers shared by the tests: data locations, temporary files, mesh error statistics.

#include <cstdint>
#include <functional>
#include <string>

#include "runtime/depth_frame.h"
#include "runtime/image.h"
#include "runtime/point_cloud.h"
#include "runtime/threads.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::test {

/// $MESHFLOW_DATA, or ../shared/data beside the source tree. Tests that need it skip when absent.
std::string data_dir();
bool has_data(const std::string& relative);
std::string data_path(const std::string& relative);

/// Path of a fixture under tests/data.
std::string fixture(const std::string& relative);

/// A fresh empty directory for one test; removed at process exit is not guaranteed.
std::string temp_dir();

/// Writes `content` to `path` (binary).
void write_file(const std::string& path, const std::string& content);
/// The whole file at `path` (binary); empty when it cannot be read.
std::string read_file(const std::string& path);
/// `text` (not empty) with `count` bytes set to pseudo-random values at pseudo-random places,
/// drawn from a linear congruential generator advanced in `state`: corruption for the readers'
/// fuzz-style tests, the same for the same state.
std::string flip_bytes(std::string text, int count, std::uint32_t& state);
/// `text` with 1-4 random mutations of a mutation fuzzer (truncation, bit flip, random byte,
/// inserted run, erased run, a number replaced by an extreme one such as nan, 1e39 or
/// 4294967295, a slice repeated), drawn from the generator of flip_bytes() in `state`.
std::string mutate(std::string text, std::uint32_t& state);
/// A TSDF map file's bytes (at least 8) with the trailing FNV-1a 64 checksum recomputed over the
/// rest, so a changed map still passes the checksum and its fields reach the reader.
std::string resealed_tsdf_map(std::string bytes);

/// f() run under a limit of `threads` worker threads (for 1-vs-N determinism tests).
template <typename F>
auto with_threads(int threads, F f) {
  ThreadLimit limit(threads);
  return f();
}

/// The tetrahedron (0,0,0), (1,0,0), (0,1,0), (0,0,1): closed, faces outward and
/// counter-clockwise.
TriangleMesh tetrahedron();

/// An n x n vertex grid in the plane z = 0 with unit spacing (vertex j * n + i at (i, j, 0)),
/// two triangles per cell, counter-clockwise seen from +z.
TriangleMesh grid_mesh(std::uint32_t n);

/// grid_mesh(n) with the junk a clean-up meets, drawn from `seed` (deterministic): copies of
/// triangles (corners rotated or reversed), triangles repeating a corner, and triangles joining
/// random vertices (edges with three or more faces, vertices joining several fans).
TriangleMesh messy_mesh(std::uint32_t n, std::uint32_t seed);

/// What a reader that welds vertices on load (joins vertices at the same position, as Open3D's
/// OBJ and glTF readers and trimesh do) makes of a mesh's topology.
struct WeldedTopology {
  std::size_t coincident_pairs = 0;       ///< pairs of distinct vertices at the same position
  std::size_t non_manifold_vertices = 0;  ///< welded vertices whose triangles form several fans
  std::size_t non_manifold_edges = 0;     ///< welded edges with three or more triangles
};
/// Welds `mesh` by exact position and counts; brute force per vertex (tests only).
WeldedTopology welded_topology(const TriangleMesh& mesh);

/// `frame` as a Kinect driver delivers it: the organized cloud of its metric depth
/// (back_project) in the camera frame, whatever its pose; NaN where a pixel has no point.
PointCloud camera_frame_cloud(const DepthFrame& frame);

/// The largest absolute difference between corresponding channel values of two images of the
/// same size and format (0 = identical); infinity when size or format differ.
double max_abs_difference(const Image& a, const Image& b);

/// The name of synthetic::closed_test_objects()[index] as a test name ("l_shape").
std::string closed_object_test_name(int index);

struct ErrorStats {
  double mean = 0.0, max = 0.0;
};
/// Distance statistics of every mesh vertex under `distance` (e.g. to an analytic surface).
ErrorStats vertex_errors(const TriangleMesh& mesh,
                         const std::function<float(const Eigen::Vector3f&)>& distance);

}  // namespace meshflow::test

#define MESHFLOW_REQUIRE_DATA(relative)                                                \
  do {                                                                                 \
    if (!::meshflow::test::has_data(relative))                                         \
      GTEST_SKIP() << "real data not found: " << ::meshflow::test::data_path(relative) \
                   << " (set MESHFLOW_DATA to the shared data directory)";             \
  } while (0)
