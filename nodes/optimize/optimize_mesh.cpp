#include "nodes/optimize/optimize_mesh.h"

#include <algorithm>
#include <cstdio>
#include <optional>
#include <sstream>

#include "nodes/decimate/qem_finding_features.h"
#include "nodes/optimize/planar/plane_intersections.h"
#include "runtime/error.h"
#include "runtime/half_edge_mesh.h"
#include "runtime/tracing.h"

namespace meshflow {
namespace {

constexpr OptimizeStep kAllSteps[] = {OptimizeStep::kClean,         OptimizeStep::kHoles,
                                      OptimizeStep::kPlanes,        OptimizeStep::kSharpen,
                                      OptimizeStep::kRetriangulate, OptimizeStep::kRemesh,
                                      OptimizeStep::kDecimate};

std::string format(const char* pattern, std::size_t a, std::size_t b = 0, std::size_t c = 0,
                   std::size_t d = 0) {
  char text[200];
  std::snprintf(text, sizeof text, pattern, a, b, c, d);
  return text;
}

// ", 3 regions not planar within 0.012 m left alone", or nothing when none was.
std::string not_planar_note(const PlanarSegmentation& s) {
  if (s.curved == 0) return "";
  char text[120];
  std::snprintf(text, sizeof text, ", %zu regions not planar within %.3g m left alone", s.curved,
                static_cast<double>(s.tolerance));
  return text;
}

// What one step hands to the next: the feature graph (detected once, then carried while the
// mesh stays what it is: clean and holes on a clean, closed mesh, and planes, which only moves
// vertices), the mesh maker's feature vertices (one byte per vertex while the steps keep the
// vertices: lines of their edges are no noise) and the planes
// step's plane tolerance (for retriangulate or sharpen right after it: measured again on the
// flattened mesh, a scan's roughness would be gone).
struct CarriedState {
  std::optional<MeshFeatures> features;
  std::vector<std::uint8_t> seed;
  float plane_tolerance = 0.0f;
};

// The feature graph of `mesh`, detected once while the topology lasts (from the seed while
// there is one for these vertices); `around` (optional): vertex_triangles(mesh), when the step
// has it.
const MeshFeatures& carried_features(const TriangleMesh& mesh, const OptimizeConfig& config,
                                     CarriedState& carried,
                                     const VertexTriangles* around = nullptr) {
  if (!carried.features) {
    const std::vector<std::uint8_t>* seed = carried.seed.empty() ? nullptr : &carried.seed;
    const float angle = config.feature_angle_deg, length = config.feature_min_length;
    if (around != nullptr)
      carried.features = detect_features(mesh, *around, seed, angle, length);
    else if (seed != nullptr)
      carried.features = detect_features(mesh, *seed, angle, length);
    else
      carried.features = detect_features(mesh, angle, length);
  }
  return *carried.features;
}

// The planar regions of `mesh`, held to the planes step's tolerance right after it.
PlanarSegmentation carried_segmentation(const TriangleMesh& mesh, const OptimizeConfig& config,
                                        const CarriedState& carried) {
  PlanarRegionConfig planes = config.planes;
  if (planes.fixed_tolerance == 0.0f) planes.fixed_tolerance = carried.plane_tolerance;
  return grow_planar_regions(HalfEdgeMesh(mesh), planes);
}

// The bytes of `held` that apply: one per held vertex, or none without `held`.
std::vector<std::uint8_t> held_mask(const HeldVertices* held) {
  std::vector<std::uint8_t> mask;
  if (held == nullptr) return mask;
  mask.resize(held->flags.size());
  for (std::size_t v = 0; v < mask.size(); ++v)
    mask[v] = (held->flags[v] & held->held_bits) != 0 ? 1 : 0;
  return mask;
}

// `flags` (one per vertex of the mesh clean_mesh() received) for the vertices it kept (`kept`,
// one input index per output vertex); none when `kept` does not describe `out` (split vertices).
std::vector<std::uint8_t> kept_flags(const std::vector<std::uint8_t>& flags,
                                     const std::vector<std::uint32_t>& kept,
                                     const TriangleMesh& out) {
  std::vector<std::uint8_t> result;
  if (kept.size() != out.vertices.size()) return result;
  result.resize(kept.size());
  for (std::size_t v = 0; v < kept.size(); ++v) result[v] = flags[kept[v]];
  return result;
}

TriangleMesh clean_step(const TriangleMesh& mesh, const OptimizeConfig& config,
                        OptimizeReport& report, CarriedState& carried, OptimizeStepReport& step,
                        HeldVertices* held = nullptr) {
  const std::vector<std::uint8_t> mask = held_mask(held);
  std::vector<std::uint32_t> kept;
  const bool follow = held != nullptr || !carried.seed.empty();
  TriangleMesh out = clean_mesh(mesh, config.cleanup, &report.cleanup, held ? &mask : nullptr,
                                follow ? &kept : nullptr);
  if (held != nullptr) held->flags = kept_flags(held->flags, kept, out);
  if (!carried.seed.empty()) carried.seed = kept_flags(carried.seed, kept, out);
  const CleanupReport& c = report.cleanup;
  step.detail =
      format("removed %zu degenerate/duplicate, %zu in %zu small components",
             c.degenerate_triangles + c.duplicate_triangles, c.removed_component_triangles,
             c.removed_components) +
      (c.split_vertices > 0 ? format(", %zu non-manifold vertices split", c.split_vertices)
                            : format(", %zu non-manifold vertices repaired (%zu triangles of their "
                                     "smaller fans removed)",
                                     c.non_manifold_vertices, c.removed_fan_triangles));
  return out;
}

TriangleMesh holes_step(const TriangleMesh& mesh, const OptimizeConfig& config,
                        CarriedState& carried, OptimizeStepReport& step,
                        HeldVertices* held = nullptr) {
  HoleFillingReport r;
  HoleFillingConfig holes = config.holes;
  holes.feature_angle_deg = config.feature_angle_deg;
  holes.feature_min_length = config.feature_min_length;
  const std::vector<std::uint8_t> mask = held_mask(held);
  // The graph carried from an earlier step on this mesh, else the maker's feature vertices: the
  // fills continue the lines the later steps keep, nothing detected twice.
  HoleFeatures known;
  if (carried.features) known.graph = &*carried.features;
  if (!carried.seed.empty()) known.marks = &carried.seed;
  TriangleMesh out = fill_holes(mesh, holes, &r, held ? &mask : nullptr, known);
  if (held != nullptr) held->flags.resize(out.vertices.size(), 0);  // added vertices: none
  if (!carried.seed.empty()) carried.seed.resize(out.vertices.size(), 0);
  step.detail = format("%zu holes filled (+%zu triangles), %zu larger than allowed, %zu outlines",
                       r.filled, r.added_triangles, r.too_large, r.outer_borders);
  if (r.not_fillable > 0) step.detail += format(", %zu not fillable", r.not_fillable);
  if (r.centre_vertices > 0)
    step.detail += format(", %zu fanned from a new centre vertex", r.centre_vertices);
  if (r.along_features > 0) step.detail += format(", %zu along feature lines", r.along_features);
  if (r.held_open > 0) step.detail += format(", %zu through held (seam) vertices", r.held_open);
  return out;
}

TriangleMesh planes_step(const TriangleMesh& mesh, const OptimizeConfig& config,
                         CarriedState& carried, OptimizeStepReport& step) {
  HalfEdgeMesh h(mesh);
  const PlanarSegmentation s = grow_planar_regions(h, config.planes);
  const std::size_t moved = project_onto_planes(h, s, config.planes.max_projection);
  // Feature vertices onto the lines and corners where their regions' planes meet, no farther
  // than a few plane tolerances (an edge's vertices lie within one of each plane): the
  // tolerance asked for, not the tighter one a smooth mesh's regions are held to (an exact
  // extraction's edge vertices lie up to a few hundredths of a voxel off its exact planes).
  const MeshFeatures& features = carried_features(mesh, config, carried);
  const float base = std::max(s.tolerance, config.planes.max_deviation);
  float limit = base > 0.0f ? 4.0f * base : 0.0f;
  if (config.planes.max_projection > 0.0f)
    limit =
        limit > 0.0f ? std::min(limit, config.planes.max_projection) : config.planes.max_projection;
  const PlaneIntersectionReport meet = project_onto_plane_intersections(h, s, features, limit);
  std::size_t counts[4] = {0, 0, 0, 0};
  for (const PlanarRegion& r : s.regions) ++counts[static_cast<int>(r.kind)];
  step.detail =
      format("%zu planar regions (%zu floor, %zu ceiling, %zu wall)", s.regions.size(), counts[0],
             counts[1], counts[2]) +
      format(", %zu vertices projected, %zu feature vertices onto lines, %zu onto corners", moved,
             meet.to_line, meet.to_corner);
  step.detail += not_planar_note(s);
  TriangleMesh out = mesh;  // same topology: only positions change
  for (std::uint32_t v = 0; v < out.vertices.size(); ++v) out.vertices[v] = h.position(v);
  // A scan's tolerance goes on to the next step (its flattened mesh has lost the noise); a
  // smooth mesh's regions are grown there at the flattened mesh's own tighter one (measured:
  // the chamfered cube's planar list 10x the raw p95 with the tolerance carried, 1.0x without).
  if (s.tolerance >= config.planes.max_deviation) carried.plane_tolerance = s.tolerance;
  return out;
}

TriangleMesh sharpen_step(const TriangleMesh& mesh, const OptimizeConfig& config,
                          CarriedState& carried, OptimizeStepReport& step) {
  const PlanarSegmentation s = carried_segmentation(mesh, config, carried);
  SharpEdgeReport r;
  TriangleMesh out = sharpen_creases(mesh, s, config.sharpen, &r);
  step.detail = format("%zu creases: %zu vertices onto planes, %zu onto lines, %zu onto corners",
                       r.creases, r.to_plane, r.to_line, r.to_corner) +
                format(", %zu edges cut", r.split_edges);
  return out;
}

TriangleMesh retriangulate_step(const TriangleMesh& mesh, const OptimizeConfig& config,
                                CarriedState& carried, OptimizeStepReport& step) {
  const PlanarSegmentation s = carried_segmentation(mesh, config, carried);
  RetriangulationReport r;
  RetriangulationConfig retriangulation = config.retriangulation;
  retriangulation.feature_angle_deg = config.feature_angle_deg;
  retriangulation.feature_min_length = config.feature_min_length;
  const MeshFeatures* features = config.feature_angle_deg < 180.0f && !s.regions.empty()
                                     ? &carried_features(mesh, config, carried)
                                     : nullptr;
  TriangleMesh out = retriangulate_regions(mesh, s, retriangulation, &r, features);
  step.detail = format("%zu of %zu regions retriangulated (-%zu +%zu triangles)", r.retriangulated,
                       r.regions, r.removed_faces, r.added_faces) +
                not_planar_note(s) +
                format(", %zu of %zu contour vertices dropped", r.dropped_contour_vertices,
                       r.contour_vertices);
  char deviation[64];
  std::snprintf(deviation, sizeof deviation, " (within %.4f m)", r.max_contour_deviation);
  step.detail += deviation;
  return out;
}

TriangleMesh remesh_step(const TriangleMesh& mesh, const OptimizeConfig& config,
                         CarriedState& carried, OptimizeStepReport& step) {
  AdaptiveRemeshReport r;
  AdaptiveRemeshConfig remesh = config.remesh;
  remesh.feature_angle_deg = config.feature_angle_deg;
  remesh.feature_min_length = config.feature_min_length;
  TriangleMesh out = adaptive_remesh(mesh, remesh, &r, &carried_features(mesh, config, carried));
  step.detail = format("%zu -> %zu vertices (%zu splits, %zu collapses", r.vertices_in,
                       r.vertices_out, r.splits, r.collapses) +
                format(
                    ", %zu flips; %zu sharp edges, %zu corners kept, %zu feature vertices "
                    "snapped)",
                    r.flips, r.sharp_edges_in, r.corners, r.snapped);
  char lengths[120];
  std::snprintf(lengths, sizeof lengths, ", target edges %.4f-%.4f m at tolerance %.4f m",
                r.min_target, r.max_target, r.tolerance);
  step.detail += lengths;
  return out;
}

TriangleMesh decimate_step(const TriangleMesh& mesh, const OptimizeConfig& config,
                           CarriedState& carried, OptimizeStepReport& step) {
  QemReport r;
  const MeshFeatures none;
  const MeshFeatures* found = &none;  // detected beside the decimation's setup
  TriangleMesh out = qem_decimate_finding_features(
      mesh,
      [&](const VertexTriangles& around) -> const QemFeatureEdges& {
        if (config.decimate_keeps_features)
          found = &carried_features(mesh, config, carried, &around);
        return found->edges;
      },
      config.decimate, &r);
  const MeshFeatures& features = *found;
  step.detail = format("%zu collapses in %zu passes", r.collapses, r.passes) +
                format("; refused %zu topology, %zu normal, %zu border", r.rejected_topology,
                       r.rejected_normal, r.rejected_border) +
                format(", %zu feature; %zu sharp edges, %zu corners kept", r.rejected_feature,
                       features.edges.size(), features.count(MeshFeatures::VertexKind::kCorner));
  return out;
}

}  // namespace

const char* optimize_step_name(OptimizeStep step) {
  switch (step) {
    case OptimizeStep::kClean:
      return "clean";
    case OptimizeStep::kHoles:
      return "holes";
    case OptimizeStep::kPlanes:
      return "planes";
    case OptimizeStep::kSharpen:
      return "sharpen";
    case OptimizeStep::kRetriangulate:
      return "retriangulate";
    case OptimizeStep::kRemesh:
      return "remesh";
    case OptimizeStep::kDecimate:
      break;
  }
  return "decimate";
}

std::vector<OptimizeStep> parse_optimize_steps(const std::string& list) {
  if (list == "default") return OptimizeConfig{}.steps;
  std::vector<OptimizeStep> steps;
  if (list == "none") return steps;
  std::stringstream in(list);
  std::string name;
  while (std::getline(in, name, ',')) {
    bool known = false;
    for (OptimizeStep s : kAllSteps)
      if (name == optimize_step_name(s)) {
        steps.push_back(s);
        known = true;
      }
    if (!known)
      throw Error("--optimize", "step '" + name + "'",
                  "expected default, none, or a comma-separated list of clean, holes, planes, "
                  "sharpen, retriangulate, remesh, decimate");
  }
  return steps;
}

namespace {

TriangleMesh run_steps(const TriangleMesh& mesh, const OptimizeConfig& given,
                       OptimizeReport* report, HeldVertices* held,
                       const std::vector<std::uint8_t>* feature_vertices) {
  OptimizeConfig config = given;
  if (config.feature_min_length == 0.0f)  // one scale for every step: the input's
    config.feature_min_length = kMinFeatureLineEdges * median_edge_length(mesh);
  OptimizeReport r;
  TriangleMesh current = mesh;
  CarriedState carried;
  if (feature_vertices != nullptr && feature_vertices->size() == mesh.vertices.size())
    carried.seed = *feature_vertices;
  if (held != nullptr && held->feature_bits != 0 &&
      std::any_of(held->flags.begin(), held->flags.end(),
                  [&](std::uint8_t f) { return (f & held->feature_bits) != 0; })) {
    carried.seed.resize(held->flags.size());
    for (std::size_t v = 0; v < held->flags.size(); ++v)
      carried.seed[v] = (held->flags[v] & held->feature_bits) != 0 ? 1 : 0;
  }
  const bool had_normals = !mesh.normals.empty() && mesh.normals.size() == mesh.vertices.size();
  for (OptimizeStep s : config.steps) {
    OptimizeStepReport step;
    step.step = s;
    step.triangles_in = current.triangles.size();
    if (config.on_step) config.on_step(s);
    const double start = monotonic_seconds();
    // clean and holes leave a clean, closed mesh as it was; then what was carried still holds.
    const std::vector<Triangle> before = s == OptimizeStep::kClean || s == OptimizeStep::kHoles
                                             ? current.triangles
                                             : std::vector<Triangle>{};
    const std::size_t vertices_before = current.vertices.size();
    try {
      switch (s) {
        case OptimizeStep::kClean:
          current = clean_step(current, config, r, carried, step, held);
          break;
        case OptimizeStep::kHoles:
          current = holes_step(current, config, carried, step, held);
          break;
        case OptimizeStep::kPlanes:
          current = planes_step(current, config, carried, step);
          break;
        case OptimizeStep::kSharpen:
          current = sharpen_step(current, config, carried, step);
          break;
        case OptimizeStep::kRetriangulate:
          current = retriangulate_step(current, config, carried, step);
          break;
        case OptimizeStep::kRemesh:
          current = remesh_step(current, config, carried, step);
          break;
        case OptimizeStep::kDecimate:
          current = decimate_step(current, config, carried, step);
          break;
      }
    } catch (const Error& e) {  // not a 2-manifold: this step cannot run, the mesh goes on
      step.skipped = true;
      step.detail = std::string("skipped: ") + e.what();
    }
    // The planes step moves vertices onto their planes and keeps the topology: its input's
    // feature graph goes on (its sharp edges stay sharp, only flatter elsewhere), so the planar
    // list detects once. The steps that change the topology end the graph and the seed.
    const bool same_mesh =
        step.skipped || s == OptimizeStep::kPlanes ||
        ((s == OptimizeStep::kClean || s == OptimizeStep::kHoles) &&
         current.vertices.size() == vertices_before && current.triangles == before);
    if (!same_mesh) carried.features.reset();
    const bool same_vertices = step.skipped || s == OptimizeStep::kClean ||
                               s == OptimizeStep::kHoles || s == OptimizeStep::kPlanes;
    if (!same_vertices) carried.seed.clear();
    if (s != OptimizeStep::kPlanes || step.skipped) carried.plane_tolerance = 0.0f;
    step.seconds = monotonic_seconds() - start;
    step.triangles_out = current.triangles.size();
    r.steps.push_back(std::move(step));
  }
  const bool moved = std::any_of(r.steps.begin(), r.steps.end(), [](const OptimizeStepReport& s) {
    return (s.step == OptimizeStep::kPlanes || s.step == OptimizeStep::kSharpen ||
            s.step == OptimizeStep::kRetriangulate || s.step == OptimizeStep::kRemesh) &&
           !s.skipped;
  });
  if (had_normals && (moved || current.normals.size() != current.vertices.size()))
    compute_vertex_normals(current);
  if (report != nullptr) *report = std::move(r);
  return current;
}

}  // namespace

TriangleMesh optimize_mesh(const TriangleMesh& mesh, const OptimizeConfig& config,
                           OptimizeReport* report) {
  return run_steps(mesh, config, report, nullptr, nullptr);
}

TriangleMesh optimize_mesh(const TriangleMesh& mesh, const OptimizeConfig& config,
                           OptimizeReport* report,
                           const std::vector<std::uint8_t>& feature_vertices) {
  return run_steps(mesh, config, report, nullptr, &feature_vertices);
}

TriangleMesh optimize_mesh(const TriangleMesh& mesh, const OptimizeConfig& config,
                           OptimizeReport* report, HeldVertices& held) {
  if (held.flags.size() != mesh.vertices.size())
    throw Error("optimize", "held",
                std::to_string(held.flags.size()) + " vertex flags for " +
                    std::to_string(mesh.vertices.size()) + " vertices; expected one per vertex");
  for (const OptimizeStep s : config.steps)
    if (s != OptimizeStep::kClean && s != OptimizeStep::kHoles)
      throw Error("optimize", optimize_step_name(s),
                  "cannot hold seam vertices fixed; only the clean and holes steps can (finish "
                  "such chunks after stitching)");
  if (config.cleanup.non_manifold_vertices == NonManifoldVertexRepair::kSplit)
    throw Error("optimize", "clean",
                "splitting non-manifold vertices cannot hold seam vertices fixed");
  return run_steps(mesh, config, report, &held, nullptr);
}

std::string format_optimize_report(const OptimizeReport& report) {
  std::string out;
  for (const OptimizeStepReport& s : report.steps) {
    char line[160];
    std::snprintf(line, sizeof line, "  %-9s %9zu -> %9zu triangles %8.1f ms  ",
                  optimize_step_name(s.step), s.triangles_in, s.triangles_out, 1e3 * s.seconds);
    out += line + s.detail + "\n";
  }
  return out;
}

}  // namespace meshflow
