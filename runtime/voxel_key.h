#pragma once
// Packed integer cell keys for sparse voxel grids: 19 bits per axis (about +-262k cells, e.g.
// +-2.6 km at 1 cm voxels) in the low 57 bits of a uint64; the top bits stay free for tags.
// Sorting keys orders cells z-major, then y, then x.

#include <Eigen/Core>
#include <cassert>
#include <cmath>
#include <cstdint>

namespace meshflow {

using VoxelKey = std::uint64_t;

constexpr int kKeyBitsPerAxis = 19;
constexpr int kKeyBits = 3 * kKeyBitsPerAxis;                    ///< bits used by a packed key
constexpr std::int32_t kKeyOffset = 1 << (kKeyBitsPerAxis - 1);  ///< index 0 maps to this
constexpr std::int32_t kMaxCellIndex = kKeyOffset - 2;           ///< keeps +1 neighbours packable
constexpr std::uint64_t kKeyAxisMask = (std::uint64_t{1} << kKeyBitsPerAxis) - 1;

/// True when every component of the cell index can be packed, with room for one neighbour.
inline bool cell_index_in_range(const Eigen::Vector3i& c) {
  return (c.array() >= -kMaxCellIndex).all() &&
         (c.array() <= kMaxCellIndex).all();  // no abs(INT_MIN)
}

/// Packs a cell index; precondition: cell_index_in_range(c) (or one step beyond it).
inline VoxelKey pack_key(const Eigen::Vector3i& c) {
  assert((c.array().abs() < kKeyOffset).all());
  return (static_cast<std::uint64_t>(c.z() + kKeyOffset) << (2 * kKeyBitsPerAxis)) |
         (static_cast<std::uint64_t>(c.y() + kKeyOffset) << kKeyBitsPerAxis) |
         static_cast<std::uint64_t>(c.x() + kKeyOffset);
}

inline Eigen::Vector3i unpack_key(VoxelKey k) {
  return {static_cast<std::int32_t>(k & kKeyAxisMask) - kKeyOffset,
          static_cast<std::int32_t>((k >> kKeyBitsPerAxis) & kKeyAxisMask) - kKeyOffset,
          static_cast<std::int32_t>((k >> (2 * kKeyBitsPerAxis)) & kKeyAxisMask) - kKeyOffset};
}

/// floor(x) as an integer, inline (std::floor is a library call on baseline x86-64). Exact for
/// |x| <= 2^30; larger values saturate at +-2^30 and NaN gives -2^30, both outside the key range.
inline std::int32_t floor_to_int(float x) {
  constexpr float kLimit = 1073741824.0f;  // 2^30
  const float c = x >= -kLimit ? (x <= kLimit ? x : kLimit) : -kLimit;
  const auto i = static_cast<std::int32_t>(c);  // rounds towards zero
  return c < static_cast<float>(i) ? i - 1 : i;
}

/// Cell containing p for cells of edge `voxel_size` with a corner at the origin.
inline Eigen::Vector3i cell_of(const Eigen::Vector3f& p, float voxel_size) {
  return {floor_to_int(p.x() / voxel_size), floor_to_int(p.y() / voxel_size),
          floor_to_int(p.z() / voxel_size)};
}

}  // namespace meshflow
