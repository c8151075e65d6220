#include "options/json_report.h"

#include <cmath>

#include "nodes/eval/vertex_quality.h"
#include "nodes/extract/extract_surface.h"
#include "nodes/normals/normals.h"

namespace meshflow::options {

nlohmann::json distance_json(const DistanceStats& s) {
  return {{"mean", s.mean}, {"rms", s.rms}, {"median", s.median},
          {"p95", s.p95},   {"max", s.max}, {"samples", s.samples}};
}

nlohmann::json observations_json(const std::vector<float>& counts) {
  const ObservationStats s = observation_stats(counts);
  return {{"mean", s.mean},
          {"median", s.median},
          {"p5", s.p5},
          {"min", s.min},
          {"vertices", s.vertices}};
}

nlohmann::json topology_json(const MeshTopology& t) {
  return {{"edges", t.edges.edges},
          {"boundary_edges", t.edges.boundary_edges},
          {"non_manifold_edges", t.edges.non_manifold_edges},
          {"inconsistent_edges", t.edges.inconsistent_edges},
          {"boundary_loops", t.boundary_loops},
          {"degenerate_faces", t.degenerate_faces},
          {"watertight", t.edges.closed() && t.edges.inconsistent_edges == 0}};
}

nlohmann::json stages_json(const std::vector<StageSummary>& summaries) {
  nlohmann::json stages = nlohmann::json::array();
  for (const StageSummary& s : summaries) {
    stages.push_back({{"stage", s.stage},
                      {"calls", s.calls},
                      {"total_ms", 1e3 * s.total_s},
                      {"mean_ms", 1e3 * s.mean_s},
                      {"p50_ms", 1e3 * s.p50_s},
                      {"p95_ms", 1e3 * s.p95_s},
                      {"max_ms", 1e3 * s.max_s},
                      {"items", s.items}});
  }
  return stages;
}

namespace {

nlohmann::json normals_json(const Frame& f) {
  if (f.kind == FrameKind::kDepthImage) return {{"source", "image"}};
  const NormalsReport& r = f.normals;
  nlohmann::json n = {{"source", r.source == NormalSource::kInput ? "input" : "estimate"},
                      {"estimated", r.estimated}};
  if (r.estimated > 0) {
    n["orientation"] = orientation_name(r.orientation);
    n["kn"] = r.kn;
    n["median_variation"] = r.median_variation;
    n["sharp"] = r.sharp;
    if (r.orientation == NormalOrientation::kPropagate || r.orientation == NormalOrientation::kUp ||
        r.orientation == NormalOrientation::kDown) {
      n["components"] = r.components;
      n["flipped_by_vote"] = r.flipped_by_vote;
      n["side"] = side_name(r.side, r.side_axis);
      if (r.orientation == NormalOrientation::kPropagate) n["scene"] = scene_kind_name(r.scene);
    }
  }
  n["flipped"] = r.flipped;
  return n;
}

}  // namespace

nlohmann::json optimize_json(const OptimizeReport& report) {
  nlohmann::json steps = nlohmann::json::array();
  for (const OptimizeStepReport& s : report.steps) {
    steps.push_back({{"step", optimize_step_name(s.step)},
                     {"triangles_in", s.triangles_in},
                     {"triangles_out", s.triangles_out},
                     {"ms", 1e3 * s.seconds},
                     {"skipped", s.skipped},
                     {"detail", s.detail}});
  }
  return steps;
}

nlohmann::json close_json(const CloseReport& c) {
  return {{"ran", c.ran},
          {"filled", c.filled},
          {"observed", c.observed},
          {"seen_empty", c.seen_empty},
          {"through", c.through},
          {"cells_added", c.cells_added},
          {"levels", c.levels},
          {"coarse_step", c.coarse_step},
          {"tiles", c.tiles},
          {"fill", close_fill_name(c.fill)},
          {"held_out", c.held_out},
          {"held_out_error_gradient", c.held_out_error_gradient},
          {"held_out_error_diffusion", c.held_out_error_diffusion},
          {"held_out_error_indicator", c.held_out_error_indicator}};
}

nlohmann::json frame_json(const Frame& f, double wall_s, int threads) {
  const FilterCounts& c = f.filter_counts;
  return {{"input", f.name},
          {"origin", {f.origin.x(), f.origin.y(), f.origin.z()}},
          {"points", c.input},
          {"filter",
           {{"non_finite", c.non_finite},
            {"cropped", c.cropped},
            {"merged", c.merged},
            {"outliers", c.outliers},
            {"isolated", c.isolated},
            {"sparse_clusters", c.sparse_clusters},
            {"output", c.output}}},
          {"normals", normals_json(f)},
          {"voxel", f.voxel_size},
          {"grid",
           {{"cells", f.grid.cells.size()},
            {"corners", f.grid.corners.size()},
            {"valid_corners", f.distance.valid_count()},
            {"disagreeing", f.distance.disagreeing},
            {"extrapolated", f.distance.extrapolated}}},
          {"close", close_json(f.closing)},
          {"mesh",
           {{"vertices", f.mesh.vertices.size()},
            {"triangles", f.mesh.triangles.size()},
            {"extract", extract_method_name(f.extract_method)},
            {"rim_trimmed", f.rim_trimmed},
            {"colors", !f.mesh.colors.empty()}}},
          {"optimize", optimize_json(f.optimize)},
          {"time_ms", 1e3 * wall_s},
          {"threads", threads},
          {"stages", stages_json(summarize_stages(f.timings))}};
}

nlohmann::json run_json(const std::string& sequence, const SequenceRunStats& stats, int threads,
                        std::size_t in_flight) {
  return {{"sequence", sequence},
          {"frames_ok", stats.frames_ok},
          {"frames_failed", stats.frames_failed},
          {"stopped_early", stats.stopped_early},
          {"wall_s", stats.wall_s},
          {"frames_per_second", stats.frames_per_second()},
          {"threads", threads},
          {"in_flight", in_flight},
          {"stages", stages_json(stats.stages.summaries())}};
}

nlohmann::json chunked_timing_json(const std::vector<chunk::RankTimes>& ranks, double wall_s) {
  nlohmann::json per_rank = nlohmann::json::array();
  for (const chunk::RankTimes& r : ranks) {
    nlohmann::json phases = nlohmann::json::array();
    for (const chunk::PhaseTime& p : r.phases)
      phases.push_back({{"phase", p.name},
                        {"wall_s", p.wall_s},
                        {"cpu_s", p.cpu_s},
                        {"work_s", p.work_s},
                        {"serial", p.serial}});
    per_rank.push_back({{"rank", r.rank},
                        {"chunks", r.chunks},
                        {"peak_rss_mib", static_cast<double>(r.peak_bytes) / (1024.0 * 1024.0)},
                        {"phases", phases}});
  }
  const chunk::SerialFraction f = chunk::serial_fraction(ranks, wall_s);
  nlohmann::json speedup = nlohmann::json::object();
  for (int workers : {2, 8, 32, 128}) speedup[std::to_string(workers)] = f.speedup(workers);
  return {{"ranks", per_rank},
          {"serial",
           {{"serial_s", f.serial_s},
            {"parallel_work_s", f.parallel_work_s},
            {"fraction", f.fraction},
            {"max_speedup", f.max_speedup},
            {"wall_share", f.wall_share},
            {"speedup", speedup}}}};
}

}  // namespace meshflow::options
