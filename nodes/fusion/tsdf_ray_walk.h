#pragma once
// The voxel traversal of the along-ray integrator (tsdf_ray_integration.cpp): which voxels a ray
// segment crosses. Internal to nodes/fusion; always inlined, as it runs once per ray in the
// integrator's inner loop and takes the instruction set of the function calling it
// (MESHFLOW_AVX2_CLONES). Points are 4-lane vectors
// (x, y, z, unused) so that the three axes' products, quotients and floors are one instruction
// each; every lane sees the IEEE operations the scalar code would (no FMA), so results do not
// depend on the vector width.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>

#include "nodes/fusion/tsdf_map.h"

namespace meshflow {

namespace ray_walk {

using Floats4 = float __attribute__((vector_size(16)));
using Ints4 = std::int32_t __attribute__((vector_size(16)));

/// The four floats at `v`.
inline Floats4 load4(const float* v) {
  Floats4 out;
  std::memcpy(&out, v, sizeof out);
  return out;
}

/// floor_to_int() of each lane: floor, saturating at +-2^30 (NaN gives -2^30).
inline Ints4 floor4(const Floats4& x) {
  constexpr float kLimit = 1073741824.0f;  // 2^30
  const Floats4 low = Floats4{} - kLimit, high = Floats4{} + kLimit;
  Floats4 c = x >= low ? x : low;  // NaN fails: low
  c = c <= high ? c : high;
  const Ints4 i = __builtin_convertvector(c, Ints4);     // rounds towards zero
  return i + (c < __builtin_convertvector(i, Floats4));  // a true lane is -1
}

}  // namespace ray_walk

/// Calls visit(cell) for every voxel whose cell (the unit cube centred on its sample point) the
/// segment from -> to (voxel units, lanes 0..2) crosses, in order (Amanatides & Woo's
/// traversal); `cell` holds the voxel's (x, y, z, 0). Each step crosses the boundary the segment
/// meets first, the lowest axis on a tie; the walk stops after the cells a straight line between
/// the end cells needs (rounding can miss the last cell by one). Branch-free steps (the axis
/// order is data, not control flow). O(cells).
template <class Visit>
[[gnu::always_inline]] inline void walk_voxels(const ray_walk::Floats4& from,
                                               const ray_walk::Floats4& to, Visit&& visit) {
  using ray_walk::Floats4;
  using ray_walk::Ints4;
  const Floats4 a = from + 0.5f, b = to + 0.5f;  // cells [i, i + 1)
  Ints4 cell = ray_walk::floor4(a);
  const Ints4 gap = ray_walk::floor4(b) - cell;
  const int steps = std::abs(gap[0]) + std::abs(gap[1]) + std::abs(gap[2]);
  const Floats4 d = b - a;
  const Ints4 up = d > 0.0f, down = d < 0.0f;  // -1 where true
  const Ints4 moving = (up | down) & Ints4{-1, -1, -1, 0};
  const Ints4 step = (down - up) & moving;
  // The segment parameter of the next boundary per axis (never on a still axis, which keeps it
  // as it adds 0), and per cell.
  const Floats4 boundary = __builtin_convertvector(cell - up, Floats4);  // cell + 1 going up
  Floats4 next = moving ? (boundary - a) / d : Floats4{} + std::numeric_limits<float>::infinity();
  const Floats4 delta = moving ? __builtin_convertvector(step, Floats4) / d : Floats4{};
  for (int s = 0;; ++s) {
    visit(cell);
    if (s == steps) break;
    // Axis i goes first when its boundary comes before every lower axis' and no later than
    // every higher axis': x <= y, z; y < x, y <= z; z < x, y. That is, the lowest axis whose
    // boundary is the nearest (next is never NaN: 0 <= next, delta <= +inf): every lane 0..2 of
    // `nearest` holds the minimum, and a lane is taken where it equals it and no lower lane does.
    const Floats4 yzx = __builtin_shufflevector(next, next, 1, 2, 0, 3);
    const Floats4 zxy = __builtin_shufflevector(next, next, 2, 0, 1, 3);
    const Floats4 nearer = yzx < next ? yzx : next;
    const Floats4 nearest = zxy < nearer ? zxy : nearer;
    const Ints4 at_nearest = next == nearest;
    const Ints4 zero{};
    const Ints4 lower = __builtin_shufflevector(at_nearest, zero, 4, 0, 1, 4) |
                        __builtin_shufflevector(at_nearest, zero, 4, 4, 0, 4);
    const Ints4 take = at_nearest & ~lower;
    cell += step & take;
    next += reinterpret_cast<Floats4>(reinterpret_cast<Ints4>(delta) & take);  // + 0 elsewhere
  }
}

}  // namespace meshflow
