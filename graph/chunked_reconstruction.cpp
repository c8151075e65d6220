#include "graph/chunked_reconstruction.h"

#include <algorithm>
#include <cmath>

#include "graph/pipeline.h"
#include "nodes/chunk/mesh_stitch.h"
#include "nodes/extract/rim_trim.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/normals/scene_side.h"
#include "nodes/search/spatial_index.h"
#include "runtime/error.h"
#include "runtime/tracing.h"

namespace meshflow {
namespace {

// The voxel (unless given) and the chunk grid from the first batch of the input: the voxel as
// suggest_voxel_size() gives it, the chunk edge as given or as auto_chunk_size() gives it.
// Throws meshflow::Error naming `path` when the batch has too few distinct finite points.
chunk::ChunkGrid grid_from_first_batch(const PointCloud& batch, float voxel_size,
                                       ChunkingConfig chunking, const std::string& path) {
  PointCloud finite;
  for (const Eigen::Vector3f& p : batch.positions)
    if (p.allFinite()) finite.positions.push_back(p);
  std::unique_ptr<KdTreeIndex> index;
  if (finite.size() >= 2) index = std::make_unique<KdTreeIndex>(finite.positions);
  if (!(voxel_size > 0.0f) && index) voxel_size = suggest_voxel_size(finite, *index);
  if (!(voxel_size > 0.0f)) {
    throw Error(path, "voxel size",
                "cannot be chosen from the first points (fewer than 2 finite, or all "
                "coincide); give --voxel");
  }
  if (!(chunking.chunk_size > 0.0f)) {
    chunking.chunk_size = index ? auto_chunk_size(finite, *index, voxel_size,
                                                  chunking.memory_budget, chunking.in_flight)
                                : 4.0f * voxel_size;
  }
  return make_chunk_grid(voxel_size, chunking);
}

std::string chunk_label(const chunk::ChunkFile& file) {
  return "chunk (" + std::to_string(file.index.x()) + "," + std::to_string(file.index.y()) + "," +
         std::to_string(file.index.z()) + ")";
}

}  // namespace

ReconstructionConfig chunk_stage_config(const ReconstructionConfig& config, float voxel_size) {
  ReconstructionConfig c = config;
  c.voxelize.voxel_size = voxel_size;
  c.optimize.steps.clear();
  c.compression = MeshCompression::kNone;
  c.normals.whole_scene = false;  // a chunk is a piece of a larger cloud: no view, no terrain
  return c;
}

float auto_chunk_size(const PointCloud& sample, const SpatialIndex& index, float voxel_size,
                      std::size_t memory_budget, std::size_t in_flight) {
  const std::size_t budget = memory_budget > 0 ? memory_budget : std::size_t{1} << 30;
  const double points = static_cast<double>(budget) /
                        static_cast<double>(std::max<std::size_t>(in_flight, 1)) /
                        static_cast<double>(kChunkBytesPerPoint);
  // suggest_voxel_size() with factor 1: the median nearest-neighbour spacing (or 1/2000 of the
  // sample's diagonal, whichever is larger).
  const double spacing = suggest_voxel_size(sample, index, 1.0f);
  const double edge = spacing * std::sqrt(4.5 * points / 2.0);
  return static_cast<float>(std::max(edge, 4.0 * static_cast<double>(voxel_size)));
}

chunk::ChunkGrid make_chunk_grid(float voxel_size, const ChunkingConfig& chunking) {
  if (!(chunking.chunk_size > 0.0f) || !std::isfinite(chunking.chunk_size))
    throw Error("--chunk", std::to_string(chunking.chunk_size),
                "expected a positive size in metres");
  chunk::ChunkGrid grid;
  grid.voxel_size = voxel_size;
  const double cells = std::round(static_cast<double>(chunking.chunk_size) / voxel_size);
  grid.chunk_cells = static_cast<int>(std::clamp(cells, 1.0, 100000.0));
  grid.overlap_cells = std::max(1, chunking.overlap_voxels);
  return grid;
}

std::unique_ptr<chunk::ChunkStore> partition_input(
    const std::string& path, const std::string& columns, const ReconstructionConfig& config,
    const ChunkingConfig& chunking, std::vector<chunk::ChunkFile>& files, float& voxel_size) {
  std::unique_ptr<chunk::ChunkStore> store;
  voxel_size = config.voxelize.voxel_size;
  io::for_each_point_batch(path, columns, chunking.batch_points, [&](const PointCloud& batch) {
    if (!store) {
      const chunk::ChunkGrid grid = grid_from_first_batch(batch, voxel_size, chunking, path);
      voxel_size = grid.voxel_size;
      store = std::make_unique<chunk::ChunkStore>(grid, chunking.directory);
      store->add(batch);
      // A chunk cannot tell a terrain from an object by itself (whole_scene is off for chunks):
      // the first batch decides for all, as one process decides for the whole cloud.
      if (!batch.has_normals() && classify_scene(batch) == SceneKind::kHeightField)
        store->set_z_up();
      return;
    }
    store->add(batch);
  });
  if (!store || store->points_read() == 0)
    throw Error(path, "points", "no finite points to reconstruct");
  files = store->finish();
  return store;
}

void mesh_chunk_files(const std::vector<chunk::ChunkFile>& files,
                      const std::function<long long()>& next, const chunk::ChunkGrid& grid,
                      const chunk::ChunkRows& rows, const ReconstructionConfig& config,
                      std::size_t in_flight, const std::string& name,
                      const std::function<void(const FramePtr&)>& sink) {
  ReconstructionPipeline pipeline(chunk_stage_config(config, grid.voxel_size), in_flight);
  pipeline.run(
      [&]() -> FramePtr {
        const long long position = next();
        if (position < 0 || static_cast<std::size_t>(position) >= files.size()) return nullptr;
        const chunk::ChunkFile& file = files[static_cast<std::size_t>(position)];
        auto frame = std::make_shared<Frame>();
        frame->name = name + " " + chunk_label(file);
        frame->source_index = static_cast<std::size_t>(position);
        frame->owned_cells = grid.owned_cells(file.index);
        frame->load = [file, rows] {
          PointCloud cloud = chunk::read_chunk_file(file, rows);
          chunk::remove_chunk_file(file);
          return cloud;
        };
        return frame;
      },
      sink);
}

void mesh_chunk_files(const std::vector<chunk::ChunkFile>& files, const chunk::ChunkGrid& grid,
                      const chunk::ChunkRows& rows, const ReconstructionConfig& config,
                      std::size_t in_flight, const std::string& name,
                      const std::function<void(const FramePtr&)>& sink) {
  long long position = 0;
  const auto n = static_cast<long long>(files.size());
  mesh_chunk_files(
      files, [&] { return position < n ? position++ : -1LL; }, grid, rows, config, in_flight, name,
      sink);
}

void collect_chunk_frame(Frame& frame, chunk::MeshStitcher& stitcher, ChunkedReport& report) {
  report.timings.insert(report.timings.end(), frame.timings.begin(), frame.timings.end());
  if (!frame.ok()) {
    report.failed.push_back(frame.name + ": " + frame.error);
    return;
  }
  stitcher.add(frame.mesh, frame.beyond_data);
  frame.mesh = TriangleMesh{};
  frame.beyond_data.clear();
}

TriangleMesh finish_chunked_mesh(chunk::MeshStitcher& stitcher, const ReconstructionConfig& config,
                                 float voxel_size, ChunkedReport& report,
                                 const std::function<void(const std::string&)>& on_step) {
  double t = monotonic_seconds();
  std::vector<std::uint8_t> beyond;
  TriangleMesh joined = stitcher.stitch(&report.seam_vertices, &beyond);
  if (!beyond.empty()) joined = trim_rim(joined, beyond, &report.rim_trimmed);
  report.stitch_s = monotonic_seconds() - t;
  t = monotonic_seconds();
  OptimizeConfig optimize = optimize_config_for_voxel(config, voxel_size);
  if (on_step) optimize.on_step = [&](OptimizeStep step) { on_step(optimize_step_name(step)); };
  TriangleMesh mesh = optimize_mesh(joined, optimize, &report.optimize);
  report.optimize_s = monotonic_seconds() - t;
  return mesh;
}

ChunkedResult reconstruct_chunked(const std::string& path, const std::string& columns,
                                  const ReconstructionConfig& config,
                                  const ChunkingConfig& chunking,
                                  const std::function<void(const std::string&)>& on_stage) {
  const auto tell = [&](const std::string& what) {
    if (on_stage) on_stage(what);
  };
  ChunkedResult result;
  ChunkedReport& report = result.report;
  double t = monotonic_seconds();
  tell("partition");
  std::vector<chunk::ChunkFile> files;
  float voxel = 0.0f;
  const std::unique_ptr<chunk::ChunkStore> store =
      partition_input(path, columns, config, chunking, files, voxel);
  report.voxel_size = voxel;
  report.chunk_cells = store->grid().chunk_cells;
  report.chunks = files.size();
  report.points = store->points_read();
  report.dropped = store->points_dropped();
  report.rows_written = store->rows_written();
  for (const chunk::ChunkFile& f : files)
    report.max_chunk_points = std::max(report.max_chunk_points, f.points);
  result.origin = store->rows().origin;
  report.partition_s = monotonic_seconds() - t;

  t = monotonic_seconds();
  chunk::MeshStitcher stitcher(voxel, report.chunk_cells);
  std::size_t done = 0;
  mesh_chunk_files(files, store->grid(), store->rows(), config, chunking.in_flight, path,
                   [&](const FramePtr& frame) {
                     ++done;
                     tell("chunk " + std::to_string(done) + "/" + std::to_string(files.size()));
                     collect_chunk_frame(*frame, stitcher, report);
                   });
  report.mesh_s = monotonic_seconds() - t;

  tell("stitch");
  result.mesh = finish_chunked_mesh(stitcher, config, voxel, report, tell);
  return result;
}

}  // namespace meshflow
