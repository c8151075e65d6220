#include "graph/chunked_reconstruction.h"

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "graph/chunk_finish.h"
#include "graph/chunk_output.h"
#include "graph/pipeline.h"
#include "graph/tile_levels.h"
#include "nodes/chunk/mesh_spill.h"
#include "nodes/chunk/mesh_stitch.h"
#include "nodes/chunk/mesh_tiles.h"
#include "nodes/extract/feature_edge_flips.h"
#include "nodes/extract/rim_trim.h"
#include "nodes/filter/filter.h"
#include "nodes/io/mesh_writers.h"
#include "nodes/io/parse_util.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/normals/scene_side.h"
#include "nodes/voxelize/spacing_sample.h"
#include "runtime/error.h"
#include "runtime/tracing.h"

namespace meshflow {
namespace {

// Whether `config`'s normals stage would take sharp-feature normals for an input whose median
// plane-fit variation is `variation` (NormalsConfig::Sharp, with the pipeline's kWhenClean for
// --extract auto), given whether the input carries normals and a sensor position.
bool sharp_for_input(const ReconstructionConfig& config, float variation, bool input_normals,
                     bool sensor) {
  const NormalsConfig& n = config.normals;
  if (n.sharp == NormalsConfig::Sharp::kOn) return true;
  const bool clean = variation < n.clean_variation;
  const bool from_input = input_normals && n.source != NormalSource::kEstimate;
  if (from_input) return clean;
  NormalOrientation orientation = n.orientation;
  if (orientation == NormalOrientation::kAuto)
    orientation = sensor ? NormalOrientation::kTowardSensor : NormalOrientation::kPropagate;
  return orientation == NormalOrientation::kPropagate && clean;
}

// Adds a chunk's optimize report to the sum over chunks: step by step, triangles and seconds
// summed, the clean counts summed, the details of the first chunk that did something.
void chunked_add_optimize(OptimizeReport& total, const OptimizeReport& chunk) {
  for (std::size_t i = 0; i < chunk.steps.size(); ++i) {
    const OptimizeStepReport& s = chunk.steps[i];
    if (i >= total.steps.size()) {
      total.steps.push_back(s);
      total.steps.back().detail = "summed over the chunks";
      continue;
    }
    OptimizeStepReport& t = total.steps[i];
    t.triangles_in += s.triangles_in;
    t.triangles_out += s.triangles_out;
    t.seconds += s.seconds;
  }
  CleanupReport& c = total.cleanup;
  const CleanupReport& d = chunk.cleanup;
  c.degenerate_triangles += d.degenerate_triangles;
  c.duplicate_triangles += d.duplicate_triangles;
  c.components += d.components;
  c.removed_components += d.removed_components;
  c.removed_component_triangles += d.removed_component_triangles;
  c.removed_vertices += d.removed_vertices;
  c.non_manifold_vertices += d.non_manifold_vertices;
  c.removed_fan_triangles += d.removed_fan_triangles;
}

std::string chunk_label(const chunk::ChunkFile& file) {
  return "chunk (" + std::to_string(file.index.x()) + "," + std::to_string(file.index.y()) + "," +
         std::to_string(file.index.z()) + ")";
}

}  // namespace

std::vector<Eigen::Vector3f> points_to_sample(const PointCloud& batch, const FilterConfig& filter) {
  FilterConfig crop = filter;  // the per-point part of the filters
  crop.voxel_size = 0.0f;
  crop.outlier_k = 0;
  std::vector<Eigen::Vector3f> kept;
  if (crop.keeps_every_finite_point()) {
    kept.reserve(batch.size());
    for (const Eigen::Vector3f& p : batch.positions)
      if (p.allFinite()) kept.push_back(p);
    return kept;
  }
  crop.crop_min = (filter.crop_min.cast<double>() - batch.origin).cast<float>();
  crop.crop_max = (filter.crop_max.cast<double>() - batch.origin).cast<float>();
  for (const std::uint32_t i : crop_indices(batch, crop))
    if (batch.positions[i].allFinite()) kept.push_back(batch.positions[i]);
  return kept;
}

bool finishes_in_place(const ReconstructionConfig& config, const ChunkingConfig& chunking) {
  if (!chunking.finish_in_place) return false;
  if (config.optimize.cleanup.non_manifold_vertices == NonManifoldVertexRepair::kSplit)
    return false;
  return std::all_of(
      config.optimize.steps.begin(), config.optimize.steps.end(),
      [](OptimizeStep s) { return s == OptimizeStep::kClean || s == OptimizeStep::kHoles; });
}

ReconstructionConfig chunk_stage_config(const ReconstructionConfig& config,
                                        const InputDecisions& decided, bool finish_in_place) {
  ReconstructionConfig c = config;
  c.voxelize.voxel_size = decided.voxel_size;
  c.voxel_from_whole_input = decided.voxel_automatic;
  if (c.extract.method == ExtractMethod::kAuto) c.extract.method = decided.method;
  c.extract.defer_feature_flips = true;  // flipped once the chunks are stitched
  if (decided.noisy) c.normals.kn = 2 * std::max(c.normals.kn, 3);
  c.normals.noisy_variation = 0.0f;  // decided for the whole input, not per chunk
  if (!finish_in_place) c.optimize.steps.clear();
  c.compression = MeshCompression::kNone;
  c.normals.whole_scene = false;  // a chunk is a piece of a larger cloud: no view, no terrain
  return c;
}

InputParts input_parts(const std::string& path, const std::string& columns, std::size_t parts) {
  InputParts out;
  const io::PointRanges ranges = io::point_ranges(path, columns);
  out.why_not = ranges.why_not;
  if (!ranges.by_byte_range) return out;
  out.by_byte_range = true;
  constexpr std::uint64_t kMinPartPoints = 4096;
  const std::uint64_t n = ranges.points;
  const std::uint64_t count =
      std::clamp<std::uint64_t>(n / kMinPartPoints, 1, std::max<std::size_t>(parts, 1));
  for (std::uint64_t p = 0; p < count; ++p) {
    const std::uint64_t first = n * p / count, end = n * (p + 1) / count;
    out.ranges.emplace_back(first, end - first);
  }
  return out;
}

void for_each_input_part(const std::string& path, const std::string& columns,
                         const InputParts& parts, std::size_t batch_points,
                         const std::function<void(std::size_t, const PointCloud&)>& sink) {
  if (!parts.by_byte_range) {
    io::for_each_point_batch(path, columns, batch_points,
                             [&](const PointCloud& batch) { sink(0, batch); });
    return;
  }
  tbb::parallel_for(std::size_t{0}, parts.ranges.size(), [&](std::size_t p) {
    io::for_each_point_batch_in_range(path, columns, parts.ranges[p].first, parts.ranges[p].second,
                                      batch_points,
                                      [&](const PointCloud& batch) { sink(p, batch); });
  });
}

InputDecisions decide_from_input(const std::string& path, const std::string& columns,
                                 const ReconstructionConfig& config, std::size_t batch_points,
                                 const InputParts& given_parts, bool measure_density) {
  if (!decisions_need_sample(config) && !measure_density) {
    InputDecisions decided;
    decided.voxel_size = config.voxelize.voxel_size;
    decided.method = config.extract.method;
    return decided;
  }
  const InputParts& parts = given_parts;
  const std::size_t count = std::max<std::size_t>(parts.ranges.size(), 1);
  // Pass 1: the sample (the lowest-ranked points) and the bounds; pass 2: their neighbours.
  // Each part samples and measures its own points; the parts are joined in order.
  const SpacingSample empty = empty_input_sample(config);
  std::vector<SpacingSample> samples(count, empty);
  bool normals = false, sensor = false, first = true;
  for_each_input_part(path, columns, parts, batch_points,
                      [&](std::size_t part, const PointCloud& batch) {
                        if (part == 0 && first) {  // the file's first batch
                          normals = batch.has_normals();
                          sensor = batch.has_sensor_origin;
                          first = false;
                        }
                        samples[part].offer(points_to_sample(batch, config.filter));
                      });
  SpacingSample sample = empty;
  for (const SpacingSample& s : samples) sample.merge_offered(s);
  std::fill(samples.begin(), samples.end(), sample);
  for_each_input_part(
      path, columns, parts, batch_points, [&](std::size_t part, const PointCloud& batch) {
        const std::vector<Eigen::Vector3f> points = points_to_sample(batch, config.filter);
        samples[part].measure(points);  // no kd-tree per batch: see measure()
      });
  for (std::size_t part = 1; part < count; ++part) samples[0].merge_measured(samples[part]);
  return decisions_from_sample(samples[0], config, normals, sensor, path);
}

SpacingSample empty_input_sample(const ReconstructionConfig& config) {
  return SpacingSample(static_cast<std::size_t>(std::max(config.normals.kn, 3)));
}

bool decisions_need_sample(const ReconstructionConfig& config) {
  return !(config.voxelize.voxel_size > 0.0f) || config.extract.method == ExtractMethod::kAuto;
}

bool input_needs_sample(const ReconstructionConfig& config, const ChunkingConfig& chunking) {
  return decisions_need_sample(config) || !(chunking.chunk_size > 0.0f);
}

InputDecisions decisions_from_sample(const SpacingSample& sample,
                                     const ReconstructionConfig& config, bool input_normals,
                                     bool sensor, const std::string& path) {
  InputDecisions decided;
  decided.voxel_size = config.voxelize.voxel_size;
  decided.voxel_automatic = !(decided.voxel_size > 0.0f);
  decided.method = config.extract.method;
  if (decided.voxel_automatic) {
    decided.voxel_size = sample.voxel_size();
    if (!(decided.voxel_size > 0.0f))
      throw Error(path, "voxel size",
                  "cannot be chosen from the points (fewer than 2 finite, or all coincide); "
                  "give --voxel");
  }
  decided.median_variation = sample.median_variation();
  decided.density = sample.surface_density();
  if (config.extract.method == ExtractMethod::kAuto)
    decided.method = sharp_for_input(config, decided.median_variation, input_normals, sensor)
                         ? ExtractMethod::kExtendedMarchingCubes
                         : ExtractMethod::kMarchingCubes;
  const bool estimated = !input_normals || config.normals.source == NormalSource::kEstimate;
  decided.noisy = estimated && config.normals.noisy_variation > 0.0f &&
                  decided.median_variation > config.normals.noisy_variation;
  return decided;
}

double chunk_bytes_estimate(double edge, double density, double voxel_size, int overlap_voxels) {
  const double seen = edge + 2.0 * std::max(0, overlap_voxels) * voxel_size;
  const double surface = 2.0 * seen * seen;
  const double per_m2 = std::max(0.0, density) * static_cast<double>(kChunkBytesPerPoint) +
                        static_cast<double>(kChunkBytesPerCell) / (voxel_size * voxel_size);
  return surface * per_m2;
}

float auto_chunk_size(float density, float voxel_size, std::size_t memory_budget,
                      std::size_t in_flight, int overlap_voxels) {
  const std::size_t budget = memory_budget > 0 ? memory_budget : std::size_t{1} << 30;
  const double per_chunk =
      static_cast<double>(budget) / static_cast<double>(std::max<std::size_t>(in_flight, 1));
  const double v = static_cast<double>(voxel_size);
  const double density_or_none = std::isfinite(density) ? static_cast<double>(density) : 0.0;
  // chunk_bytes_estimate() grows as the square of the edge with its overlap: the edge whose
  // estimate is the chunk's share.
  const double seen = std::sqrt(per_chunk / chunk_bytes_estimate(1.0, density_or_none, v, 0));
  const double edge = seen - 2.0 * std::max(0, overlap_voxels) * v;
  return static_cast<float>(std::max(edge, 4.0 * v));
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

chunk::ChunkGrid grid_for_input(const InputDecisions& decided, ChunkingConfig chunking) {
  if (!(chunking.chunk_size > 0.0f))
    chunking.chunk_size =
        auto_chunk_size(decided.density, decided.voxel_size, chunking.memory_budget,
                        chunking.in_flight, chunking.overlap_voxels);
  return make_chunk_grid(decided.voxel_size, chunking);
}

std::unique_ptr<chunk::ChunkStore> partition_input(
    const std::string& path, const std::string& columns, const ReconstructionConfig& config,
    const ChunkingConfig& chunking, std::vector<chunk::ChunkFile>& files, InputDecisions& decided,
    chunk::PhaseClock* clock) {
  const std::size_t threads = static_cast<std::size_t>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  const InputParts parts =
      input_parts(path, columns, chunking.read_parts > 0 ? chunking.read_parts : threads);
  const bool serial = !parts.by_byte_range;  // else as many parts as workers
  if (clock) clock->begin("decide", serial);
  decided = decide_from_input(path, columns, config, chunking.batch_points, parts,
                              input_needs_sample(config, chunking));
  if (clock) clock->begin("partition", serial);
  // The grid from the whole input's decisions; the first batch (the first part's) tells the
  // scene's kind, before the parts are read at once.
  std::unique_ptr<chunk::ChunkStore> store;
  bool z_up = false;
  const auto first_batch = [&](const PointCloud& batch) {
    if (store) return;
    store =
        std::make_unique<chunk::ChunkStore>(grid_for_input(decided, chunking), chunking.directory);
    // A chunk cannot tell a terrain from an object by itself (whole_scene is off for chunks):
    // the first batch decides for all, as one process decides for the whole cloud.
    z_up = !batch.has_normals() && classify_scene(batch) == SceneKind::kHeightField;
  };
  if (parts.by_byte_range) {
    io::for_each_point_batch_in_range(
        path, columns, 0, std::min<std::uint64_t>(parts.ranges[0].second, chunking.batch_points),
        chunking.batch_points, first_batch);
  } else {
    io::for_each_point_batch(path, columns, chunking.batch_points, [&](const PointCloud& batch) {
      first_batch(batch);
      store->add(batch);
    });
  }
  if (!store) throw Error(path, "points", "no finite points to reconstruct");
  if (parts.by_byte_range) {
    std::vector<chunk::ChunkWriter> writers;
    writers.reserve(parts.ranges.size());
    for (std::size_t p = 0; p < parts.ranges.size(); ++p)
      writers.push_back(store->writer(static_cast<long>(p)));
    for_each_input_part(path, columns, parts, chunking.batch_points,
                        [&](std::size_t p, const PointCloud& batch) { writers[p].add(batch); });
    std::vector<chunk::WrittenPart> written;
    written.reserve(writers.size());
    for (chunk::ChunkWriter& w : writers) written.push_back(w.finish());
    files = store->finish(written);
  } else {
    files = store->finish();
  }
  if (z_up) store->set_z_up();
  if (store->points_read() == 0) throw Error(path, "points", "no finite points to reconstruct");
  if (clock) clock->end();
  return store;
}

void mesh_chunk_files(const std::vector<chunk::ChunkFile>& files,
                      const std::function<long long()>& next, const chunk::ChunkGrid& grid,
                      const chunk::ChunkRows& rows, const ReconstructionConfig& config,
                      const InputDecisions& decided, std::size_t in_flight, bool finish_in_place,
                      const std::string& name, const std::function<void(const FramePtr&)>& sink) {
  ReconstructionPipeline pipeline(chunk_stage_config(config, decided, finish_in_place), in_flight);
  pipeline.run(
      [&]() -> FramePtr {
        const long long position = next();
        if (position < 0 || static_cast<std::size_t>(position) >= files.size()) return nullptr;
        const chunk::ChunkFile& file = files[static_cast<std::size_t>(position)];
        auto frame = std::make_shared<Frame>();
        frame->name = name + " " + chunk_label(file);
        frame->source_index = static_cast<std::size_t>(position);
        ChunkPart chunk;
        chunk.owned_cells = grid.owned_cells(file.index);
        chunk.finish_cells = finish_in_place ? grid.chunk_cells : 0;
        frame->chunk = std::move(chunk);
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
                      const InputDecisions& decided, std::size_t in_flight, bool finish_in_place,
                      const std::string& name, const std::function<void(const FramePtr&)>& sink) {
  long long position = 0;
  const auto n = static_cast<long long>(files.size());
  mesh_chunk_files(
      files, [&] { return position < n ? position++ : -1LL; }, grid, rows, config, decided,
      in_flight, finish_in_place, name, sink);
}

bool report_chunk_frame(const Frame& frame, ChunkedReport& report) {
  report.timings.insert(report.timings.end(), frame.timings.begin(), frame.timings.end());
  if (!frame.ok()) {
    report.failed.push_back(frame.name + ": " + frame.error);
    return false;
  }
  if (frame.chunk && frame.chunk->finish_cells > 0) {
    report.rim_trimmed += frame.rim_trimmed;
    chunked_add_optimize(report.optimize, frame.optimize);
  }
  return true;
}

void collect_chunk_frame(Frame& frame, chunk::MeshStitcher& stitcher, ChunkedReport& report) {
  if (!report_chunk_frame(frame, report)) return;
  std::vector<std::uint8_t> flags = chunk_vertex_flags(frame);
  stitcher.add(std::move(frame.mesh), std::move(flags));
  frame.mesh = TriangleMesh{};
  frame.chunk.reset();
}

chunk::MeshStitcher chunk_stitcher(float voxel_size, int chunk_cells) {
  return chunk::MeshStitcher(voxel_size, chunk_cells, kFeatureFlag);
}

std::vector<std::uint8_t> chunk_vertex_flags(const Frame& frame) {
  if (!frame.chunk) return {};
  const ChunkPart& chunk = *frame.chunk;
  const std::size_t n = frame.mesh.vertices.size();
  const bool beyond = chunk.beyond_data.size() == n, features = chunk.feature_vertices.size() == n;
  if (!beyond && !features) return {};
  std::vector<std::uint8_t> flags(n, 0);
  for (std::size_t v = 0; v < n; ++v)
    flags[v] =
        static_cast<std::uint8_t>((beyond && chunk.beyond_data[v] ? kBeyondDataFlag : 0) |
                                  (features && chunk.feature_vertices[v] ? kFeatureFlag : 0));
  return flags;
}

TriangleMesh finish_chunked_mesh(chunk::MeshStitcher& stitcher, const ReconstructionConfig& config,
                                 float voxel_size, ChunkedReport& report,
                                 const std::function<void(const std::string&)>& on_step,
                                 bool finished_in_place, int chunk_cells) {
  report.clock.begin("stitch", true);
  std::vector<std::uint8_t> flags;
  TriangleMesh joined = stitcher.stitch(&report.seam_vertices, &flags);
  return finish_joined_mesh(std::move(joined), flags, config, voxel_size, report, on_step,
                            finished_in_place, chunk_cells);
}

TriangleMesh finish_joined_mesh(TriangleMesh joined, const std::vector<std::uint8_t>& flags,
                                const ReconstructionConfig& config, float voxel_size,
                                ChunkedReport& report,
                                const std::function<void(const std::string&)>& on_step,
                                bool finished_in_place, int chunk_cells) {
  std::vector<std::uint8_t> beyond(flags.size()), features(flags.size());
  for (std::size_t v = 0; v < flags.size(); ++v) {
    beyond[v] = (flags[v] & kBeyondDataFlag) ? 1 : 0;
    features[v] = (flags[v] & kFeatureFlag) ? 1 : 0;
  }
  if (finished_in_place) {  // the chunks did the rest; what spans a seam is done here
    report.clock.begin("finish", true);
    chunk::finish_seams(joined, features, voxel_size, chunk_cells);
    report.clock.end();
    return joined;
  }
  if (std::find(features.begin(), features.end(), 1) != features.end()) {
    // Extended marching cubes' flips, as one process makes them over its whole mesh; the
    // vertex normals then follow the flipped fans, as extraction computes them after its flips.
    flip_edges_between_features(joined, features);
    if (!joined.normals.empty()) compute_vertex_normals(joined);
  }
  if (!beyond.empty() && config.max_rim_voxels > 0.0f) {
    std::vector<std::uint32_t> kept;
    joined = trim_rim(joined, beyond, &report.rim_trimmed, &kept);
    std::vector<std::uint8_t> moved(kept.size());
    for (std::size_t v = 0; v < kept.size(); ++v) moved[v] = features[kept[v]];
    features = std::move(moved);
  }
  report.clock.begin("finish", true);
  OptimizeConfig optimize = optimize_config_for_voxel(config, voxel_size);
  if (on_step) optimize.on_step = [&](OptimizeStep step) { on_step(optimize_step_name(step)); };
  // The feature vertices seed the steps' graph as one process's extraction seeds them.
  TriangleMesh mesh = optimize_mesh(joined, optimize, &report.optimize, features);
  report.clock.end();
  return mesh;
}

namespace {

// What reconstruct_chunked() and reconstruct_chunked_to_ply() start from: the input partitioned
// (partition_input() into `files`; the report's input and chunk fields and result.origin
// filled; `store`'s destructor removes the files) and the progress callback.
struct ChunkedRun {
  std::function<void(const std::string&)> on_stage;
  ChunkedResult result;
  std::vector<chunk::ChunkFile> files;
  std::unique_ptr<chunk::ChunkStore> store;
  std::size_t done = 0;  // chunks delivered

  void tell(const std::string& what) const {
    if (on_stage) on_stage(what);
  }
  // One more chunk delivered: "chunk i/n".
  void chunk_done() {
    ++done;
    tell("chunk " + std::to_string(done) + "/" + std::to_string(files.size()));
  }
};

ChunkedRun start_chunked_run(const std::string& path, const std::string& columns,
                             const ReconstructionConfig& config, const ChunkingConfig& chunking,
                             const std::function<void(const std::string&)>& on_stage) {
  ChunkedRun run;
  run.on_stage = on_stage;
  run.tell("partition");
  ChunkedReport& report = run.result.report;
  run.store =
      partition_input(path, columns, config, chunking, run.files, report.decided, &report.clock);
  report.voxel_size = report.decided.voxel_size;
  report.chunk_cells = run.store->grid().chunk_cells;
  report.chunks = run.files.size();
  report.points = run.store->points_read();
  report.dropped = run.store->points_dropped();
  report.rows_written = run.store->rows_written();
  for (const chunk::ChunkFile& f : run.files)
    report.max_chunk_points = std::max(report.max_chunk_points, f.points);
  run.result.origin = run.store->rows().origin;
  return run;
}

}  // namespace

ChunkedResult reconstruct_chunked(const std::string& path, const std::string& columns,
                                  const ReconstructionConfig& config,
                                  const ChunkingConfig& chunking,
                                  const std::function<void(const std::string&)>& on_stage) {
  ChunkedRun run = start_chunked_run(path, columns, config, chunking, on_stage);
  ChunkedResult& result = run.result;
  ChunkedReport& report = result.report;
  const float voxel = report.voxel_size;

  report.clock.begin("chunks", false);
  chunk::MeshStitcher stitcher = chunk_stitcher(voxel, report.chunk_cells);
  const bool in_place = finishes_in_place(config, chunking);
  mesh_chunk_files(run.files, run.store->grid(), run.store->rows(), config, report.decided,
                   chunking.in_flight, in_place, path, [&](const FramePtr& frame) {
                     run.chunk_done();
                     collect_chunk_frame(*frame, stitcher, report);
                   });
  report.clock.end();

  run.tell("stitch");
  result.mesh =
      finish_chunked_mesh(stitcher, config, voxel, report, on_stage, in_place, report.chunk_cells);
  report.output_vertices = result.mesh.vertices.size();
  report.output_triangles = result.mesh.triangles.size();
  return std::move(result);
}

bool streams_output(const std::string& output, const ReconstructionConfig& config,
                    const ChunkingConfig& chunking) {
  return io::lower_extension(output) == ".ply" && finishes_in_place(config, chunking);
}

ChunkedResult reconstruct_chunked_to_ply(const std::string& path, const std::string& columns,
                                         const ReconstructionConfig& config,
                                         const ChunkingConfig& chunking, const std::string& output,
                                         const std::string& tiles_dir,
                                         const std::function<void(const std::string&)>& on_stage) {
  if (!streams_output(output, config, chunking)) {
    ChunkedResult result = reconstruct_chunked(path, columns, config, chunking, on_stage);
    ChunkedReport& r = result.report;
    if (!result.mesh.empty()) {
      if (on_stage) on_stage("write");
      r.clock.begin("write", true);
      io::write_mesh(output, result.mesh, result.origin);
      if (!tiles_dir.empty()) {  // cut from the whole mesh
        if (on_stage) on_stage("tiles");
        r.clock.begin("tiles", false);  // the tiles and their levels in parallel
        const chunk::ChunkGrid grid{r.voxel_size, r.chunk_cells, 0};
        const std::vector<chunk::MeshTile> split = chunk::split_into_tiles(result.mesh, grid);
        chunk::write_tiles(tiles_dir, split, grid, result.origin, progressive_levels());
        r.tiles = split.size();
      }
      r.clock.end();
    }
    return result;
  }
  ChunkedRun run = start_chunked_run(path, columns, config, chunking, on_stage);
  ChunkedResult& result = run.result;
  ChunkedReport& report = result.report;
  const std::vector<chunk::ChunkFile>& files = run.files;
  const std::unique_ptr<chunk::ChunkStore>& store = run.store;
  const float voxel = report.voxel_size;
  const int cells = report.chunk_cells;

  // Each chunk's seam summarized and its mesh spilled as it arrives: the chunks in flight are
  // all that is held.
  report.clock.begin("chunks", false);
  std::vector<chunk::ChunkSeams> seams;
  std::vector<Eigen::Vector3i> chunk_of;  // per seams entry: its chunk index (its tile)
  const auto spill_path = [&](std::size_t c) {
    return store->directory() + "/mesh_" + std::to_string(c) + ".bin";
  };
  mesh_chunk_files(files, store->grid(), store->rows(), config, report.decided, chunking.in_flight,
                   true, path, [&](const FramePtr& frame) {
                     run.chunk_done();
                     if (!report_chunk_frame(*frame, report)) return;
                     chunk::SpilledMesh spilled;
                     spilled.flags = chunk_vertex_flags(*frame);
                     spilled.mesh = std::move(frame->mesh);
                     frame->mesh = TriangleMesh{};
                     frame->chunk.reset();
                     chunk_of.push_back(files[frame->source_index].index);
                     seams.push_back(chunk::summarize_seams(spilled.mesh, spilled.flags, voxel,
                                                            cells, kFeatureFlag));
                     spilled.vertex_piece = std::move(seams.back().vertex_piece);
                     seams.back().vertex_piece = {};
                     chunk::write_mesh_spill(spill_path(seams.size() - 1), spilled);
                   });
  report.clock.end();

  run.tell("stitch");
  report.clock.begin("stitch", true);  // the weld's plan, from the seam summaries alone
  std::vector<const chunk::ChunkSeams*> summaries;
  summaries.reserve(seams.size());
  for (const chunk::ChunkSeams& s : seams) summaries.push_back(&s);
  const chunk::WeldPlan plan = chunk::plan_weld(summaries);
  report.seam_vertices = plan.merged;
  report.output_vertices = plan.vertices;
  report.output_triangles = plan.triangles;
  if (plan.triangles == 0) {
    report.clock.end();
    return std::move(result);  // nothing to write; the caller reports the empty mesh
  }

  // Each chunk welded (in parallel, a few at a time) and written in chunk order.
  run.tell("write");
  report.clock.begin("write", true);
  chunk::StreamedChunkOutput out(output, plan, result.origin, voxel, cells, kFeatureFlag);
  struct Welded {
    TriangleMesh part;
    std::vector<std::uint8_t> flags;
    std::size_t index = 0;
  };
  std::size_t next = 0;
  const std::size_t threads = static_cast<std::size_t>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  tbb::parallel_pipeline(
      std::max<std::size_t>(2, threads),
      tbb::make_filter<void, std::size_t>(tbb::filter_mode::serial_in_order,
                                          [&](tbb::flow_control& fc) -> std::size_t {
                                            if (next == seams.size()) fc.stop();
                                            return next++;
                                          }) &
          tbb::make_filter<std::size_t, std::shared_ptr<Welded>>(
              tbb::filter_mode::parallel,
              [&](std::size_t c) {
                chunk::SpilledMesh spilled = chunk::read_mesh_spill(spill_path(c));
                std::remove(spill_path(c).c_str());
                chunk::ChunkSeams& s = seams[c];
                s.vertex_piece = std::move(spilled.vertex_piece);
                auto welded = std::make_shared<Welded>();
                welded->index = c;
                welded->part =
                    chunk::weld_chunk(spilled.mesh, spilled.flags, s, plan, c, &welded->flags);
                s = chunk::ChunkSeams{};
                return welded;
              }) &
          tbb::make_filter<std::shared_ptr<Welded>, void>(
              tbb::filter_mode::serial_in_order, [&](const std::shared_ptr<Welded>& w) {
                out.add(w->part, w->flags, chunk_of[w->index]);
              }));
  report.clock.begin("finish", true);  // the seams: flips and normals, their rows rewritten
  out.finish_seams();
  if (!tiles_dir.empty()) {
    report.clock.begin("tiles", true);  // each chunk's finished rows read back
    report.tiles = out.write_tiles(tiles_dir, progressive_levels());
  }
  out.commit();
  report.clock.end();
  return std::move(result);
}

}  // namespace meshflow
