#include "runtime/planar_segmentation.h"

namespace meshflow {

const char* region_class_name(RegionClass c) {
  switch (c) {
    case RegionClass::kFloor:
      return "floor";
    case RegionClass::kCeiling:
      return "ceiling";
    case RegionClass::kWall:
      return "wall";
    case RegionClass::kOther:
      break;
  }
  return "other";
}

}  // namespace meshflow
