#include "nodes/fusion/tsdf_projective_update.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "nodes/fusion/tsdf_band.h"
#include "runtime/simd.h"

namespace meshflow {

namespace {

using simd::Floats8;
using simd::Ints8;

// Half the difference across both neighbours on d's surface (within `one_surface` x d), the
// difference to the one that is, or 0.
inline float surface_slope(float before, float d, float after, float one_surface) {
  const float limit = one_surface * d;
  const bool b = before > 0.0f && std::abs(before - d) <= limit;
  const bool a = after > 0.0f && std::abs(after - d) <= limit;
  if (a && b) return 0.5f * (after - before);
  if (a) return after - d;
  if (b) return d - before;
  return 0.0f;
}

// |x| as std::abs does it: the sign bit cleared.
#define MESHFLOW_SLOPE_ABS(x) reinterpret_cast<Floats8>(reinterpret_cast<Ints8>(x) & 0x7fffffff)

// surface_slope() lane by lane (the same comparisons and IEEE operations).
#define MESHFLOW_SURFACE_SLOPE8(before, d, after, out)                                 \
  do {                                                                                 \
    const Floats8 limit = one_surface * (d);                                           \
    const Ints8 b = ((before) > 0.0f) & (MESHFLOW_SLOPE_ABS((before) - (d)) <= limit); \
    const Ints8 a = ((after) > 0.0f) & (MESHFLOW_SLOPE_ABS((after) - (d)) <= limit);   \
    (out) = (a & b) ? 0.5f * ((after) - (before))                                      \
                    : (a ? (after) - (d) : (b ? (d) - (before) : Floats8{}));          \
  } while (false)

// depth_slopes() of one row: `here` its pixels (depth, band), `above` / `below` the rows beside
// it (null past the image's edge), `out` its slopes; eight pixels at a time in vectors, each lane
// exactly surface_slope()'s arithmetic.
MESHFLOW_AVX2_CLONES void row_slopes(const float* here, const float* above, const float* below,
                                     std::size_t w, float one_surface, float* out) {
  const auto pixel = [&](std::size_t u) {
    const float d = here[2 * u];
    out[4 * u] = d;
    out[4 * u + 1] = here[2 * u + 1];
    if (!(d > 0.0f)) {
      out[4 * u + 2] = out[4 * u + 3] = 0.0f;
      return;
    }
    out[4 * u + 2] = surface_slope(u > 0 ? here[2 * u - 2] : 0.0f, d,
                                   u + 1 < w ? here[2 * u + 2] : 0.0f, one_surface);
    out[4 * u + 3] =
        surface_slope(above ? above[2 * u] : 0.0f, d, below ? below[2 * u] : 0.0f, one_surface);
  };
  std::size_t u = 0;
  for (; u < std::min<std::size_t>(1, w); ++u) pixel(u);
  for (; u + 9 <= w; u += 8) {  // u - 1 .. u + 8 inside the row
    // Pixels' (depth, band) pairs as two vectors each; the depths are their even lanes.
    const auto pairs = [](const float* at, Floats8& first, Floats8& second) {
      __builtin_memcpy(&first, at, sizeof first);
      __builtin_memcpy(&second, at + 8, sizeof second);
    };
    Floats8 p0, p1, l0, l1, r0, r1, a0{}, a1{}, b0{}, b1{};
    pairs(here + 2 * u, p0, p1);
    pairs(here + 2 * u - 2, l0, l1);
    pairs(here + 2 * u + 2, r0, r1);
    if (above) pairs(above + 2 * u, a0, a1);
    if (below) pairs(below + 2 * u, b0, b1);
#define MESHFLOW_EVEN_LANES(x0, x1) __builtin_shufflevector(x0, x1, 0, 2, 4, 6, 8, 10, 12, 14)
    const Floats8 d = MESHFLOW_EVEN_LANES(p0, p1), left = MESHFLOW_EVEN_LANES(l0, l1),
                  right = MESHFLOW_EVEN_LANES(r0, r1), up = MESHFLOW_EVEN_LANES(a0, a1),
                  down = MESHFLOW_EVEN_LANES(b0, b1);
#undef MESHFLOW_EVEN_LANES
    Floats8 du, dv;
    MESHFLOW_SURFACE_SLOPE8(left, d, right, du);
    MESHFLOW_SURFACE_SLOPE8(up, d, down, dv);
    const Ints8 valid = d > 0.0f;
    du = valid ? du : Floats8{};
    dv = valid ? dv : Floats8{};
    // Records (depth, band, du, dv): the pairs interleaved with the slopes.
    const Floats8 s0 = __builtin_shufflevector(du, dv, 0, 8, 1, 9, 2, 10, 3, 11);
    const Floats8 s1 = __builtin_shufflevector(du, dv, 4, 12, 5, 13, 6, 14, 7, 15);
    const Floats8 records[4] = {__builtin_shufflevector(p0, s0, 0, 1, 8, 9, 2, 3, 10, 11),
                                __builtin_shufflevector(p0, s0, 4, 5, 12, 13, 6, 7, 14, 15),
                                __builtin_shufflevector(p1, s1, 0, 1, 8, 9, 2, 3, 10, 11),
                                __builtin_shufflevector(p1, s1, 4, 5, 12, 13, 6, 7, 14, 15)};
    __builtin_memcpy(out + 4 * u, records, sizeof records);
  }
  for (; u < w; ++u) pixel(u);
}

#undef MESHFLOW_SURFACE_SLOPE8
#undef MESHFLOW_SLOPE_ABS

}  // namespace

void depth_slopes(const std::vector<float>& pixels, int width, int height, float one_surface,
                  std::vector<float>& slopes) {
  const auto w = static_cast<std::size_t>(width);
  slopes.resize(2 * pixels.size());
  tbb::parallel_for(0, height, [&](int v) {
    const std::size_t row = static_cast<std::size_t>(v) * w;
    const float* here = pixels.data() + 2 * row;
    const float* above = v > 0 ? here - 2 * w : nullptr;
    const float* below = v + 1 < height ? here + 2 * w : nullptr;
    row_slopes(here, above, below, w, one_surface, slopes.data() + 4 * row);
  });
}

namespace {

// project_block()'s body, built for AVX2 and for the baseline (the clones must stay in this
// translation unit: GCC keeps them local).
MESHFLOW_AVX2_CLONES void project_voxel_rows(const Eigen::Vector3i& origin,
                                             const BlockUpdate& frame, BlockProjection& out) {
  static_assert(kTsdfBlockSide == 8, "one 8-wide vector per voxel row");
  const PinholeIntrinsics& k = frame.intrinsics;
  const float voxel = frame.config.voxel_size;
  const Eigen::Matrix3f r = frame.T_camera_world.linear();
  const Eigen::Vector3f base = frame.T_camera_world * (origin.cast<float>() * voxel);
  const Eigen::Vector3f step_x = r.col(0) * voxel, step_y = r.col(1) * voxel,
                        step_z = r.col(2) * voxel;
  const simd::Floats8 lanes = {0, 1, 2, 3, 4, 5, 6, 7};
  const simd::Floats8 dx = lanes * step_x.x(), dy = lanes * step_x.y(), dz = lanes * step_x.z();
  for (int z = 0; z < kTsdfBlockSide; ++z)
    for (int y = 0; y < kTsdfBlockSide; ++y) {
      const Eigen::Vector3f row =
          base + step_y * static_cast<float>(y) + step_z * static_cast<float>(z);
      const simd::Floats8 pz = row.z() + dz;
      const simd::Floats8 inv_z = 1.0f / pz;
      const simd::Floats8 uf = k.fx * (row.x() + dx) * inv_z + k.cx;
      const simd::Floats8 vf = k.fy * (row.y() + dy) * inv_z + k.cy;
      const std::size_t i = static_cast<std::size_t>(kTsdfBlockSide * (y + kTsdfBlockSide * z));
      __builtin_memcpy(out.z + i, &pz, sizeof pz);
      __builtin_memcpy(out.u + i, &uf, sizeof uf);
      __builtin_memcpy(out.v + i, &vf, sizeof vf);
    }
}

}  // namespace

void project_block(const Eigen::Vector3i& origin, const BlockUpdate& frame, BlockProjection& out) {
  project_voxel_rows(origin, frame, out);
}

namespace {

using Pairs4 = std::uint64_t __attribute__((vector_size(32)));  // four 8-byte pairs
using Floats4 = float __attribute__((vector_size(16)));         // one 16-byte record

// A voxel record as three 32-bit words: distance, weight, colour (r, g, b and the padding byte).
static_assert(sizeof(TsdfVoxel) == 12 && offsetof(TsdfVoxel, weight) == 4 &&
                  offsetof(TsdfVoxel, color) == 8 && sizeof(Rgb8) == 3,
              "a voxel is three 32-bit words");
static_assert(std::is_trivially_copyable_v<TsdfVoxel>, "voxels are copied as bytes");

// Whether any lane of `mask` is set.
inline bool any_lane(const Ints8& mask) {
  Pairs4 halves = reinterpret_cast<const Pairs4&>(mask);
  return (halves[0] | halves[1] | halves[2] | halves[3]) != 0;
}

// The (first, second) floats of eight 8-byte pairs at `base` + 2 x index[j] (loaded as pairs).
// Inline into the clones only through the macro's caller: no vector crosses a call.
#define MESHFLOW_GATHER_PAIRS(base, index, first, second)                                   \
  do {                                                                                      \
    Pairs4 lo_, hi_;                                                                        \
    for (int j = 0; j < 4; ++j) { /* via scalars: no address of a vector lane (clang) */    \
      std::uint64_t l_, h_;                                                                 \
      __builtin_memcpy(&l_, (base) + 2 * static_cast<std::size_t>((index)[j]), 8);          \
      __builtin_memcpy(&h_, (base) + 2 * static_cast<std::size_t>((index)[j + 4]), 8);      \
      lo_[j] = l_;                                                                          \
      hi_[j] = h_;                                                                          \
    }                                                                                       \
    const Floats8 a_ = reinterpret_cast<Floats8>(lo_), b_ = reinterpret_cast<Floats8>(hi_); \
    (first) = __builtin_shufflevector(a_, b_, 0, 2, 4, 6, 8, 10, 12, 14);                   \
    (second) = __builtin_shufflevector(a_, b_, 1, 3, 5, 7, 9, 11, 13, 15);                  \
  } while (false)

// The four floats of eight 16-byte records at `base` + 4 x index[j] (loaded as records and
// transposed).
#define MESHFLOW_GATHER_RECORDS(base, index, first, second, third, fourth)                       \
  do {                                                                                           \
    Floats4 r_[8];                                                                               \
    for (int j = 0; j < 8; ++j)                                                                  \
      __builtin_memcpy(&r_[j], (base) + 4 * static_cast<std::size_t>((index)[j]), sizeof r_[j]); \
    Floats8 q_[4];                                                                               \
    for (int j = 0; j < 4; ++j)                                                                  \
      q_[j] = __builtin_shufflevector(r_[j], r_[j + 4], 0, 1, 2, 3, 4, 5, 6, 7);                 \
    const Floats8 lo01_ = __builtin_shufflevector(q_[0], q_[1], 0, 8, 1, 9, 4, 12, 5, 13);       \
    const Floats8 hi01_ = __builtin_shufflevector(q_[0], q_[1], 2, 10, 3, 11, 6, 14, 7, 15);     \
    const Floats8 lo23_ = __builtin_shufflevector(q_[2], q_[3], 0, 8, 1, 9, 4, 12, 5, 13);       \
    const Floats8 hi23_ = __builtin_shufflevector(q_[2], q_[3], 2, 10, 3, 11, 6, 14, 7, 15);     \
    (first) = __builtin_shufflevector(lo01_, lo23_, 0, 1, 8, 9, 4, 5, 12, 13);                   \
    (second) = __builtin_shufflevector(lo01_, lo23_, 2, 3, 10, 11, 6, 7, 14, 15);                \
    (third) = __builtin_shufflevector(hi01_, hi23_, 0, 1, 8, 9, 4, 5, 12, 13);                   \
    (fourth) = __builtin_shufflevector(hi01_, hi23_, 2, 3, 10, 11, 6, 7, 14, 15);                \
  } while (false)

// update_block()'s voxel loop, eight voxels (one voxel row) at a time: the tests as lane masks,
// the blend in vectors, each lane exactly the arithmetic of one voxel alone (plain IEEE products,
// sums and quotients in the same order, no FMA contraction), so every CPU and either build gives
// the same floats. A row's eight 12-byte voxels are loaded and stored as three vectors of
// words; each pixel's (depth, band, slope u, slope v) as one 16-byte record (or its (depth,
// band) as one 8-byte pair), its colour as one 4-byte word.
MESHFLOW_AVX2_CLONES std::size_t blend_voxel_rows(TsdfBlock& block, const BlockUpdate& frame,
                                                  const BlockProjection& projection) {
  const auto width = static_cast<std::int32_t>(frame.width);
  const Floats8 max_u = Floats8{} + (static_cast<float>(frame.width) - 0.5f);
  const Floats8 max_v = Floats8{} + (static_cast<float>(frame.height) - 0.5f);
  const float truncation = frame.config.truncation();
  const Floats8 least = Floats8{} + frame.config.behind_voxels * frame.config.voxel_size;
  const float max_weight = frame.config.max_weight;
  const bool inverse_depth = frame.config.weighting == TsdfWeighting::kInverseDepth;
  const std::uint8_t* const colors = frame.color != nullptr ? frame.color->data() : nullptr;
  // A pixel's colour word starts at 3 x pixel, or a byte earlier for the last pixel (its word
  // then ends with the image, shifted down by 8 bits); negative for an image of one pixel.
  const std::int32_t last_word =
      3 * static_cast<std::int32_t>(frame.width) * static_cast<std::int32_t>(frame.height) - 4;
  Ints8 counted{};
  for (std::size_t i = 0; i < kTsdfBlockVoxels; i += 8) {
    Floats8 pz, uf, vf;
    __builtin_memcpy(&pz, projection.z + i, sizeof pz);
    __builtin_memcpy(&uf, projection.u + i, sizeof uf);
    __builtin_memcpy(&vf, projection.v + i, sizeof vf);
    // In front of the camera and inside the image (false for NaN).
    Ints8 valid = (pz > 0.0f) & (uf > -0.5f) & (vf > -0.5f) & (uf < max_u) & (vf < max_v);
    if (!any_lane(valid)) continue;
    // Nearest pixels (0 in lanes left out, whose projections may not convert).
    const Ints8 u = __builtin_convertvector((valid ? uf + 0.5f : Floats8{}), Ints8);
    const Ints8 v = __builtin_convertvector((valid ? vf + 0.5f : Floats8{}), Ints8);
    const Ints8 pixel = v * width + u;
    // Gathered in every lane (lanes left out read pixel 0 and their own voxels: in bounds),
    // without branches.
    Floats8 d, band, slope_u{}, slope_v{};
    if (frame.slopes != nullptr)
      MESHFLOW_GATHER_RECORDS(frame.slopes, pixel, d, band, slope_u, slope_v);
    else
      MESHFLOW_GATHER_PAIRS(frame.pixels, pixel, d, band);  // depth 0 when invalid
    valid &= d > 0.0f;
    // The band observed voxels take: the least band or the noise allowance at this depth.
    const Floats8 noise = frame.noise_band_per_depth2 * d * d;
    const Floats8 held = noise < least ? least : noise;
    if (frame.slopes != nullptr)
      d = d + (slope_u * (uf - __builtin_convertvector(u, Floats8)) +
               slope_v * (vf - __builtin_convertvector(v, Floats8)));
    const Floats8 sdf = d - pz;
    valid &= ~(sdf < -band);  // hidden behind the surface: unknown
    if (!any_lane(valid)) continue;
    // The row's voxels as words: a = voxels 0..2 (and 2/3 of voxel 2), b, c the rest.
    auto* const row = reinterpret_cast<unsigned char*>(block.voxels.data() + i);
    Ints8 a, b, c;
    __builtin_memcpy(&a, row, sizeof a);
    __builtin_memcpy(&b, row + 32, sizeof b);
    __builtin_memcpy(&c, row + 64, sizeof c);
    const Ints8 ab_d = __builtin_shufflevector(a, b, 0, 3, 6, 9, 12, 15, -1, -1);
    const Ints8 ab_w = __builtin_shufflevector(a, b, 1, 4, 7, 10, 13, -1, -1, -1);
    const Ints8 ab_c = __builtin_shufflevector(a, b, 2, 5, 8, 11, 14, -1, -1, -1);
    const Floats8 distance =
        reinterpret_cast<Floats8>(__builtin_shufflevector(ab_d, c, 0, 1, 2, 3, 4, 5, 10, 13));
    const Floats8 weight =
        reinterpret_cast<Floats8>(__builtin_shufflevector(ab_w, c, 0, 1, 2, 3, 4, 8, 11, 14));
    const Ints8 color = __builtin_shufflevector(ab_c, c, 0, 1, 2, 3, 4, 9, 12, 15);
    valid &= ~((weight > 0.0f) & (sdf < -held));  // observed, past the held band: kept
    // (Lanes left out divide by 1, never by 0, and store their voxel's own values.)
    const Floats8 one = Floats8{} + 1.0f;
    const Floats8 w = inverse_depth ? 1.0f / ((valid ? d : one) * (valid ? d : one)) : one;
    const Floats8 total = weight + w;
    const Floats8 inv_total = 1.0f / (valid ? total : one);
    const Floats8 clipped = (truncation < sdf ? Floats8{} + truncation : sdf);
    const Floats8 blended = valid ? (distance * weight + clipped * w) * inv_total : distance;
    const Floats8 capped = valid ? (max_weight < total ? Floats8{} + max_weight : total) : weight;
    Ints8 new_color = color;
    if (colors != nullptr) {
      const Ints8 at = 3 * pixel;
      Ints8 seen;  // the pixel's r, g, b in the low bytes
      if (last_word >= 0) {
        const Ints8 start = at < last_word ? at : Ints8{} + last_word;
        for (int j = 0; j < 8; ++j) {  // via a scalar: no address of a vector lane (clang)
          std::int32_t word;
          __builtin_memcpy(&word, colors + start[j], 4);
          seen[j] = word;
        }
        seen = seen >> ((at - start) << 3);
      } else {  // an image of one pixel: no 4-byte word inside it
        for (int j = 0; j < 8; ++j)
          seen[j] = colors[at[j]] | colors[at[j] + 1] << 8 | colors[at[j] + 2] << 16;
      }
      // Rounded to nearest (the values are >= 0), kept to 8 bits as the byte stores did.
      Ints8 fused = color & static_cast<std::int32_t>(0xff000000);  // the padding byte
      for (int shift = 0; shift < 24; shift += 8) {
        const Floats8 old = __builtin_convertvector((color >> shift) & 0xff, Floats8);
        const Floats8 now = __builtin_convertvector((seen >> shift) & 0xff, Floats8);
        fused |=
            (__builtin_convertvector((old * weight + now * w) * inv_total + 0.5f, Ints8) & 0xff)
            << shift;
      }
      new_color = valid ? fused : color;
    }
    const Ints8 dist_bits = reinterpret_cast<Ints8>(blended);
    const Ints8 weight_bits = reinterpret_cast<Ints8>(capped);
    const Ints8 a_dw = __builtin_shufflevector(dist_bits, weight_bits, 0, 8, -1, 1, 9, -1, 2, 10);
    const Ints8 b_dw = __builtin_shufflevector(dist_bits, weight_bits, -1, 3, 11, -1, 4, 12, -1, 5);
    const Ints8 c_dw =
        __builtin_shufflevector(dist_bits, weight_bits, 13, -1, 6, 14, -1, 7, 15, -1);
    a = __builtin_shufflevector(a_dw, new_color, 0, 1, 8, 3, 4, 9, 6, 7);
    b = __builtin_shufflevector(b_dw, new_color, 10, 1, 2, 11, 4, 5, 12, 7);
    c = __builtin_shufflevector(c_dw, new_color, 0, 13, 2, 3, 14, 5, 6, 15);
    __builtin_memcpy(row, &a, sizeof a);
    __builtin_memcpy(row + 32, &b, sizeof b);
    __builtin_memcpy(row + 64, &c, sizeof c);
    counted += valid & 1;
  }
  std::size_t count = 0;
  for (int j = 0; j < 8; ++j) count += static_cast<std::size_t>(counted[j]);
  return count;
}

#undef MESHFLOW_GATHER_RECORDS
#undef MESHFLOW_GATHER_PAIRS

}  // namespace

std::size_t update_block(TsdfBlock& block, const BlockUpdate& frame) {
  BlockProjection projection;
  project_block(block.coords * kTsdfBlockSide, frame, projection);
  return blend_voxel_rows(block, frame, projection);
}

}  // namespace meshflow
