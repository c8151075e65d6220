// `meshflow run` (mesh a recorded sequence) and `meshflow profile` (where the time goes).

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "graph/fusion_pipeline.h"
#include "graph/merged_scans.h"
#include "graph/sequence_runner.h"
#include "nodes/compress/compressed_mesh.h"
#include "nodes/compress/progressive_mesh.h"
#include "nodes/eval/vertex_quality.h"
#include "nodes/fusion/tsdf_map_file.h"
#include "nodes/fusion/tsdf_sampling.h"
#include "nodes/io/atomic_file.h"
#include "nodes/io/byte_buffer.h"
#include "nodes/io/mesh_writers.h"
#include "nodes/io/parse_util.h"
#include "options/json_report.h"
#include "runtime/error.h"
#include "runtime/threads.h"
#include "tools/cli_checks.h"
#include "tools/commands.h"
#include "tools/console.h"
#include "tools/fusion_breakdown.h"
#include "tools/pipeline_options.h"
#include "tools/progress.h"
#include "tools/report.h"
#include "tools/run_view.h"

namespace meshflow::cli {
namespace {

std::size_t selected_frames(const io::Sequence& seq, const SequenceArgument& a) {
  const std::size_t n = (seq.size() + a.every - 1) / a.every;
  return a.max_frames > 0 ? std::min(n, a.max_frames) : n;
}

// The stages' configuration from the command line, per-frame triangulation included.
ReconstructionConfig pipeline_config(const PipelineOptions& pipeline,
                                     const TriangulationOptions& triangulation) {
  ReconstructionConfig config = pipeline.config();
  triangulation.apply(config);
  return config;
}

// -v: one line per finished frame.
void print_frame_line(const Frame& f) {
  if (!f.ok()) return;
  double busy = 0.0;
  for (const StageRecord& r : f.timings) busy += r.end_s - r.start_s;
  const ComponentCounts& removed = f.triangulation.components;
  std::string components;
  if (removed.removed_components > 0)
    components = ", " + std::to_string(removed.removed_components) + " small components (" +
                 std::to_string(removed.removed_triangles) + " triangles) removed";
  detail("frame %zu   %s: %zu points -> %zu vertices, %zu triangles%s, %.1f ms in stages\n",
         f.source_index, f.name.c_str(), f.filter_counts.input, f.mesh.vertices.size(),
         f.mesh.triangles.size(), components.c_str(), 1e3 * busy);
}

// Per-frame triangulation: the smaller fans and small components removed over the frames.
struct RemovedComponents {
  ComponentCounts sum;
  FanRemovalCounts fans;
  void add(const Frame& f) {
    sum.components += f.triangulation.components.components;
    sum.removed_components += f.triangulation.components.removed_components;
    sum.removed_triangles += f.triangulation.components.removed_triangles;
    fans.vertices += f.triangulation.fans.vertices;
    fans.triangles += f.triangulation.fans.triangles;
  }
  nlohmann::json json(std::size_t min_triangles) const {
    return {{"components", sum.components},
            {"removed_components", sum.removed_components},
            {"removed_triangles", sum.removed_triangles},
            {"min_component", min_triangles},
            {"non_manifold_vertices", fans.vertices},
            {"removed_fan_triangles", fans.triangles}};
  }
  void print(std::size_t min_triangles) const {
    report("components %zu of %zu removed for having fewer than %zu triangles (%zu triangles)\n",
           sum.removed_components, sum.components, min_triangles, sum.removed_triangles);
    if (fans.vertices > 0)
      report(
          "manifold   %zu non-manifold vertices repaired (%zu triangles of their smaller fans "
          "removed)\n",
          fans.vertices, fans.triangles);
  }
};

// The failed frames of a run: each printed to stderr as it arrives and kept for --json's
// "failed_frames" (index, file, stage, message).
class FailedFrames {
 public:
  void add(const Frame& f) {
    std::fprintf(stderr, "meshflow: frame %zu (%s) failed in %s: %s\n", f.source_index,
                 f.name.c_str(), f.failed_stage.c_str(), f.error.c_str());
    frames_.push_back({{"index", f.source_index},
                       {"file", f.name},
                       {"stage", f.failed_stage},
                       {"message", f.error}});
  }
  const nlohmann::json& json() const { return frames_; }

 private:
  nlohmann::json frames_ = nlohmann::json::array();
};

// The human report of a run, or with --json the document (with `extra` fields merged in).
void print_run_summary(const io::Sequence& seq, const SequenceRunStats& stats, int threads,
                       std::size_t in_flight, const FailedFrames& failed,
                       const nlohmann::json& extra = {}) {
  if (console().json) {
    nlohmann::json doc = options::run_json(seq.description(), stats, threads, in_flight);
    doc["failed_frames"] = failed.json();
    if (extra.is_object()) doc.update(extra);
    return print_json(doc);
  }
  report("sequence   %s\n", seq.description().c_str());
  report(
      "frames     %zu ok, %zu failed%s; %.3f s wall, %.2f frames/s on %d thread%s, %zu in flight\n",
      stats.frames_ok, stats.frames_failed, stats.stopped_early ? " (stopped: --strict)" : "",
      stats.wall_s, stats.frames_per_second(), threads, threads == 1 ? "" : "s", in_flight);
  report("%s", format_stage_table(stats.stages.summaries(), stats.wall_s).c_str());
}

struct RunOptions {
  PipelineOptions pipeline;
  TriangulationOptions triangulation;
  SequenceArgument sequence;
  std::string output_dir;
  bool merged = false;       ///< one surface from all frames
  bool concatenate = false;  ///< the per-frame meshes in one file
  bool quality = false;      ///< per-frame PLYs get each vertex's distance to the frame's points
  bool strict = false;
  bool fuse = false;
  std::size_t mesh_every = 0;
  float truncation_voxels = 4.0f;
  float behind_voxels = TsdfConfig{}.behind_voxels;
  std::string integrator = "projective";  ///< --integrator
  bool no_carve = false;                  ///< --no-carve
  float min_weight = 0.0f;
  std::string save_map, load_map;
  std::string compress;          ///< --compress method ("" = PLY outputs)
  ServeOptions serve;            ///< --serve: show the run in a browser
  double rate_hz = 0.0;          ///< --rate: paced replay (SequenceRunOptions::rate_hz)
  std::string policy = "queue";  ///< --policy: queue or realtime (drop_late) with --rate
  std::size_t loops = 1;         ///< --loops
};

// With --rate: the replay's settings and what it dropped, for the summary (--json), and a line
// of the text report.
nlohmann::json replay_json(const RunOptions& o, const SequenceRunStats& stats) {
  if (o.rate_hz <= 0.0) return nullptr;
  report("replay     %.1f Hz, policy %s, %zu loop%s: %zu frames dropped\n", o.rate_hz,
         o.policy.c_str(), o.loops, o.loops == 1 ? "" : "s", stats.frames_dropped);
  return {{"rate_hz", o.rate_hz},
          {"policy", o.policy},
          {"loops", o.loops},
          {"frames_dropped", stats.frames_dropped}};
}

// The frame feeding of run's per-frame and fused modes (--every, --max-frames, --strict,
// --rate, --loops).
SequenceRunOptions sequence_run_options(const RunOptions& o) {
  SequenceRunOptions r{o.sequence.every, o.sequence.max_frames, o.strict};
  r.rate_hz = o.rate_hz;
  r.drop_late = o.policy == "realtime";
  r.loops = o.loops;
  return r;
}

// The graph's threads: --threads (every core when 0), one more with --rate, whose source sleeps
// on one of them until each frame's release.
int run_threads(const RunOptions& o) {
  if (o.rate_hz <= 0.0) return o.pipeline.threads;
  return (o.pipeline.threads > 0 ? o.pipeline.threads : hardware_threads()) + 1;
}

// -o of run names a directory; a mesh file's name there is a usage error, not a directory
// called "out.ply".
std::string output_directory_check(const std::string& path) {
  const std::string ext = io::lower_extension(path);
  for (const char* mesh : {".ply", ".obj", ".stl", ".off", ".glb", ".mfc"}) {
    if (ext == mesh)
      return "run writes its meshes into a directory (frame_NNNNNN.ply, merged.ply, fused.ply, "
             "...); '" +
             path + "' is a mesh file's name: give a directory";
  }
  return "";
}

// The output directory of a run: created (with its missing parents) before the first frame, so
// an unwritable place fails before any work, and removed again when the run leaves it empty
// (a failed run leaves no empty directories behind).
class OutputDirectory {
 public:
  explicit OutputDirectory(const std::string& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    fs::path deepest = fs::path(path).lexically_normal();
    if (!deepest.has_filename()) deepest = deepest.parent_path();  // "dir/"
    for (fs::path p = deepest; !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
      created_.push_back(p);
      if (p == p.parent_path()) break;
    }
    fs::create_directories(path, ec);
    if (ec || !fs::is_directory(path)) {
      remove_if_empty();
      throw Error(path, "",
                  "cannot create output directory: " +
                      (ec ? ec.message() : std::string("a file of that name exists")));
    }
    try {
      io::check_output_writable((fs::path(path) / "meshflow_probe").string());
    } catch (...) {
      remove_if_empty();
      throw;
    }
  }
  ~OutputDirectory() { remove_if_empty(); }
  OutputDirectory(const OutputDirectory&) = delete;
  OutputDirectory& operator=(const OutputDirectory&) = delete;

 private:
  // The directories this run created, deepest first, while they are empty.
  void remove_if_empty() noexcept {
    std::error_code ec;
    for (const std::filesystem::path& p : created_) {
      if (!std::filesystem::is_empty(p, ec) || ec) return;
      std::filesystem::remove(p, ec);
    }
    created_.clear();
  }

  std::vector<std::filesystem::path> created_;
};

// The sequence, and the output directory (which removes itself when the run leaves it empty).
std::pair<std::unique_ptr<io::Sequence>, std::unique_ptr<OutputDirectory>> open_output(
    const RunOptions& o) {
  auto sequence = open_sequence_argument(o.sequence);
  return {std::move(sequence), std::make_unique<OutputDirectory>(o.output_dir)};
}

// Writes DIR/STEM.ply, or with --compress DIR/STEM.mfc: `compressed` when the graph's compress
// stage made it, else the mesh compressed here (one mesh at the end of a run).
void write_run_mesh(const RunOptions& o, const std::string& stem, const TriangleMesh& mesh,
                    const Eigen::Vector3d& origin = Eigen::Vector3d::Zero(),
                    const std::vector<unsigned char>* compressed = nullptr,
                    const std::vector<io::VertexScalar>& scalars = {}) {
  const std::filesystem::path dir(o.output_dir);
  const MeshCompression method = compression_for(o.compress, "");
  if (method == MeshCompression::kNone)
    return io::write_ply((dir / (stem + ".ply")).string(), mesh, io::PlyEncoding::kBinary, origin,
                         scalars);
  const std::string path = (dir / (stem + ".mfc")).string();
  if (compressed != nullptr && !compressed->empty()) return io::write_file_bytes(path, *compressed);
  compress::CompressConfig config;
  config.origin_offset = origin;
  io::write_file_bytes(path, method == MeshCompression::kProgressive
                                 ? compress::compress_progressive(mesh, config)
                                 : compress::compress_mesh(mesh, config));
}

void finish_run(const SequenceRunStats& stats) {
  if (stats.stopped_early) throw std::runtime_error("stopped at the first failed frame (--strict)");
  if (stats.frames_ok == 0) throw std::runtime_error("no frame could be reconstructed");
}

// `meshflow run --fuse`: every frame into one TSDF map, fused.ply at the end (and
// fused_NNNNNN.ply after every --mesh-every frames).
void run_fusion(const RunOptions& o) {
  ThreadLimit limit(run_threads(o));
  const auto opened = open_output(o);
  const std::unique_ptr<io::Sequence>& sequence = opened.first;
  if (!o.save_map.empty()) io::check_output_writable(o.save_map);
  FusionConfig config;
  config.frames = o.pipeline.config();
  config.tsdf.voxel_size = o.pipeline.voxel > 0.0f ? o.pipeline.voxel : 0.01f;
  config.tsdf.truncation_voxels = o.truncation_voxels;
  config.tsdf.behind_voxels = std::min(o.behind_voxels, o.truncation_voxels);
  config.tsdf.integrator =
      o.integrator == "along-ray" ? TsdfIntegrator::kAlongRay : TsdfIntegrator::kProjective;
  config.tsdf.carve_free_space = !o.no_carve;
  config.tsdf.max_memory_bytes = config.frames.max_memory_bytes;
  config.mesh_every = o.mesh_every;
  config.min_weight = o.min_weight;
  const auto pipeline = o.load_map.empty()
                            ? std::make_unique<FusionPipeline>(config, o.sequence.in_flight)
                            : std::make_unique<FusionPipeline>(config, o.sequence.in_flight,
                                                               read_tsdf_map(o.load_map));
  const std::unique_ptr<RunView> view = start_run_view(o.serve, "meshflow run --fuse");
  if (view)
    pipeline->set_integration_observer(
        view->map_observer(config.tsdf.voxel_size, config.min_weight));
  FrameProgress progress(selected_frames(*sequence, o.sequence) * o.loops);
  std::size_t done = 0, written = 0;
  const std::filesystem::path dir(o.output_dir);
  const SequenceRunOptions run_options = sequence_run_options(o);
  FusionBreakdown breakdown;
  FailedFrames failed;
  const SequenceRunStats stats =
      run_sequence(*pipeline, *sequence, run_options, [&](const Frame& f) {
        progress.update(++done);
        if (view) view->frame(f, false);
        if (!f.ok()) return failed.add(f);
        breakdown.add(f);
        if (f.mesh.empty()) return;
        char name[64];
        std::snprintf(name, sizeof name, "fused_%06zu", f.source_index);
        write_run_mesh(o, name, f.mesh);
        ++written;
      });
  const double t0 = monotonic_seconds();
  TsdfExtractStats extraction;
  const TriangleMesh mesh = pipeline->extract_mesh(&extraction);
  const double extract_s = monotonic_seconds() - t0;
  std::vector<float> observations;  // --quality: the map's weight at each vertex
  if (!mesh.empty()) {
    if (o.quality) observations = tsdf_weights_at(pipeline->map(), mesh.vertices);
    write_run_mesh(o, "fused", mesh, Eigen::Vector3d::Zero(), nullptr,
                   o.quality ? std::vector<io::VertexScalar>{{"observations", observations}}
                             : std::vector<io::VertexScalar>{});
    ++written;
  }
  if (!o.save_map.empty()) write_tsdf_map(o.save_map, pipeline->map());
  const TsdfVolume& map = pipeline->map();
  nlohmann::json summary = {
      {"map",
       {{"blocks", map.block_count()},
        {"voxel", map.config().voxel_size},
        {"bytes", map.memory_bytes()}}},
      {"mesh", {{"vertices", mesh.vertices.size()}, {"triangles", mesh.triangles.size()}}},
      {"extract_ms", extract_s * 1e3},
      {"completeness", breakdown.json(extraction.cells)},
      {"files_written", written},
      {"output", o.output_dir}};
  if (o.quality) summary["observations"] = options::observations_json(observations);
  if (o.rate_hz > 0.0) summary["replay"] = replay_json(o, stats);
  if (pipeline->closing().ran) summary["close"] = options::close_json(pipeline->closing());
  print_run_summary(*sequence, stats, limit.threads(), o.sequence.in_flight, failed, summary);
  breakdown.print(extraction.cells);
  report("map        %zu blocks of 8^3 voxels at %.4f m, %.1f MB%s%s\n", map.block_count(),
         map.config().voxel_size, static_cast<double>(map.memory_bytes()) / 1e6,
         o.save_map.empty() ? "" : ", saved to ", o.save_map.c_str());
  report_closing(pipeline->closing());
  report("mesh       %zu vertices, %zu triangles, extracted in %.1f ms\n", mesh.vertices.size(),
         mesh.triangles.size(), extract_s * 1e3);
  if (o.quality) report_observations(observations, "the map's weight (frames) at each vertex");
  report("output     %zu mesh file%s in %s\n", written, written == 1 ? "" : "s",
         o.output_dir.c_str());
  if (view) {
    // The map's blocks make extract()'s mesh; the optimisation steps change it, so then the
    // page gets fused.ply's mesh as a whole too.
    view->map_result(pipeline->map());
    if (!config.frames.optimize.steps.empty()) view->result(mesh, Eigen::Vector3d::Zero(), {});
    view->finish_and_serve();
  }
  finish_run(stats);
}

// Appends `mesh` to `into`; normals and colours stay while every mesh so far had them.
void append_mesh(TriangleMesh& into, const TriangleMesh& mesh) {
  const auto offset = static_cast<std::uint32_t>(into.vertices.size());
  const auto append = [&](auto& to, const auto& from) {
    if (to.size() == into.vertices.size() && from.size() == mesh.vertices.size())
      to.insert(to.end(), from.begin(), from.end());
    else
      to.clear();
  };
  append(into.normals, mesh.normals);
  append(into.colors, mesh.colors);
  into.vertices.insert(into.vertices.end(), mesh.vertices.begin(), mesh.vertices.end());
  for (const Triangle& t : mesh.triangles)
    into.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
}

// `meshflow run --merged`: every frame prepared (read, filter, normals towards its own sensor)
// in a flow graph, the clouds joined in the world frame, one reconstruction of the whole.
void run_merged(const RunOptions& o) {
  ThreadLimit limit(o.pipeline.threads);
  const auto opened = open_output(o);
  const std::unique_ptr<io::Sequence>& sequence = opened.first;
  ReconstructionConfig config = o.pipeline.config();
  config.compression = compression_for(o.compress, "");
  ScanPreparationPipeline preparation(config, o.sequence.in_flight);
  const std::unique_ptr<RunView> view = start_run_view(o.serve, "meshflow run --merged");
  FrameProgress progress(selected_frames(*sequence, o.sequence) * o.loops);
  PointCloud joined;
  std::size_t done = 0;
  const SequenceRunOptions run_options{o.sequence.every, o.sequence.max_frames, o.strict};
  FailedFrames failed;
  const SequenceRunStats stats =
      run_sequence(preparation, *sequence, run_options, [&](const Frame& f) {
        progress.update(++done);
        if (view) view->frame(f, false);
        if (!f.ok()) return failed.add(f);
        detail("frame %zu   %s: %zu points, normals %s\n", f.source_index, f.name.c_str(),
               f.cloud.size(),
               f.kind == FrameKind::kDepthImage ? "from the image"
                                                : describe_normals(f.normals).c_str());
        append_scan(joined, f.cloud);
      });
  finish_run(stats);
  StepProgress steps;
  auto frame = std::make_shared<Frame>();
  frame->name = "merged";
  frame->cloud = std::move(joined);
  frame->on_stage = [&steps](const char* stage, const char* step) { steps.begin(stage, step); };
  ReconstructionPipeline pipeline(merged_pass_config(config), 1);
  const double t0 = monotonic_seconds();
  pipeline.run_frame(frame);
  throw_if_failed(*frame);
  const std::string output =
      (std::filesystem::path(o.output_dir) /
       (config.compression == MeshCompression::kNone ? "merged.ply" : "merged.mfc"))
          .string();
  write_run_mesh(o, "merged", frame->mesh, frame->origin, &frame->compressed);
  const double wall = monotonic_seconds() - t0;
  print_run_summary(*sequence, stats, limit.threads(), o.sequence.in_flight, failed,
                    {{"merged", options::frame_json(*frame, wall, limit.threads())},
                     {"files_written", 1},
                     {"output", output}});
  report_closing(frame->closing);
  report("merged     %zu points of %zu frames -> %zu vertices, %zu triangles in %.1f ms\n",
         frame->filter_counts.input, stats.frames_ok, frame->mesh.vertices.size(),
         frame->mesh.triangles.size(), 1e3 * wall);
  report("output     %s\n", output.c_str());
  if (view) {
    view->frame(*frame, false);  // the merged pass's stage timings
    view->result(frame->mesh, frame->origin,
                 config.compression == MeshCompression::kProgressive
                     ? frame->compressed
                     : std::vector<unsigned char>{});
    view->finish_and_serve();
  }
}

void run_run(const RunOptions& o) {
  if (o.fuse) return run_fusion(o);
  if (o.merged) return run_merged(o);
  ThreadLimit limit(run_threads(o));
  const auto opened = open_output(o);
  const std::unique_ptr<io::Sequence>& sequence = opened.first;
  ReconstructionConfig config = pipeline_config(o.pipeline, o.triangulation);
  if (!o.concatenate) config.compression = compression_for(o.compress, "");
  ReconstructionPipeline pipeline(config, o.sequence.in_flight, o.triangulation.enabled());
  const std::unique_ptr<RunView> view = start_run_view(o.serve, "meshflow run");
  FrameProgress progress(selected_frames(*sequence, o.sequence) * o.loops);
  TriangleMesh merged;
  std::size_t done = 0, written = 0;
  RemovedComponents removed;
  const SequenceRunOptions run_options = sequence_run_options(o);
  FailedFrames failed;
  const SequenceRunStats stats =
      run_sequence(pipeline, *sequence, run_options, [&](const Frame& f) {
        progress.update(++done);
        if (view) view->frame(f, true);
        if (!f.ok()) return failed.add(f);
        print_frame_line(f);
        removed.add(f);
        if (o.concatenate) return append_mesh(merged, f.mesh);
        char name[64];
        std::snprintf(name, sizeof name, "frame_%06zu", f.source_index);
        std::vector<io::VertexScalar> scalars;  // --quality: distances to the frame's points
        if (o.quality) {
          VertexSupport support = vertex_support(f.mesh.vertices, f.cloud.positions, f.voxel_size);
          scalars = {{"quality", std::move(support.distances)},
                     {"observations", std::move(support.observations)}};
        }
        write_run_mesh(o, name, f.mesh, f.origin, &f.compressed, scalars);
        ++written;
      });
  if (o.concatenate && !merged.empty()) {
    write_run_mesh(o, "concatenated", merged);
    written = 1;
  }
  nlohmann::json extra = {{"files_written", written}, {"output", o.output_dir}};
  if (o.rate_hz > 0.0) extra["replay"] = replay_json(o, stats);
  const std::size_t min_component = config.triangulation.min_component_triangles;
  if (o.triangulation.enabled()) extra["components"] = removed.json(min_component);
  print_run_summary(*sequence, stats, limit.threads(), o.sequence.in_flight, failed, extra);
  if (o.triangulation.enabled()) removed.print(min_component);
  report("output     %zu mesh file%s in %s\n", written, written == 1 ? "" : "s",
         o.output_dir.c_str());
  if (view) view->finish_and_serve();
  finish_run(stats);
}

struct ProfileOptions {
  PipelineOptions pipeline;
  TriangulationOptions triangulation;
  SequenceArgument sequence;
  std::string trace_path;
  std::string csv_path;
  std::string compress;  ///< --compress: time the compress stage too
};

void write_text(const std::string& path, const std::string& text) {
  io::AtomicOutputFile file(path);
  file.stream() << text;
  file.commit();
}

void run_profile(const ProfileOptions& o) {
  ThreadLimit limit(o.pipeline.threads);
  const auto sequence = open_sequence_argument(o.sequence);
  ReconstructionConfig config = pipeline_config(o.pipeline, o.triangulation);
  config.compression = compression_for(o.compress, "");
  ReconstructionPipeline pipeline(config, o.sequence.in_flight, o.triangulation.enabled());
  const SequenceRunOptions run_options{o.sequence.every, o.sequence.max_frames, false,
                                       !o.trace_path.empty()};
  FailedFrames failed;
  const SequenceRunStats stats =
      run_sequence(pipeline, *sequence, run_options, [&failed](const Frame& f) {
        if (!f.ok()) return failed.add(f);
        print_frame_line(f);
      });
  nlohmann::json files = nlohmann::json::object();
  if (!o.trace_path.empty()) files["trace"] = o.trace_path;
  if (!o.csv_path.empty()) files["csv"] = o.csv_path;
  print_run_summary(*sequence, stats, limit.threads(), o.sequence.in_flight, failed, files);
  const auto summaries = stats.stages.summaries();
  if (!o.trace_path.empty()) {
    write_text(o.trace_path, chrome_trace_json(stats.records));
    report("trace      %s (open in https://ui.perfetto.dev or chrome://tracing)\n",
           o.trace_path.c_str());
  }
  if (!o.csv_path.empty()) {
    write_text(o.csv_path, format_stage_csv(summaries, stats.wall_s));
    report("csv        %s\n", o.csv_path.c_str());
  }
}

}  // namespace

void add_run_options(CLI::App* cmd) {
  auto o = std::make_shared<RunOptions>();
  add_sequence_options(cmd, o->sequence);
  cmd->add_option("-o,--output", o->output_dir,
                  "Output directory (created if missing; not a mesh file's name)")
      ->required()
      ->check(CLI::Validator(output_directory_check, "DIR"));
  auto* per_frame = cmd->add_flag("--per-frame", "One mesh per frame, frame_NNNNNN.ply (default)");
  auto* merged = cmd->add_flag("--merged", o->merged,
                               "One surface of all frames (registered scans, posed depth frames): "
                               "each frame's normals towards its own sensor, then one "
                               "reconstruction in the world frame; merged.ply")
                     ->excludes(per_frame);
  auto* concatenate =
      cmd->add_flag("--concatenate", o->concatenate,
                    "The per-frame meshes side by side in one file, concatenated.ply")
          ->excludes(per_frame)
          ->excludes(merged);
  cmd->add_flag("--strict", o->strict, "Stop at the first bad frame (exit code 1)");
  cmd->add_option("--rate", o->rate_hz,
                  "Paced replay, frames per second: the n-th frame enters the graph no sooner "
                  "than n / HZ s after the start, as from a sensor; a slower graph queues the "
                  "frames (none dropped: the files are the same), and a frame's latency counts "
                  "from its scheduled release. The source waits on a graph thread of its own (one "
                  "more than --threads)")
      ->check(number_in(0.1, 10000))
      ->excludes(merged)
      ->excludes(concatenate);
  cmd->add_option("--policy", o->policy,
                  "With --rate: queue (every frame, late when the graph is slower than the rate) "
                  "or realtime (a late source skips to the newest frame due, dropping the older "
                  "ones: bounded latency, fewer frames in the result)")
      ->check(CLI::IsMember({"queue", "realtime"}))
      ->needs("--rate");
  cmd->add_option("--loops", o->loops,
                  "Feed the selected frames this many times over (per-frame files are "
                  "rewritten; a fused map integrates them again)")
      ->check(CLI::Range(std::size_t{1}, std::size_t{100000}))
      ->excludes(merged)
      ->excludes(concatenate);
  auto* quality =
      cmd->add_flag("--quality", o->quality,
                    "Per-frame PLYs: each vertex's distance to the frame's nearest point "
                    "(metres, after the filter stage) and the frame's points within one voxel of "
                    "it as the float vertex properties 'quality' and 'observations'; with --fuse: "
                    "fused.ply's 'observations', the map's accumulated weight at each vertex "
                    "(frames that saw it, at the default constant weighting)")
          ->excludes(merged)
          ->excludes(concatenate);
  add_compress_option(cmd, o->compress);
  quality->excludes("--compress");
  auto* fuse = cmd->add_flag("--fuse", o->fuse,
                             "Fuse depth frames (or organized Kinect-type clouds) into one TSDF "
                             "map (--voxel, default 0.01 m); writes fused.ply")
                   ->excludes(per_frame)
                   ->excludes(merged)
                   ->excludes(concatenate);
  cmd->add_option("--mesh-every", o->mesh_every,
                  "With --fuse: also write the map's mesh after every N frames")
      ->check(number_in(0, 1e9))
      ->needs(fuse);
  cmd->add_option("--truncation", o->truncation_voxels, "With --fuse: truncation in voxels")
      ->check(number_in(0, 1000, true))
      ->needs(fuse);
  cmd->add_option("--behind", o->behind_voxels,
                  "With --fuse: the least band behind each measured surface that a frame "
                  "updates, in voxels; it widens with the frame's depth noise up to --truncation "
                  "(= --truncation: the symmetric band of KinectFusion and Open3D)")
      ->check(number_in(0, 1000, true))
      ->needs(fuse);
  cmd->add_option("--integrator", o->integrator,
                  "With --fuse: how frames reach the voxels: projective (each voxel of a touched "
                  "block projected into the image; fastest) or along-ray (each pixel's ray walks "
                  "its band, pixels in one voxel merged as in voxblox; more accurate, about "
                  "2-2.6x slower)")
      ->check(CLI::IsMember({"projective", "along-ray"}))
      ->needs(fuse);
  cmd->add_flag("--no-carve", o->no_carve,
                "With --fuse: keep surface that later frames see through (by default a frame "
                "carves existing surface where it measured free space a truncation behind it: "
                "moved objects and stray surface leave the map)")
      ->needs(fuse);
  cmd->add_option("--min-weight", o->min_weight,
                  "With --fuse: extraction treats voxels of at most this accumulated weight as "
                  "unobserved (0 = all observed voxels; e.g. 2 = surface seen in 3 frames)")
      ->check(number_in(0, 1e6))
      ->needs(fuse);
  cmd->add_option("--save-map", o->save_map, "With --fuse: write the TSDF map to this file")
      ->needs(fuse);
  cmd->add_option("--load-map", o->load_map, "With --fuse: start from this TSDF map (resume a run)")
      ->needs(fuse);
  add_triangulation_options(cmd, o->triangulation);
  fuse->excludes("--triangulate");
  quality->excludes("--triangulate");
  merged->excludes("--triangulate");
  add_pipeline_options(cmd, o->pipeline);
  // --close fills the distance field of per-frame and merged reconstructions and the fused
  // map's (its final mesh); triangulated depth images have none.
  cmd->get_option("--close")->excludes("--triangulate");
  add_serve_options(cmd, o->serve);
  add_console_flags(cmd, true);
  cmd->callback([o] { run_run(*o); });
}

void add_profile_options(CLI::App* cmd) {
  auto o = std::make_shared<ProfileOptions>();
  add_sequence_options(cmd, o->sequence);
  cmd->add_option("--trace", o->trace_path,
                  "Write a Chrome trace-event JSON (Perfetto, chrome://tracing)");
  cmd->add_option("--csv", o->csv_path, "Write the stage table as CSV");
  add_compress_option(cmd, o->compress);
  add_triangulation_options(cmd, o->triangulation);
  add_pipeline_options(cmd, o->pipeline);
  add_console_flags(cmd, true);
  cmd->callback([o] { run_profile(*o); });
}

}  // namespace meshflow::cli
