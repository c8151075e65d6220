#pragma once
// The planar regions the planes step finds on a mesh, which the sharpen, retriangulate and
// texture steps read: each region's faces, plane and class.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace meshflow {

enum class RegionClass { kFloor, kCeiling, kWall, kOther };
/// "floor", "ceiling", "wall" or "other".
const char* region_class_name(RegionClass c);

struct PlanarRegion {
  std::vector<std::uint32_t> faces;                   ///< ascending
  Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();  ///< unit, the faces' side
  float offset = 0.0f;                                ///< the plane is normal . x = offset (metres)
  RegionClass kind = RegionClass::kOther;
  float deviation = 0.0f;  ///< 95th percentile of the vertices' distances to the plane, metres
};

struct PlanarSegmentation {
  std::vector<std::int32_t> region_of_face;  ///< per face slot; -1 = in no region
  std::vector<PlanarRegion> regions;         ///< by first face
  std::size_t curved = 0;  ///< grown regions dropped because their plane did not explain them
  float tolerance = 0.0f;  ///< the deviation allowed (metres; 0 = no check)
};

}  // namespace meshflow
