#include "graph/stages.h"

#include <algorithm>
#include <array>
#include <cstdio>
#include <exception>
#include <optional>
#include <string>

#include "graph/chunk_finish.h"
#include "nodes/close/close_surface.h"
#include "nodes/compress/progressive_mesh.h"
#include "nodes/depth/organized_depth.h"
#include "nodes/extract/extract_surface.h"
#include "nodes/extract/planar_marching_cubes.h"
#include "nodes/extract/rim_trim.h"
#include "nodes/extract/vertex_colors.h"
#include "nodes/filter/point_clusters.h"
#include "nodes/filter/spatial_order.h"
#include "nodes/normals/organized_normals.h"
#include "nodes/voxelize/spacing_sample.h"
#include "runtime/error.h"

namespace meshflow {

OptimizeConfig optimize_config_for_voxel(const ReconstructionConfig& c, float voxel_size) {
  OptimizeConfig oc = c.optimize;
  if (oc.planes.max_deviation == 0.0f)
    oc.planes.max_deviation = c.plane_tolerance_voxels * voxel_size;
  if (c.contour_tolerance_voxels > 0.0f)
    oc.retriangulation.contour_tolerance = c.contour_tolerance_voxels * voxel_size;
  // Feature lines shorter than a few voxels are noise: measured in voxels, not in the mesh's
  // own edges, so a coarse mesh given to `meshflow optimize --voxel` keeps its lines. (An
  // extracted mesh's median edge is about one voxel: 1.01 on kurt3d at 5 cm with marching
  // cubes, 1.0 on the closed test objects with extended marching cubes.)
  if (oc.feature_min_length == 0.0f && voxel_size > 0.0f)
    oc.feature_min_length = kMinFeatureLineEdges * voxel_size;
  return oc;
}

std::size_t frame_memory_estimate(const PointCloud& cloud, const SparseGrid& grid) {
  const std::size_t per_point = sizeof(Eigen::Vector3f) * (1 + (cloud.has_normals() ? 1 : 0)) +
                                (cloud.colors.empty() ? 0 : sizeof(Rgb8)) +
                                (cloud.intensities.empty() ? 0 : sizeof(float));
  const std::size_t per_cell = sizeof(VoxelKey) + sizeof(std::array<std::uint32_t, 8>);
  const std::size_t per_corner = sizeof(VoxelKey) + sizeof(float) + sizeof(std::uint8_t);
  return cloud.size() * per_point + grid.cells.size() * per_cell + grid.corners.size() * per_corner;
}

}  // namespace meshflow

namespace meshflow::stages {
namespace {

// A size or setting in a message: "0.05", "3", "1.5e-05" (std::to_string gives "0.050000").
std::string short_number(float value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", static_cast<double>(value));
  return text;
}

// The scale of the outlier links: the configured voxel, but never below the one the points'
// spacing suggests (a voxel chosen far smaller than the spacing must not isolate every point).
// An automatic voxel (f.voxel_size, chosen by "index" from the whole cloud, or decided from the
// whole input for a chunk) is the scale itself.
float outlier_link_voxel(const Frame& f, const ReconstructionConfig& c) {
  if (c.voxel_from_whole_input) return c.voxelize.voxel_size;
  if (!(c.voxelize.voxel_size > 0.0f) && f.voxel_size > 0.0f) return f.voxel_size;
  return std::max(c.voxelize.voxel_size, suggest_voxel_size(f.cloud, *f.index));
}

// Drops the points of clusters too small to make a surface (c.filter.outlier_cluster), with the
// index just built, and rebuilds the index over the points kept; counts them in filter_counts.
void remove_point_clusters(Frame& f, const ReconstructionConfig& c) {
  ClusterConfig config;
  config.min_points = c.filter.outlier_cluster;
  config.link_radius = c.filter.outlier_radius_voxels * outlier_link_voxel(f, c);
  if (!(config.link_radius > 0.0f)) return;  // coinciding points: "voxelize" says so
  ClusterCounts counts;
  const std::vector<std::uint32_t> keep =
      surface_cluster_indices(f.cloud, *f.index, config, &counts);
  // No cluster large enough: the cloud is too small for the criterion; the later stages say
  // why it gives no surface.
  if (keep.size() == f.cloud.size() || counts.clusters == 0) return;
  f.filter_counts.isolated = counts.isolated;
  f.filter_counts.sparse_clusters = counts.sparse;
  if (keep.size() < 3)
    throw Error(f.name, "outliers",
                "only " + std::to_string(keep.size()) + " of " + std::to_string(f.cloud.size()) +
                    " points lie in clusters of at least --outlier-cluster " +
                    std::to_string(config.min_points) + " points linked within " +
                    short_number(config.link_radius) +
                    " m; need at least 3 (is the voxel size too small for the spacing?)");
  f.cloud = select_points(f.cloud, keep);  // keeps the Morton order
  f.filter_counts.output = f.cloud.size();
  f.index = std::make_shared<KdTreeIndex>(f.cloud.positions);
}

}  // namespace

std::uint64_t read(Frame& f, const ReconstructionConfig& c) {
  if (f.load_depth) {
    f.set_depth_image(f.load_depth());
    return f.depth->image.depth.pixels();
  }
  if (f.load) f.cloud = f.load();
  f.origin = f.cloud.origin;
  if (c.organized_as_depth && f.cloud.is_organized()) {
    if (std::optional<DepthFrame> depth = depth_frame_from_organized(f.cloud)) {
      f.set_depth_image(std::move(*depth));
      f.cloud = PointCloud{};
      return f.depth->image.depth.pixels();
    }
  }
  return f.cloud.size();
}

namespace {

// c.filter on the frame's cloud (a georeferenced cloud's crop box moved into its local frame);
// expect_three_points() checks what remains.
void filter_points(Frame& f, const ReconstructionConfig& c) {
  if (f.cloud.origin.isZero()) {
    f.cloud = filter_cloud(f.cloud, c.filter, &f.filter_counts);
  } else {  // a georeferenced cloud is in its local frame; the crop box in the file's world one
    FilterConfig local = c.filter;
    local.crop_min = (c.filter.crop_min.cast<double>() - f.cloud.origin).cast<float>();
    local.crop_max = (c.filter.crop_max.cast<double>() - f.cloud.origin).cast<float>();
    f.cloud = filter_cloud(f.cloud, local, &f.filter_counts);
  }
}

// Fails a frame left with fewer than 3 points, saying what the filter took.
void expect_three_points(const Frame& f) {
  if (f.cloud.size() >= 3) return;
  throw Error(f.name, "filter",
              "only " + std::to_string(f.cloud.size()) + " finite points remain of " +
                  std::to_string(f.filter_counts.input) + " (" +
                  std::to_string(f.filter_counts.non_finite) + " NaN/Inf, " +
                  std::to_string(f.filter_counts.cropped) +
                  " outside the crop box or range); need at least 3");
}

}  // namespace

std::uint64_t filter(Frame& f, const ReconstructionConfig& c) {
  filter_points(f, c);
  expect_three_points(f);
  // A point or a line has no surface: say so instead of meshing a ribbon.
  const Eigen::Vector3d extents = principal_extents(f.cloud);
  if (!(extents[2] > 0.0))
    throw Error(f.name, "points",
                "all " + std::to_string(f.cloud.size()) +
                    " points coincide; there is no surface to extract");
  if (extents[1] <= 1e-4 * extents[2])
    throw Error(f.name, "points",
                "all " + std::to_string(f.cloud.size()) + " points lie on a line (spread " +
                    std::to_string(extents[2]) + " m along it, " + std::to_string(extents[1]) +
                    " m across); a surface needs points spread in two directions");
  return f.cloud.size();
}

std::uint64_t depth_to_cloud(Frame& f, const ReconstructionConfig& c) {
  DepthImagePart& input = *f.depth;
  const Image depth_m = filter_depth(input.image, c.depth_filter, &input.counts);
  if (input.counts.valid == 0) {
    throw Error(f.name, "depth",
                "no valid depth pixel (" + std::to_string(input.counts.invalid) +
                    " without measurement, " + std::to_string(input.counts.out_of_range) +
                    " out of range)");
  }
  f.cloud = back_project_valid(input.image, depth_m);  // finite points with normals only
  input.image.depth = depth_m;     // keep only the filtered metric depth for the distance stage
  input.image.depth_scale = 1.0f;  // the colour stays for the mesh's vertex colours
  if (c.filter.keeps_every_finite_point()) {  // nothing left to filter: no copy
    f.filter_counts = FilterCounts{};
    f.filter_counts.input = f.filter_counts.output = f.cloud.size();
  } else {
    filter_points(f, c);
  }
  expect_three_points(f);
  return f.cloud.size();
}

std::uint64_t filter_depth_image(Frame& f, const ReconstructionConfig& c) {
  if (!f.depth)
    throw Error(f.name, "input",
                "fusion needs depth images, or organized clouds that are a pinhole camera's "
                "back-projection; got " +
                    std::string(f.cloud.is_organized() ? "an organized cloud that is not"
                                                       : "an unorganized cloud"));
  DepthImagePart& input = *f.depth;
  input.image.depth = filter_depth(input.image, c.depth_filter, &input.counts);
  input.image.depth_scale = 1.0f;
  if (input.counts.valid == 0) {
    throw Error(f.name, "depth", "no valid depth pixel");
  }
  return input.counts.valid;
}

std::uint64_t index(Frame& f, const ReconstructionConfig& c) {
  // Neighbours in space become neighbours in memory for every pass that follows.
  if (!f.cloud.is_organized()) f.cloud = in_morton_order(f.cloud);
  f.index = std::make_shared<KdTreeIndex>(f.cloud.positions);
  // The automatic voxel from the whole filtered cloud, before any cluster is dropped: the
  // statistic the out-of-core path measures while streaming its input (spacing_sample.h).
  if (!(c.voxelize.voxel_size > 0.0f) && !f.cloud.is_organized())
    f.voxel_size = auto_voxel_size(f.cloud, *f.index);
  if (c.filter.outlier_cluster > 1 && !f.cloud.is_organized()) remove_point_clusters(f, c);
  return f.cloud.size();
}

std::uint64_t normals(Frame& f, const ReconstructionConfig& c) {
  NormalsConfig config = c.normals;
  if (c.extract.method == ExtractMethod::kExtendedMarchingCubes)
    config.sharp = NormalsConfig::Sharp::kOn;
  else if (c.extract.method == ExtractMethod::kAuto && config.sharp == NormalsConfig::Sharp::kOff)
    config.sharp = NormalsConfig::Sharp::kWhenClean;
  ComputedNormals computed = compute_normals(f.cloud, *f.index, config);
  f.cloud.normals = std::move(computed.normals);
  f.normals = computed.report;
  return computed.report.estimated;
}

std::uint64_t voxelize(Frame& f, const ReconstructionConfig& c) {
  VoxelizeConfig vc = c.voxelize;
  if (!(vc.voxel_size > 0.0f)) {
    vc.voxel_size = f.depth ? suggest_voxel_size_for_depth(f.cloud, f.depth->image.intrinsics.fx)
                    : f.voxel_size > 0.0f ? f.voxel_size  // chosen by "index"
                                          : suggest_voxel_size(f.cloud, *f.index);
    if (!(vc.voxel_size > 0.0f))
      throw Error("voxelize", "voxel_size",
                  "cannot be chosen from the points: their spacing and extent are 0 (do they all "
                  "coincide?); there is no surface to extract");
  }
  f.voxel_size = vc.voxel_size;
  f.grid = meshflow::voxelize(f.cloud, vc);
  if (f.chunk) keep_cells_in(f.grid, f.chunk->owned_cells);
  const std::size_t bytes = frame_memory_estimate(f.cloud, f.grid);
  if (c.max_memory_bytes > 0 && bytes > c.max_memory_bytes) {
    const auto mib = [](std::size_t b) { return std::to_string(b >> 20) + " MiB"; };
    const std::string grid =
        std::to_string(f.grid.cells.size()) + " cells of " + std::to_string(vc.voxel_size) + " m";
    f.grid = SparseGrid{};
    throw Error(
        f.name, "memory",
        std::to_string(f.cloud.size()) + " points in " + grid + " need about " + mib(bytes) +
            " with their distances, past the limit of " + mib(c.max_memory_bytes) +
            " (--max-memory); use a larger --voxel, or --chunk auto to mesh it in pieces out "
            "of core");
  }
  return f.grid.cells.size();
}

std::uint64_t distance(Frame& f, const ReconstructionConfig& c) {
  f.distance = hoppe_distance(f.grid, f.cloud, *f.index, c.distance);
  return f.grid.corners.size();
}

std::uint64_t depth_distance(Frame& f, const ReconstructionConfig& c) {
  DepthFrame& image = f.depth->image;
  f.distance = projective_distance(f.grid, image.depth, image.intrinsics, image.T_world_camera,
                                   c.projective);
  image.depth = Image();  // keep frames in flight small; the colour waits for "extract"
  return f.grid.corners.size();
}

std::uint64_t close(Frame& f, const ReconstructionConfig& c) {
  if (f.chunk)
    throw Error(f.name, "close",
                "--close needs the whole cloud in one piece; it cannot close chunks (--chunk)");
  ClosedDistance closed = close_distance_field(f.grid, f.distance, f.cloud, c.close, &f.closing);
  f.grid = std::move(closed.grid);
  f.distance = std::move(closed.distance);
  return f.closing.filled;
}

namespace {

// Frees the grid's cell corners and the distance values once the surface is extracted: no stage
// after "extract" reads them (the reports count the grid's cells and corners and the valid
// samples, which stay). 32 bytes per cell and 4 per corner, at the run's peak.
void release_extracted_field(Frame& f) {
  std::vector<std::array<std::uint32_t, 8>>().swap(f.grid.cell_corners);
  std::vector<float>().swap(f.distance.values);
}

}  // namespace

std::uint64_t extract(Frame& f, const ReconstructionConfig& c) {
  ExtractConfig config = c.extract;
  if (config.method == ExtractMethod::kAuto)  // sharp normals were estimated for clean samples
    config.method =
        f.normals.sharp ? ExtractMethod::kExtendedMarchingCubes : ExtractMethod::kMarchingCubes;
  f.extract_method = config.method;
  // Extended marching cubes' feature vertices: a chunk's for its deferred flips, a whole
  // mesh's for the optimize stage's feature graph.
  const bool emc = config.method == ExtractMethod::kExtendedMarchingCubes;
  std::vector<std::uint8_t>* feature_vertices =
      f.chunk ? (config.defer_feature_flips ? &f.chunk->feature_vertices : nullptr)
              : (emc ? &f.feature_vertices : nullptr);
  f.mesh = extract_surface(f.grid, f.distance, f.cloud, f.index.get(), config, feature_vertices);
  release_extracted_field(f);
  // Planar marching cubes places no vertex on a feature, but knows the data: on clean samples
  // (sharp normals, or estimated ones whose plane fits are as exact as NormalsConfig's
  // clean_variation; a scan's would flag nearly every vertex) the vertices where it shows one.
  const bool clean = f.normals.sharp || (f.normals.estimated > 0 &&
                                         f.normals.median_variation < c.normals.clean_variation);
  if (!f.chunk && f.index && clean && config.method == ExtractMethod::kPlanarMarchingCubes)
    f.feature_vertices = data_feature_vertices(f.mesh, f.cloud, *f.index, f.grid.voxel_size);
  const std::size_t extracted = f.mesh.triangles.size();
  if (f.index && c.max_rim_voxels > 0.0f) {
    const float limit = c.max_rim_voxels * f.voxel_size;
    if (f.chunk)  // a chunk: the rim is trimmed once the chunks are stitched
      f.chunk->beyond_data =
          vertices_beyond_data(f.mesh.vertices, f.cloud.positions, *f.index, limit);
    else {
      std::vector<std::uint32_t> kept;  // the feature vertices follow their vertices
      f.mesh = trim_rim(f.mesh, f.cloud.positions, *f.index, limit, &f.rim_trimmed,
                        f.feature_vertices.empty() ? nullptr : &kept);
      if (!f.feature_vertices.empty() && f.rim_trimmed > 0) {
        std::vector<std::uint8_t> flags(kept.size());
        for (std::size_t v = 0; v < kept.size(); ++v) flags[v] = f.feature_vertices[kept[v]];
        f.feature_vertices = std::move(flags);
      }
    }
  }
  if (f.feature_vertices.size() != f.mesh.vertices.size()) f.feature_vertices.clear();
  // A frame without a surface fails here, on every path (reconstruct, run, the embedding API),
  // rather than passing on as an "ok" frame with an empty mesh. A chunk may own no surface.
  if (f.mesh.triangles.empty() && !f.chunk) {
    const std::string grid = std::to_string(f.grid.cells.size()) + " cells of " +
                             short_number(f.voxel_size) + " m from " +
                             std::to_string(f.cloud.size()) + " points";
    throw Error(f.name, "extract",
                extracted == 0
                    ? "no surface was extracted (" + grid +
                          "); expected at least one triangle: too few points, or a voxel size "
                          "too small or too large for their spacing?"
                    : "the rim trim (--max-rim " + short_number(c.max_rim_voxels) +
                          " voxels) removed all " + std::to_string(extracted) +
                          " extracted triangles (" + grid +
                          "); expected a surface within reach of the points");
  }
  if (f.depth) {  // a depth frame with a colour image gives a coloured mesh
    f.mesh.colors = vertex_colors_from_image(f.mesh.vertices, f.depth->image);
    f.depth->image = DepthFrame{};             // the counts stay for the report
  } else if (f.cloud.has_colors() && f.index)  // so does a coloured cloud
    f.mesh.colors = vertex_colors(f.mesh.vertices, f.cloud, *f.index);
  f.index.reset();  // no stage after "extract" searches the points (about 16 bytes per point)
  return f.mesh.triangles.size();
}

std::uint64_t optimize(Frame& f, const ReconstructionConfig& c) {
  OptimizeConfig config = optimize_config_for_voxel(c, f.voxel_size);
  if (f.on_stage)
    config.on_step = [&f](OptimizeStep step) { f.on_stage("optimize", optimize_step_name(step)); };
  if (f.chunk && f.chunk->finish_cells > 0) {  // a chunk finished here, its seams held
    chunk::ChunkFinishConfig finish;
    finish.voxel_size = f.voxel_size;
    finish.chunk_cells = f.chunk->finish_cells;
    finish.trim_rim = c.max_rim_voxels > 0.0f;
    finish.optimize = std::move(config);
    chunk::ChunkFinishReport report;
    f.mesh = chunk::finish_chunk_mesh(f.mesh, f.chunk->beyond_data, f.chunk->feature_vertices,
                                      finish, &report);
    f.chunk->beyond_data.clear();
    f.rim_trimmed = report.rim_trimmed;
    f.optimize = std::move(report.optimize);
    return f.mesh.triangles.size();
  }
  const std::size_t before = f.mesh.triangles.size();
  f.mesh = optimize_mesh(f.mesh, config, &f.optimize, f.feature_vertices);
  if (!config.steps.empty()) f.feature_vertices = {};        // no longer this mesh's vertices
  if (f.mesh.triangles.empty() && before > 0 && !f.chunk) {  // nothing left: a failed frame
    std::string why = "the steps removed all " + std::to_string(before) + " triangles";
    for (const OptimizeStepReport& step : f.optimize.steps) {
      if (step.triangles_in == 0 || step.triangles_out > 0) continue;
      why = "the " + std::string(optimize_step_name(step.step)) + " step removed all " +
            std::to_string(step.triangles_in) + " triangles" +
            (step.detail.empty() ? "" : " (" + step.detail + ")");
      if (step.step == OptimizeStep::kClean)
        why += ": every component has fewer than --min-component " +
               std::to_string(config.cleanup.min_component_triangles) + " triangles";
      break;
    }
    throw Error(f.name, "optimize", why + "; expected a mesh with at least one triangle");
  }
  return f.mesh.triangles.size();
}

namespace {

// Vertex normals where the mesh has none: computed from its triangles, as for a depth image. An
// input's normal that is missing (NaN or zero, as PCL leaves them at image borders) takes the
// computed one.
void complete_vertex_normals(TriangleMesh& mesh) {
  if (mesh.normals.empty()) return compute_vertex_normals(mesh);
  const auto missing = [](const Eigen::Vector3f& n) {
    return !n.allFinite() || n.squaredNorm() == 0.0f;
  };
  if (std::none_of(mesh.normals.begin(), mesh.normals.end(), missing)) return;
  std::vector<Eigen::Vector3f> given = std::move(mesh.normals);
  compute_vertex_normals(mesh);
  for (std::size_t v = 0; v < given.size(); ++v)
    if (!missing(given[v])) mesh.normals[v] = given[v];
}

}  // namespace

std::uint64_t triangulate(Frame& f, const ReconstructionConfig& c) {
  if (f.depth) {
    f.mesh = triangulate_depth(f.depth->image, c.triangulation, &f.triangulation);
    f.mesh.colors = vertex_colors_from_image(f.mesh.vertices, f.depth->image);
    f.depth->image = DepthFrame{};
  } else if (f.cloud.is_organized()) {
    // The cloud's colours and normals stay on the vertices (each vertex is one of its points).
    f.mesh = triangulate_organized(f.cloud, c.triangulation, &f.triangulation);
    f.cloud = PointCloud{};  // keep frames in flight small
  } else {
    throw Error(f.name, "input",
                "depth-map triangulation needs a depth image or an organized point cloud "
                "(width x height points); got an unorganized cloud of " +
                    std::to_string(f.cloud.size()) + " points");
  }
  if (f.mesh.triangles.empty())  // a failed frame, not an "ok" one with an empty mesh
    throw Error(f.name, "triangulate",
                "no triangle was made: expected valid depths at three neighbouring pixels or "
                "points at least once (is the frame empty or all out of range?)");
  complete_vertex_normals(f.mesh);
  return f.mesh.triangles.size();
}

const NamedStage kDepthTriangulationStages[2] = {{"read", read}, {"triangulate", triangulate}};

const NamedStage kPointCloudStages[8] = {
    {"read", read},         {"filter", filter},     {"index", index},     {"normals", normals},
    {"voxelize", voxelize}, {"distance", distance}, {"extract", extract}, {"optimize", optimize}};

const NamedStage kDepthImageStages[6] = {{"read", read},         {"filter", depth_to_cloud},
                                         {"voxelize", voxelize}, {"distance", depth_distance},
                                         {"extract", extract},   {"optimize", optimize}};

std::uint64_t compress(Frame& f, const ReconstructionConfig& c) {
  compress::CompressConfig config = c.compress;
  config.origin_offset += f.origin;
  f.compressed = c.compression == MeshCompression::kProgressive
                     ? compress::compress_progressive(f.mesh, config)
                     : compress::compress_mesh(f.mesh, config);
  return f.compressed.size();
}

namespace {

// The stages of `table` after "read", with "close" before "extract" when `close_surfaces`.
template <std::size_t N>
std::vector<NamedStage> route_after_read(const NamedStage (&table)[N], bool close_surfaces) {
  std::vector<NamedStage> route;
  route.reserve(N);  // the stages after "read", and "close"
  for (std::size_t i = 1; i < N; ++i) {
    if (close_surfaces && std::string(table[i].name) == "extract")
      route.push_back({"close", stages::close});
    route.push_back(table[i]);
  }
  return route;
}

}  // namespace

FrameRoutes frame_routes(bool triangulate_depth_maps, MeshCompression compression,
                         bool close_surfaces) {
  FrameRoutes routes{{"read", read}, {}, {}};
  if (triangulate_depth_maps) {
    routes.cloud = routes.depth = route_after_read(kDepthTriangulationStages, false);
  } else {
    routes.cloud = route_after_read(kPointCloudStages, close_surfaces);
    routes.depth = route_after_read(kDepthImageStages, close_surfaces);
  }
  if (compression != MeshCompression::kNone) {
    routes.cloud.push_back({"compress", compress});
    routes.depth.push_back({"compress", compress});
  }
  return routes;
}

void run_stage(const char* name, StageFunction body, Frame& f, const ReconstructionConfig& c) {
  run_stage(
      name, [&](Frame& frame) { return body(frame, c); }, f);
}

void run_stage(const char* name, const std::function<std::uint64_t(Frame&)>& body, Frame& f) {
  if (!f.ok()) return;
  if (f.on_stage) f.on_stage(name, nullptr);
  StageRecord record{name, monotonic_seconds(), 0.0, current_thread_index(), 0, f.seq};
  try {
    record.items = body(f);
  } catch (const std::exception& e) {
    f.error = e.what();
    f.failed_stage = name;
  }
  record.end_s = monotonic_seconds();
  f.timings.push_back(std::move(record));
}

}  // namespace meshflow::stages
