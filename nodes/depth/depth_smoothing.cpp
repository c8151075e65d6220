#include "nodes/depth/depth_smoothing.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "runtime/simd.h"

namespace meshflow {
namespace {

// The comparators of Batcher's odd-even merge sort on 32 wires (ascending: `lo` gets the
// smaller value) that the 13th smallest value, the median of 25, depends on, with the wires
// 25-31 holding +infinity: comparators whose upper wire is still +infinity change nothing and
// are left out, and so is every comparator after the last one that touches a wire output 12
// depends on.
struct Comparator {
  std::uint8_t lo, hi;
};
struct MedianNetwork {
  std::array<Comparator, 200> comparators{};
  int size = 0;
};

constexpr MedianNetwork median_of_25_network() {
  constexpr int kWires = 32, kValues = 25, kMedian = 12;
  std::array<Comparator, 240> all{};
  int count = 0;
  for (int p = 1; p < kWires; p <<= 1)
    for (int k = p; k >= 1; k >>= 1)
      for (int j = k % p; j + k < kWires; j += 2 * k)
        for (int i = 0; i < k && i + j + k < kWires; ++i)
          if ((i + j) / (2 * p) == (i + j + k) / (2 * p))
            all[static_cast<std::size_t>(count++)] = {static_cast<std::uint8_t>(i + j),
                                                      static_cast<std::uint8_t>(i + j + k)};
  // Forward: drop comparators whose upper wire is known to hold +infinity.
  std::array<bool, kWires> infinite{};
  for (int w = kValues; w < kWires; ++w) infinite[static_cast<std::size_t>(w)] = true;
  std::array<bool, 240> keep{};
  for (int c = 0; c < count; ++c) {
    const Comparator x = all[static_cast<std::size_t>(c)];
    if (infinite[x.hi]) continue;
    keep[static_cast<std::size_t>(c)] = true;
    if (infinite[x.lo]) {  // a swap: +infinity moves up
      infinite[x.lo] = false;
      infinite[x.hi] = true;
    }
  }
  // Backward: keep only what output `kMedian` depends on.
  std::array<bool, kWires> needed{};
  needed[kMedian] = true;
  for (int c = count - 1; c >= 0; --c) {
    const Comparator x = all[static_cast<std::size_t>(c)];
    if (!keep[static_cast<std::size_t>(c)] || !(needed[x.lo] || needed[x.hi])) {
      keep[static_cast<std::size_t>(c)] = false;
      continue;
    }
    needed[x.lo] = needed[x.hi] = true;
  }
  MedianNetwork network;
  for (int c = 0; c < count; ++c)
    if (keep[static_cast<std::size_t>(c)])
      network.comparators[static_cast<std::size_t>(network.size++)] =
          all[static_cast<std::size_t>(c)];
  return network;
}

constexpr MedianNetwork kMedianOf25 = median_of_25_network();

// Medians of the 5 x 5 windows of pixels u0 .. u0 + 7 of row v (2 <= u0, u0 + 9 < cols,
// 2 <= v < rows - 2) when all their 8 x 25 depths are valid; false (nothing written) otherwise.
// Eight pixels at once through the sorting network.
MESHFLOW_AVX2_CLONES bool median5_of_eight(const Image& depth_m, int v, int u0, float* out) {
  using simd::Floats8;
  Floats8 w[32];
  for (int i = 25; i < 32; ++i) w[i] = Floats8{} + INFINITY;
  Floats8 valid = Floats8{} + 1.0f;
  for (int dy = -2; dy <= 2; ++dy) {
    const float* row = depth_m.ptr<float>(v + dy) + u0 - 2;
    for (int dx = 0; dx < 5; ++dx) {
      Floats8 x;
      std::memcpy(&x, row + dx, sizeof x);
      w[(dy + 2) * 5 + dx] = x;
      valid = x > 0.0f ? valid : Floats8{};
    }
  }
  for (int lane = 0; lane < 8; ++lane)
    if (valid[lane] == 0.0f) return false;
  for (int i = 0; i < kMedianOf25.size; ++i) {
    const Comparator c = kMedianOf25.comparators[static_cast<std::size_t>(i)];
    const Floats8 a = w[c.lo], b = w[c.hi];
    w[c.lo] = a < b ? a : b;
    w[c.hi] = a < b ? b : a;
  }
  std::memcpy(out, &w[12], sizeof w[12]);
  return true;
}

// Runs `pixel(v, u, out_row)` for every valid pixel of every row, in parallel over rows, and
// returns the output image (invalid pixels stay 0).
template <class PixelFn>
Image filter_valid_pixels(const Image& depth_m, PixelFn pixel) {
  assert(depth_m.format() == PixelFormat::F32 && "depth must be F32 metres");
  Image out(depth_m.rows(), depth_m.cols(), PixelFormat::F32);
  tbb::parallel_for(0, depth_m.rows(), [&](int v) {
    const float* row = depth_m.ptr<float>(v);
    float* out_row = out.ptr<float>(v);
    for (int u = 0; u < depth_m.cols(); ++u)
      if (row[u] > 0.0f) out_row[u] = pixel(v, u);
  });
  return out;
}

// x = e^x for x <= 0, in the operations of F (float, or simd::Floats8 lane by lane with I =
// simd::Ints8) so that the vector and the scalar path give the same bits: x = n ln 2 + r with
// |r| <= ln 2 / 2, e^r by its Taylor polynomial to r^6 (relative error < 2e-7), 2^n through the
// exponent bits; 0 below e^-80. In place (vectors stay out of calls: runtime/simd.h).
template <class F, class I>
inline void exp_of_nonpositive_in_place(F& x) {
  const F zero{};
  const F clamped = x < -80.0f ? zero - 80.0f : x;                  // zero - 80: a broadcast
  const F n = (clamped * 1.44269504f + 12582912.0f) - 12582912.0f;  // rounded to nearest
  const F r = (clamped - n * 0.693145751953125f) - n * 1.428606765330187e-6f;
  F p = r * (1.0f / 720.0f) + 1.0f / 120.0f;
  p = p * r + 1.0f / 24.0f;
  p = p * r + 1.0f / 6.0f;
  p = p * r + 0.5f;
  p = p * r + 1.0f;
  p = p * r + 1.0f;
  I bits;
  if constexpr (std::is_same_v<F, float>) {
    bits = (static_cast<I>(n) + 127) << 23;
  } else {
    bits = (__builtin_convertvector(n, I) + 127) << 23;
  }
  F two_to_n;
  std::memcpy(&two_to_n, &bits, sizeof two_to_n);
  x = x < -80.0f ? zero : p * two_to_n;
}

float exp_of_nonpositive(float x) {
  exp_of_nonpositive_in_place<float, std::int32_t>(x);
  return x;
}

constexpr int kRadius = 2;
constexpr float kSigmaPixels = 2.0f;
constexpr int kTaps = 2 * kRadius + 1;

constexpr std::size_t tap_index(int dy, int dx) {
  return static_cast<std::size_t>((dy + kRadius) * kTaps + dx + kRadius);
}

// The bilateral filter's weights: spatial per tap of the 5 x 5 square (0 outside the radius-2
// disc), and -1 / (2 sigma_d^2) for the depth term.
struct BilateralKernel {
  std::array<float, kTaps * kTaps> spatial{};
  float range_scale;
  explicit BilateralKernel(float sigma_depth_m)
      : range_scale(-1.0f / (2.0f * sigma_depth_m * sigma_depth_m)) {
    for (int dy = -kRadius; dy <= kRadius; ++dy)
      for (int dx = -kRadius; dx <= kRadius; ++dx) {
        const int r2 = dx * dx + dy * dy;
        spatial[tap_index(dy, dx)] =
            r2 <= kRadius * kRadius
                ? std::exp(-static_cast<float>(r2) / (2.0f * kSigmaPixels * kSigmaPixels))
                : 0.0f;
      }
  }
};

// The bilateral filter of pixels u0 .. u0 + 7 of row v, all taps inside the image
// (kRadius <= v < rows - kRadius, kRadius <= u0, u0 + 8 + kRadius <= cols): the scalar
// definition's operations in the same order, eight pixels at once; invalid taps weigh 0,
// invalid centres stay 0.
MESHFLOW_AVX2_CLONES void bilateral_of_eight(const Image& depth_m, int v, int u0,
                                             const BilateralKernel& kernel, float* out) {
  using simd::Floats8;
  using simd::Ints8;
  Floats8 centre, weighted{}, total{};
  std::memcpy(&centre, depth_m.ptr<float>(v) + u0, sizeof centre);
  for (int dy = -kRadius; dy <= kRadius; ++dy)
    for (int dx = -kRadius; dx <= kRadius; ++dx) {
      Floats8 d;
      std::memcpy(&d, depth_m.ptr<float>(v + dy) + u0 + dx, sizeof d);
      Floats8 w = kernel.range_scale * ((d - centre) * (d - centre));
      exp_of_nonpositive_in_place<Floats8, Ints8>(w);
      w = kernel.spatial[tap_index(dy, dx)] * w;
      const Floats8 valid_w = d > 0.0f ? w : Floats8{};
      weighted += valid_w * d;
      total += valid_w;
    }
  const Floats8 result = centre > 0.0f ? weighted / total : Floats8{};
  std::memcpy(out, &result, sizeof result);
}

}  // namespace

Image median_filter_depth(const Image& depth_m, int k) {
  assert((k == 3 || k == 5) && "median kernel must be 3 or 5");
  assert(depth_m.format() == PixelFormat::F32 && "depth must be F32 metres");
  const int r = k / 2, rows = depth_m.rows(), cols = depth_m.cols();
  const auto window_median = [&](int v, int u) {
    std::array<float, 25> window;
    int n = 0;
    for (int y = std::max(v - r, 0); y <= std::min(v + r, rows - 1); ++y) {
      const float* row = depth_m.ptr<float>(y);
      for (int x = std::max(u - r, 0); x <= std::min(u + r, cols - 1); ++x)
        if (row[x] > 0.0f) window[static_cast<std::size_t>(n++)] = row[x];
    }
    // n >= 1: the pixel itself is valid.
    std::nth_element(window.begin(), window.begin() + n / 2, window.begin() + n);
    return window[static_cast<std::size_t>(n / 2)];
  };
  Image out(rows, cols, PixelFormat::F32);
  tbb::parallel_for(0, rows, [&](int v) {
    const float* row = depth_m.ptr<float>(v);
    float* out_row = out.ptr<float>(v);
    const auto scalar = [&](int u) {
      if (row[u] > 0.0f) out_row[u] = window_median(v, u);
    };
    int u = 0;
    if (k == 5 && v >= 2 && v + 2 < rows) {
      // Inside the image, eight fully valid windows at a time (most of a depth image).
      for (; u < 2 && u < cols; ++u) scalar(u);
      for (; u + 10 <= cols; u += 8)
        if (!median5_of_eight(depth_m, v, u, out_row + u))
          for (int x = u; x < u + 8; ++x) scalar(x);
    }
    for (; u < cols; ++u) scalar(u);
  });
  return out;
}

Image bilateral_filter_depth(const Image& depth_m, float sigma_depth_m) {
  assert(sigma_depth_m > 0.0f);
  const BilateralKernel kernel(sigma_depth_m);
  const int rows = depth_m.rows(), cols = depth_m.cols();
  // Pixel (v, u) by the definition; taps outside the image are left out.
  const auto scalar = [&](int v, int u) {
    const float centre = depth_m.ptr<float>(v)[u];
    float weighted = 0.0f, total = 0.0f;
    for (int dy = -kRadius; dy <= kRadius; ++dy) {
      if (v + dy < 0 || v + dy >= rows) continue;
      const float* row = depth_m.ptr<float>(v + dy);
      for (int dx = -kRadius; dx <= kRadius; ++dx) {
        if (u + dx < 0 || u + dx >= cols) continue;
        const float d = row[u + dx];
        if (!(d > 0.0f)) continue;
        const float w = kernel.spatial[tap_index(dy, dx)] *
                        exp_of_nonpositive(kernel.range_scale * ((d - centre) * (d - centre)));
        weighted += w * d;
        total += w;
      }
    }
    return weighted / total;  // total > 0: the centre's own weight is 1
  };
  Image out(rows, cols, PixelFormat::F32);
  tbb::parallel_for(0, rows, [&](int v) {
    const float* row = depth_m.ptr<float>(v);
    float* out_row = out.ptr<float>(v);
    int u = 0;
    if (v >= kRadius && v + kRadius < rows) {
      for (; u < kRadius && u < cols; ++u)
        if (row[u] > 0.0f) out_row[u] = scalar(v, u);
      for (; u + 8 + kRadius <= cols; u += 8)
        bilateral_of_eight(depth_m, v, u, kernel, out_row + u);
    }
    for (; u < cols; ++u)
      if (row[u] > 0.0f) out_row[u] = scalar(v, u);
  });
  return out;
}

}  // namespace meshflow
