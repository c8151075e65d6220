#pragma once
// Planar regions of a mesh (the reconstruction thesis's optimisation stage): region growing
// over neighbouring faces with similar normals, a least-squares plane per region, vertices
// projected onto their region's plane, and regions classified by their normal.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "runtime/half_edge_mesh.h"
#include "runtime/planar_segmentation.h"

namespace meshflow {

struct PlanarRegionConfig {
  /// A face joins a region when its unit normal's dot product with the region's seed normal
  /// exceeds this (thesis default 0.85, about 32 degrees).
  float normal_threshold = 0.85f;
  /// Smaller regions are dropped (their faces stay unassigned or join later regions). 50 keeps
  /// the demo room at 5 cm to 48 regions covering 97 % of its faces (10: 146 fragments).
  std::size_t min_region_faces = 50;
  Eigen::Vector3f up = Eigen::Vector3f::UnitZ();  ///< world up, for the classification
  /// project_onto_planes leaves vertices farther than this (metres) from their plane where
  /// they are: clutter that joined a region within the normal threshold is not flattened.
  /// 0: no limit (the thesis).
  float max_projection = 0.0f;
  /// A grown region is planar only as far as its fitted plane explains it: it shrinks to its
  /// largest connected part of faces whose corners lie within the tolerance of the plane,
  /// refitted (up to three rounds), and is dropped when that part is smaller than
  /// min_region_faces or its 95th-percentile deviation still exceeds the tolerance. A curved
  /// surface (a cylinder, a fillet, a sphere) grows regions within the normal threshold too,
  /// and flattening them would cut chords through it; a cluttered wall keeps its wall. The
  /// tolerance is `max_deviation` (metres), or 3 x the mesh's roughness inside the regions where
  /// that is larger (a noisy scan's walls are flat only to within its noise; curvature does not
  /// count as roughness). 0: no check (the thesis). The reconstruction pipeline sets it from the
  /// voxel (ReconstructionConfig::plane_tolerance_voxels). A mesh far smoother than that (an
  /// exact extraction) is held to a tighter tolerance: see grow_planar_regions.
  float max_deviation = 0.0f;
  /// When > 0 (with max_deviation > 0), the tolerance the regions are held to, instead of one
  /// from this mesh's roughness: the planes step's, carried to the retriangulate or sharpen step
  /// after it (the flattened mesh's roughness is not the surface's). Metres.
  float fixed_tolerance = 0.0f;
};

/// Grows regions from seeds in face order (breadth-first across edges to faces within the
/// normal threshold of the seed), keeps those with at least min_region_faces faces, fits each a
/// plane through its vertices (least squares: the centroid and the smallest principal axis,
/// oriented like the faces), shrinks it to the part the plane explains or drops it
/// (max_deviation; faces shed belong to no region), and classifies the rest: floor / ceiling
/// when the normal is within about 25 degrees of up / down, wall when within about 12 degrees
/// of horizontal. With max_deviation, a mesh far smoother than it (roughness x 100 below it: an
/// exact extraction) is held to a tighter tolerance, 100 x its roughness and at least 1/1000 of
/// max_deviation (the segmentation's `tolerance`): regions shrink first within max_deviation, then
/// within that, and their planes are trimmed least squares (vertices within that tolerance or 3
/// robust deviations), so an extraction's stray vertices neither tilt an exact plane nor let a
/// cylinder pass for facets. Serial growth, plane fits parallel per region; deterministic.
/// O(F log F).
PlanarSegmentation grow_planar_regions(const HalfEdgeMesh& mesh,
                                       const PlanarRegionConfig& config = {});

/// Moves every vertex whose faces all lie in one region onto that region's plane (orthogonal
/// projection) when it lies within max_projection of it (0: any distance); vertices shared by
/// regions or touching unassigned faces stay. Returns how many moved. Parallel over vertices;
/// O(V + F).
std::size_t project_onto_planes(HalfEdgeMesh& mesh, const PlanarSegmentation& segmentation,
                                float max_projection = 0.0f);

}  // namespace meshflow
