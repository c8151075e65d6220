#include "runtime/distance_field.h"

#include <algorithm>

namespace meshflow {

std::size_t DistanceField::valid_count() const {
  return static_cast<std::size_t>(std::count(valid.begin(), valid.end(), std::uint8_t{1}));
}

}  // namespace meshflow
