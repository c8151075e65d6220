#include "tools/report.h"

#include <cstdio>
#include <stdexcept>
#include <string>

#include "nodes/eval/vertex_quality.h"
#include "tools/console.h"

namespace meshflow::cli {

void report_observations(const std::vector<float>& counts, const char* what) {
  const ObservationStats s = observation_stats(counts);
  report(
      "observed   %s: median %.4g, 5 %% of vertices at or below %.4g, min %.4g (PLY property "
      "'observations')\n",
      what, static_cast<double>(s.median), static_cast<double>(s.p5), static_cast<double>(s.min));
}

const char* scene_rule(SceneKind kind) {
  switch (kind) {
    case SceneKind::kMapFrame:
      return "up (LAS or map coordinates: heights along z)";
    case SceneKind::kHeightField:
      return "up (one surface over x-y, a terrain tile, unless its normals disagree on up: "
             "--orient down or flip turns it)";
    case SceneKind::kCameraView:
      return "towards the origin if the normals agree on one camera view, else outward";
    case SceneKind::kObject:
      break;
  }
  return "outward (a closed object)";
}

namespace {

// Which way propagation turned the components, and why.
std::string side_rule(const NormalsReport& r) {
  const std::string name = side_name(r.side, r.side_axis);
  switch (r.side) {
    case ComponentSide::kTowardPoint:
      return "facing the origin (one camera view in its camera frame)";
    case ComponentSide::kAlongAxis:
      return r.orientation == NormalOrientation::kPropagate ? scene_rule(r.scene) : name;
    case ComponentSide::kOutward:
    case ComponentSide::kViewOrOutward:
    case ComponentSide::kAxisOrOutward:
      break;
  }
  return "outward (a closed object, or no single view or surface over x-y)";
}

}  // namespace

std::string describe_normals(const NormalsReport& r) {
  const std::string flipped = r.flipped ? ", then turned over (--orient flip)" : "";
  if (r.source == NormalSource::kInput) {
    if (r.estimated == 0) return "from the input" + flipped;
    return "from the input, " + std::to_string(r.estimated) +
           " missing (zero or NaN) estimated and oriented by their neighbours";
  }
  char fits[96];
  std::snprintf(fits, sizeof fits, "estimated (kn %d, median plane-fit variation %.3f), oriented ",
                r.kn, static_cast<double>(r.median_variation));
  const std::string text = fits;
  switch (r.orientation) {
    case NormalOrientation::kTowardSensor:
      return text + "towards the sensor" + flipped;
    case NormalOrientation::kTowardViewpoint:
      return text + "towards the viewpoint" + flipped;
    case NormalOrientation::kAwayFromViewpoint:
      return text + "away from the viewpoint" + flipped;
    case NormalOrientation::kInput:
      return text + "as the input normals" + flipped;
    case NormalOrientation::kAuto:
    case NormalOrientation::kPropagate:
    case NormalOrientation::kUp:
    case NormalOrientation::kDown:
      break;
  }
  return text + "by propagation (" + std::to_string(r.components) + " component" +
         (r.components == 1 ? "" : "s") + ", " + std::to_string(r.flipped_by_vote) +
         " turned by the vote), " + side_rule(r) + flipped;
}

// "marching cubes", "extended marching cubes (clean samples without a sensor)", ...
const char* extraction_name(ExtractMethod method, bool sharp_normals) {
  switch (method) {
    case ExtractMethod::kExtendedMarchingCubes:
      return sharp_normals ? "extended marching cubes, sharp-feature normals"
                           : "extended marching cubes";
    case ExtractMethod::kMarchingTetrahedra:
      return "marching tetrahedra";
    case ExtractMethod::kPlanarMarchingCubes:
      return "planar marching cubes";
    case ExtractMethod::kAuto:
    case ExtractMethod::kMarchingCubes:
      break;
  }
  return "marching cubes";
}

void report_closing(const CloseReport& c) {
  if (!c.ran) return;
  report(
      "close      %zu corners filled (%d levels on %d x %d x %d), %zu held by data, "
      "%zu seen empty, %zu on lines through observed tunnels; %zu cells added\n",
      c.filled, c.levels, c.lattice.x(), c.lattice.y(), c.lattice.z(), c.observed, c.seen_empty,
      c.through, c.cells_added);
  if (c.held_out > 0)
    report(
        "           fill: %s (%zu observed corners near the rim held out, predicted with a mean "
        "error of %.2f voxels by the gradient fill, %.2f by diffusion, %.2f by the indicator)\n",
        close_fill_name(c.fill), c.held_out, c.held_out_error_gradient, c.held_out_error_diffusion,
        c.held_out_error_indicator);
  else
    report("           fill: %s\n", close_fill_name(c.fill));
  if (c.coarse_step > 1)
    report(
        "           tiled: a coarse lattice of every %d-th corner, %zu tiles solved at full "
        "resolution\n",
        c.coarse_step, c.tiles);
}

void print_frame_report(const Frame& f, double wall_s, int threads) {
  const FilterCounts& c = f.filter_counts;
  report("input      %s: %zu points\n", f.name.c_str(), c.input);
  if (!f.origin.isZero())
    report(
        "origin     %.3f %.3f %.3f (georeferenced: meshed in a local frame; PLY/OBJ/OFF get "
        "world coordinates, STL/glTF the local ones with this origin)\n",
        f.origin.x(), f.origin.y(), f.origin.z());
  if (c.non_finite > 0) report("filter     dropped %zu NaN/Inf points\n", c.non_finite);
  if (c.cropped + c.merged + c.outliers > 0) {
    report("filter     cropped %zu, merged %zu, outliers %zu\n", c.cropped, c.merged, c.outliers);
  }
  if (c.isolated + c.sparse_clusters > 0)
    report(
        "outliers   dropped %zu isolated points and %zu in sparse clusters (--outlier-cluster)\n",
        c.isolated, c.sparse_clusters);
  if (f.kind == FrameKind::kCloud) report("normals    %s\n", describe_normals(f.normals).c_str());
  report("grid       voxel %.4g m, %zu cells, %zu corners (%zu valid", f.voxel_size,
         f.grid.cells.size(), f.grid.corners.size(), f.distance.valid_count());
  if (f.distance.disagreeing + f.distance.extrapolated > 0)
    report("; invalid: %zu where tangent planes disagree, %zu past the data's border",
           f.distance.disagreeing, f.distance.extrapolated);
  report(")\n");
  report_closing(f.closing);
  if (f.rim_trimmed > 0)
    report("rim        %zu border triangles more than --max-rim voxels from the data peeled off\n",
           f.rim_trimmed);
  report("mesh       %zu vertices, %zu triangles (%s)\n", f.mesh.vertices.size(),
         f.mesh.triangles.size(), extraction_name(f.extract_method, f.normals.sharp));
  if (!f.optimize.steps.empty()) report("optimize\n%s", format_optimize_report(f.optimize).c_str());
  report("time       %.1f ms on %d thread%s\n", 1e3 * wall_s, threads, threads == 1 ? "" : "s");
  report("%s", format_stage_table(summarize_stages(f.timings), wall_s).c_str());
}

void throw_if_failed(const Frame& f) {
  if (!f.ok()) throw std::runtime_error(f.error);
}

}  // namespace meshflow::cli
