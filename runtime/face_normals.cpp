#include "runtime/face_normals.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdint>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define MESHFLOW_GATHERED_NORMALS 1
#else
#define MESHFLOW_GATHERED_NORMALS 0
#endif

namespace meshflow {
namespace {

// One face the plain way: face_normal() itself, and its fourth lane.
Eigen::Vector4f counted_normal(const TriangleMesh& mesh, const Triangle& t) {
  const Eigen::Vector3f n = face_normal(mesh, t);
  return {n.x(), n.y(), n.z(), n.squaredNorm() > 0.0f ? 1.0f : 0.0f};
}

#if MESHFLOW_GATHERED_NORMALS
// Vertex numbers times three (a position's first float) stay in a signed 32-bit gather index.
constexpr std::size_t kMostGatheredVertices = 0x2AAAAAAA;

#define MESHFLOW_AVX2_INLINE __attribute__((target("avx2"), always_inline)) inline

// a b - c d, each product rounded, as Eigen's cross product computes a coordinate.
MESHFLOW_AVX2_INLINE __m256 products_difference(__m256 a, __m256 b, __m256 c, __m256 d) {
  return _mm256_sub_ps(_mm256_mul_ps(a, b), _mm256_mul_ps(c, d));
}

// x^2 + (y^2 + z^2): Eigen's sum of a 3-vector's squares, in its order.
MESHFLOW_AVX2_INLINE __m256 squared_norm(__m256 x, __m256 y, __m256 z) {
  return _mm256_add_ps(_mm256_mul_ps(x, x),
                       _mm256_add_ps(_mm256_mul_ps(y, y), _mm256_mul_ps(z, z)));
}

// counted_face_normals() of the first faces of `corners` (three per face, `count` faces), eight
// at a time with AVX2 gathers: per lane face_normal()'s float operations in its order (edge
// vectors from the first corner, Eigen's cross product, x^2 + (y^2 + z^2) as Eigen sums a
// 3-vector's squares, a correctly rounded square root, one division per coordinate; no fused
// multiply-adds), so every bit matches. Writes rows (x, y, z, w) to `out` (4 floats per face).
// Returns the faces done: count rounded down to a multiple of 8.
__attribute__((target("avx2"))) std::size_t gathered_normals(const float* points,
                                                             const std::uint32_t* corners,
                                                             std::size_t count, float* out) {
  const __m256i stride = _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21);
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  std::size_t f = 0;
  for (; f + 8 <= count; f += 8) {
    const auto* face = reinterpret_cast<const int*>(corners + 3 * f);
    __m256 p[3][3];  // p[corner][coordinate] of the eight faces
    for (int j = 0; j < 3; ++j) {
      const __m256i vertex = _mm256_i32gather_epi32(face + j, stride, 4);
      const __m256i first = _mm256_add_epi32(_mm256_slli_epi32(vertex, 1), vertex);
      for (int k = 0; k < 3; ++k) p[j][k] = _mm256_i32gather_ps(points + k, first, 4);
    }
    __m256 u[3], v[3];
    for (int k = 0; k < 3; ++k) {
      u[k] = _mm256_sub_ps(p[1][k], p[0][k]);
      v[k] = _mm256_sub_ps(p[2][k], p[0][k]);
    }
    const __m256 nx = products_difference(u[1], v[2], u[2], v[1]);
    const __m256 ny = products_difference(u[2], v[0], u[0], v[2]);
    const __m256 nz = products_difference(u[0], v[1], u[1], v[0]);
    const __m256 length = _mm256_sqrt_ps(squared_norm(nx, ny, nz));
    const __m256 has_length = _mm256_cmp_ps(length, zero, _CMP_GT_OQ);  // false for NaN
    const __m256 x = _mm256_and_ps(_mm256_div_ps(nx, length), has_length);
    const __m256 y = _mm256_and_ps(_mm256_div_ps(ny, length), has_length);
    const __m256 z = _mm256_and_ps(_mm256_div_ps(nz, length), has_length);
    const __m256 w = _mm256_and_ps(one, _mm256_cmp_ps(squared_norm(x, y, z), zero, _CMP_GT_OQ));
    // Rows (x, y, z, w): lanes l and l + 4 in each 128-bit half, then halves paired.
    const __m256 xy_low = _mm256_unpacklo_ps(x, y), xy_high = _mm256_unpackhi_ps(x, y);
    const __m256 zw_low = _mm256_unpacklo_ps(z, w), zw_high = _mm256_unpackhi_ps(z, w);
    const __m256 r0 = _mm256_shuffle_ps(xy_low, zw_low, 0x44);    // faces 0 | 4
    const __m256 r1 = _mm256_shuffle_ps(xy_low, zw_low, 0xEE);    // 1 | 5
    const __m256 r2 = _mm256_shuffle_ps(xy_high, zw_high, 0x44);  // 2 | 6
    const __m256 r3 = _mm256_shuffle_ps(xy_high, zw_high, 0xEE);  // 3 | 7
    float* rows = out + 4 * f;
    _mm256_storeu_ps(rows, _mm256_permute2f128_ps(r0, r1, 0x20));
    _mm256_storeu_ps(rows + 8, _mm256_permute2f128_ps(r2, r3, 0x20));
    _mm256_storeu_ps(rows + 16, _mm256_permute2f128_ps(r0, r1, 0x31));
    _mm256_storeu_ps(rows + 24, _mm256_permute2f128_ps(r2, r3, 0x31));
  }
  return f;
}

bool cpu_gathers() {
  static const bool avx2 = __builtin_cpu_supports("avx2") != 0;
  return avx2;
}
#endif

}  // namespace

std::vector<Eigen::Vector4f> counted_face_normals(const TriangleMesh& mesh) {
  const std::size_t count = mesh.triangles.size();
  std::vector<Eigen::Vector4f> normals(count);
#if MESHFLOW_GATHERED_NORMALS
  const bool gathers = cpu_gathers() && mesh.vertices.size() <= kMostGatheredVertices;
#endif
  constexpr std::size_t kGrain = 1024;  // faces per task, about
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kGrain), [&](const auto& range) {
    std::size_t t = range.begin();
#if MESHFLOW_GATHERED_NORMALS
    if (gathers)
      t += gathered_normals(reinterpret_cast<const float*>(mesh.vertices.data()),
                            mesh.triangles[t].data(), range.size(), normals[t].data());
#endif
    for (; t < range.end(); ++t) normals[t] = counted_normal(mesh, mesh.triangles[t]);
  });
  return normals;
}

}  // namespace meshflow
