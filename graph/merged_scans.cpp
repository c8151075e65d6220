#include "graph/merged_scans.h"

#include <algorithm>
#include <iterator>
#include <vector>

#include "graph/frame_graph.h"

namespace meshflow {

ScanPreparationPipeline::ScanPreparationPipeline(ReconstructionConfig config,
                                                 std::size_t max_in_flight)
    : config_(std::move(config)), max_in_flight_(std::max<std::size_t>(1, max_in_flight)) {}

void ScanPreparationPipeline::run(const std::function<FramePtr()>& next,
                                  const std::function<void(const FramePtr&)>& sink) {
  // Clouds: read, filter, index, normals; depth images: read, filter (with image normals).
  const stages::FrameRoutes preparation{
      stages::kPointCloudStages[0],
      {std::begin(stages::kPointCloudStages) + 1, std::begin(stages::kPointCloudStages) + 4},
      {std::begin(stages::kDepthImageStages) + 1, std::begin(stages::kDepthImageStages) + 2}};
  detail::run_stage_routes(max_in_flight_, preparation, config_, next, sink);
}

void append_scan(PointCloud& into, const PointCloud& scan) {
  const bool colors = scan.has_colors() && (into.positions.empty() || into.has_colors());
  into.z_up = scan.z_up && (into.positions.empty() || into.z_up);
  if (into.positions.empty()) into.origin = scan.origin;
  // Georeferenced scans may each have their own local origin: moved into `into`'s.
  const Eigen::Vector3f shift = (scan.origin - into.origin).cast<float>();
  const std::size_t first = into.positions.size();
  into.positions.insert(into.positions.end(), scan.positions.begin(), scan.positions.end());
  if (!shift.isZero())
    for (std::size_t i = first; i < into.positions.size(); ++i) into.positions[i] += shift;
  into.normals.insert(into.normals.end(), scan.normals.begin(), scan.normals.end());
  if (colors)
    into.colors.insert(into.colors.end(), scan.colors.begin(), scan.colors.end());
  else
    into.colors.clear();
  into.intensities.clear();
  into.width = into.height = 0;  // unorganized
  into.has_sensor_origin = false;
}

ReconstructionConfig merged_pass_config(const ReconstructionConfig& config) {
  ReconstructionConfig c = config;
  c.filter = FilterConfig{};
  c.filter.outlier_cluster = 0;  // each scan's clusters were judged in its own pass
  c.normals.source = NormalSource::kInput;
  c.organized_as_depth = false;
  return c;
}

}  // namespace meshflow
