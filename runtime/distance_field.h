#pragma once
// The signed distance samples the distance stage computes at a sparse grid's corners and the
// extract stage turns into triangles.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace meshflow {

/// Signed distances (metres) per grid corner: positive on the side the normals point to.
struct DistanceField {
  std::vector<float> values;        ///< one per grid corner
  std::vector<std::uint8_t> valid;  ///< 1 where values[i] is meaningful
  std::size_t disagreeing = 0;  ///< corners invalid by the distance stage's max_disagreement_voxels
  std::size_t extrapolated = 0;  ///< corners invalid by max_extrapolation_voxels
  /// Corners with a valid value.
  std::size_t valid_count() const;
};

}  // namespace meshflow
