#pragma once
// The `extract` stage's entry point: one call for every extraction method.

#include <cstdint>
#include <string>
#include <vector>

#include "nodes/extract/marching_cubes.h"
#include "nodes/search/spatial_index.h"
#include "runtime/point_cloud.h"

namespace meshflow {

/// Runs config.method over `grid` and `field`. `cloud` and `index` (over cloud.positions) are
/// the data the field came from; planar and extended marching cubes need them (emc also the
/// normals) and throw meshflow::Error
/// when `index` is null (depth-image frames build none). `feature_vertices` (optional)
/// receives one byte per vertex, 1 for extended marching cubes' feature vertices (all 0 for
/// the other methods). Parallel and deterministic.
TriangleMesh extract_surface(const SparseGrid& grid, const DistanceField& field,
                             const PointCloud& cloud, const SpatialIndex* index,
                             const ExtractConfig& config,
                             std::vector<std::uint8_t>* feature_vertices = nullptr);

/// "mc", "mt", "emc", "pmc" -> method; throws meshflow::Error naming the accepted names otherwise.
ExtractMethod parse_extract_method(const std::string& name);
const char* extract_method_name(ExtractMethod method);

}  // namespace meshflow
