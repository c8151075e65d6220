#include "nodes/decimate/collapse_fan.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>

#include "runtime/simd.h"

namespace meshflow {
namespace {

constexpr std::size_t kBlock = CollapseFan::kBlock;
constexpr std::size_t kRows = CollapseFan::kRows;
constexpr std::size_t kEndRows = CollapseFan::kEndRows;

// A block's eight lanes as one value (runtime/simd.h).
using simd::Floats8;
using simd::Ints8;

#define MESHFLOW_INLINE inline __attribute__((always_inline))  // also at -O0: no vector ABI

template <typename V, typename T>
MESHFLOW_INLINE void load8(V& lanes, const T* from) {
  std::memcpy(&lanes, from, sizeof lanes);
}
// Consecutive rows of a block, from row `first` on, one into each of `rows`.
template <typename... V>
MESHFLOW_INLINE void load_rows(const float* block, CollapseFan::Row first, V&... rows) {
  std::size_t row = first;
  (load8(rows, block + (row++) * kBlock), ...);
}
template <typename V, typename T>
MESHFLOW_INLINE void store8(T* to, const V& lanes) {
  std::memcpy(to, &lanes, sizeof lanes);
}
// The OR / the sum of the eight lanes (three shuffles each, no extractions).
MESHFLOW_INLINE std::int32_t lane_or(const Ints8& lanes) {
  Ints8 x = lanes;
  x |= __builtin_shufflevector(x, x, 4, 5, 6, 7, 0, 1, 2, 3);
  x |= __builtin_shufflevector(x, x, 2, 3, 0, 1, 6, 7, 4, 5);
  x |= __builtin_shufflevector(x, x, 1, 0, 3, 2, 5, 4, 7, 6);
  return x[0];
}
MESHFLOW_INLINE std::int32_t lane_sum(const Ints8& lanes) {
  Ints8 x = lanes;
  x += __builtin_shufflevector(x, x, 4, 5, 6, 7, 0, 1, 2, 3);
  x += __builtin_shufflevector(x, x, 2, 3, 0, 1, 6, 7, 4, 5);
  x += __builtin_shufflevector(x, x, 1, 0, 3, 2, 5, 4, 7, 6);
  return x[0];
}

// Branch-free over every lane (no early exit: a fan has a handful of faces, and a block of them
// costs what one costs). Per face (u, a, b) without v, with va = a - v, vb = b - v and the edge
// e = b - a that stays:
// - needle: an inner angle of (v, a, b) below the minimum, cos > min_angle_cos, compared
//   squared (no trigonometry);
// - turned: the new area vector va x vb makes more than the largest turn with the old one n,
//   i.e. not (n . m >= cos |n| |m|), compared squared (no square roots), or the new face is
//   degenerate: has_area(v, a, b) of runtime/triangle_mesh.cpp, its areas at a and b implied.
MESHFLOW_AVX2_CLONES FanVerdict check_blocks(const float* lanes, const std::uint32_t* ends,
                                             std::size_t blocks, std::uint32_t v, float vx,
                                             float vy, float vz, float max_turn_cos,
                                             float min_angle_cos2) {
  using R = CollapseFan::Row;
  constexpr float kFlattest = 1e-6f;  // as has_area()
  const float turn_cos2 = max_turn_cos * max_turn_cos, flattest2 = kFlattest * kFlattest;
  const auto target = static_cast<std::int32_t>(v);
  Ints8 flags{}, shared{};  // needle in bit 0, turned in bit 1; -1 per face with v
  // The turn test differs for a limit below 90 degrees (acute) and above (obtuse): compiled
  // for each (`acute` a std::bool_constant), so that neither carries the other's lanes.
  const auto check_block = [&](const float* block, const std::uint32_t* block_ends, auto acute)
      __attribute__((always_inline)) {
    Floats8 ax, ay, az, bx, by, bz, ex, ey, ez, le, nx, ny, nz, n2;
    load_rows(block, R::kAx, ax, ay, az, bx, by, bz);
    ax -= vx;
    ay -= vy;
    az -= vz;
    bx -= vx;
    by -= vy;
    bz -= vz;
    load_rows(block, R::kEdgeX, ex, ey, ez, le);
    const Floats8 la = ax * ax + ay * ay + az * az, lb = bx * bx + by * by + bz * bz;
    const Floats8 at_v = ax * bx + ay * by + az * bz;     // cos at v  ~ va . vb
    const Floats8 at_a = -(ax * ex + ay * ey + az * ez);  // cos at a  ~ -va . e
    const Floats8 at_b = bx * ex + by * ey + bz * ez;     // cos at b  ~ vb . e
    const Ints8 is_needle = ((at_v > 0.0f) & (at_v * at_v > min_angle_cos2 * la * lb)) |
                            ((at_a > 0.0f) & (at_a * at_a > min_angle_cos2 * la * le)) |
                            ((at_b > 0.0f) & (at_b * at_b > min_angle_cos2 * lb * le));
    // m = va x vb. has_area() also asks the areas at a and b (e x va, vb x e) to be positive:
    // the flatness bound implies it, as computed they differ from |m| by at most ~10 float
    // epsilons (6e-7) x longest, below the bound's 1e-6 x longest.
    const Floats8 mx = ay * bz - az * by, my = az * bx - ax * bz, mz = ax * by - ay * bx;
    const Floats8 m2 = mx * mx + my * my + mz * mz;
    const Floats8 la_le = la > le ? la : le;
    const Floats8 longest = la_le > lb ? la_le : lb;
    const Ints8 has_area = (m2 > 0.0f) & (m2 >= flattest2 * longest * longest);
    load_rows(block, R::kNx, nx, ny, nz, n2);
    const Floats8 nm = nx * mx + ny * my + nz * mz;
    const Floats8 bound = turn_cos2 * m2 * n2;
    Ints8 turn_ok;
    if constexpr (decltype(acute)::value)
      turn_ok = (nm >= 0.0f) & (nm * nm >= bound);
    else
      turn_ok = (nm >= 0.0f) | (nm * nm <= bound);
    Ints8 end_a, end_b, active;
    load8(end_a, block_ends + CollapseFan::kA * kBlock);
    load8(end_b, block_ends + CollapseFan::kB * kBlock);
    load8(active, block_ends + CollapseFan::kActive * kBlock);
    active = active != 0;
    const Ints8 has_v = (end_a == target) | (end_b == target);
    shared += active & has_v;
    flags |= active & ~has_v & ((is_needle & 1) | (~(turn_ok & has_area) & 2));
  };
  const auto all_blocks = [&](auto acute) __attribute__((always_inline)) {
    // Most fans are one block: that case without a loop (no constants spilled across
    // iterations).
    if (blocks == 1)
      check_block(lanes, ends, acute);
    else
      for (std::size_t j = 0; j < blocks; ++j)
        check_block(lanes + j * kRows * kBlock, ends + j * kEndRows * kBlock, acute);
  };
  if (max_turn_cos >= 0.0f)
    all_blocks(std::true_type{});
  else
    all_blocks(std::false_type{});
  const std::int32_t any = lane_or(flags);
  return FanVerdict{(any & 1) != 0, (any & 2) != 0, static_cast<unsigned>(-lane_sum(shared))};
}

// Per lane, from the positions a and b: the edge e = b - a and its squared length, and the area
// vector n = (a - u) x (b - u) and its squared length (the same arithmetic as Eigen's).
MESHFLOW_AVX2_CLONES void derive_blocks(float* lanes, std::size_t blocks, float ux, float uy,
                                        float uz) {
  using R = CollapseFan::Row;
  for (std::size_t j = 0; j < blocks; ++j, lanes += kRows * kBlock) {
    Floats8 ax, ay, az, bx, by, bz;
    load_rows(lanes, R::kAx, ax, ay, az, bx, by, bz);
    const Floats8 ex = bx - ax, ey = by - ay, ez = bz - az;
    const Floats8 px = ax - ux, py = ay - uy, pz = az - uz;
    const Floats8 qx = bx - ux, qy = by - uy, qz = bz - uz;
    const Floats8 nx = py * qz - pz * qy, ny = pz * qx - px * qz, nz = px * qy - py * qx;
    store8(lanes + R::kEdgeX * kBlock, ex);
    store8(lanes + R::kEdgeY * kBlock, ey);
    store8(lanes + R::kEdgeZ * kBlock, ez);
    store8(lanes + R::kEdge2 * kBlock, Floats8(ex * ex + ey * ey + ez * ez));
    store8(lanes + R::kNx * kBlock, nx);
    store8(lanes + R::kNy * kBlock, ny);
    store8(lanes + R::kNz * kBlock, nz);
    store8(lanes + R::kN2 * kBlock, Floats8(nx * nx + ny * ny + nz * nz));
  }
}

}  // namespace

CollapseFan::CollapseFan(float max_turn_cos, float min_angle_cos_squared)
    : max_turn_cos_(max_turn_cos), min_angle_cos2_(min_angle_cos_squared) {}

void CollapseFan::reset(std::size_t faces, const Eigen::Vector3f& pu) {
  pu_ = pu;
  faces_ = faces;
  blocks_ = (faces + kBlock - 1) / kBlock;
  // The arrays only grow: a padding lane keeps whatever finite values an earlier fan left
  // there (or the zeros of the growth); being inactive, it counts in no verdict.
  if (lanes_.size() < blocks_ * kRows * kBlock) {
    lanes_.resize(blocks_ * kRows * kBlock);
    ends_.resize(blocks_ * kEndRows * kBlock);
  }
}

void CollapseFan::finish(std::size_t count) {
  // The active row of a block with `n` faces: n ones, then zeros.
  static constexpr std::uint32_t kActiveLanes[kBlock + 1][kBlock] = {
      {0, 0, 0, 0, 0, 0, 0, 0}, {1, 0, 0, 0, 0, 0, 0, 0}, {1, 1, 0, 0, 0, 0, 0, 0},
      {1, 1, 1, 0, 0, 0, 0, 0}, {1, 1, 1, 1, 0, 0, 0, 0}, {1, 1, 1, 1, 1, 0, 0, 0},
      {1, 1, 1, 1, 1, 1, 0, 0}, {1, 1, 1, 1, 1, 1, 1, 0}, {1, 1, 1, 1, 1, 1, 1, 1}};
  faces_ = std::min(count, faces_);
  blocks_ = (faces_ + kBlock - 1) / kBlock;
  for (std::size_t j = 0; j < blocks_; ++j) {
    const std::size_t active = std::min(kBlock, faces_ - j * kBlock);
    std::memcpy(&ends_[(j * kEndRows + kActive) * kBlock], kActiveLanes[active],
                sizeof kActiveLanes[active]);
  }
  derive_blocks(lanes_.data(), blocks_, pu_.x(), pu_.y(), pu_.z());
}

FanVerdict CollapseFan::check(std::uint32_t v, const Eigen::Vector3f& pv) const {
  return check_blocks(lanes_.data(), ends_.data(), blocks_, v, pv.x(), pv.y(), pv.z(),
                      max_turn_cos_, min_angle_cos2_);
}

}  // namespace meshflow

#undef MESHFLOW_INLINE  // (unity builds: not into the next file)
