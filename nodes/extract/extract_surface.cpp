#include "nodes/extract/extract_surface.h"

#include <string>

#include "nodes/extract/extended_marching_cubes.h"
#include "nodes/extract/marching_tetrahedra.h"
#include "nodes/extract/planar_marching_cubes.h"
#include "runtime/error.h"

namespace meshflow {
namespace {

TriangleMesh extract_by_method(const SparseGrid& grid, const DistanceField& field,
                               const PointCloud& cloud, const SpatialIndex* index,
                               const ExtractConfig& config,
                               std::vector<std::uint8_t>* feature_vertices) {
  switch (config.method) {
    case ExtractMethod::kMarchingTetrahedra:
      return marching_tetrahedra(grid, field, config);
    case ExtractMethod::kPlanarMarchingCubes:
      if (index == nullptr)
        throw Error("extract", "method pmc", "needs a point index (point-cloud input)");
      return planar_marching_cubes(grid, field, cloud, *index, config);
    case ExtractMethod::kExtendedMarchingCubes: {
      if (index == nullptr)
        throw Error("extract", "method emc", "needs a point index (point-cloud input)");
      ExtendedMcConfig emc;
      emc.flip_edges = !config.defer_feature_flips;
      return extended_marching_cubes(grid, field, cloud, *index, config, emc, feature_vertices);
    }
    case ExtractMethod::kAuto:
    case ExtractMethod::kMarchingCubes:
      break;
  }
  return marching_cubes(grid, field, config);
}

}  // namespace

TriangleMesh extract_surface(const SparseGrid& grid, const DistanceField& field,
                             const PointCloud& cloud, const SpatialIndex* index,
                             const ExtractConfig& config,
                             std::vector<std::uint8_t>* feature_vertices) {
  TriangleMesh mesh = extract_by_method(grid, field, cloud, index, config, feature_vertices);
  if (feature_vertices && feature_vertices->size() != mesh.vertices.size())
    feature_vertices->assign(mesh.vertices.size(), 0);
  return mesh;
}

ExtractMethod parse_extract_method(const std::string& name) {
  if (name == "auto") return ExtractMethod::kAuto;
  if (name == "mc") return ExtractMethod::kMarchingCubes;
  if (name == "mt") return ExtractMethod::kMarchingTetrahedra;
  if (name == "pmc") return ExtractMethod::kPlanarMarchingCubes;
  if (name == "emc") return ExtractMethod::kExtendedMarchingCubes;
  throw Error("extract", "method '" + name + "'", "expected auto, mc, mt, emc or pmc");
}

const char* extract_method_name(ExtractMethod method) {
  switch (method) {
    case ExtractMethod::kMarchingTetrahedra:
      return "mt";
    case ExtractMethod::kPlanarMarchingCubes:
      return "pmc";
    case ExtractMethod::kExtendedMarchingCubes:
      return "emc";
    case ExtractMethod::kAuto:
      return "auto";
    case ExtractMethod::kMarchingCubes:
      break;
  }
  return "mc";
}

}  // namespace meshflow
