#pragma once
// Several registered scans of one place into one surface (the reconstruction thesis's
// multi-scan path): each scan is read, filtered and given normals turned towards its own
// sensor position (frames in flight in a flow graph), the clouds are joined in the world frame,
// and the joined cloud, which now carries its normals, goes through the stages once. Where
// scans overlap, their points describe one surface with consistent normals, so the signed
// distance has one zero crossing there and the mesh one sheet; concatenating per-scan meshes
// would give one sheet per scan.

#include <cstddef>
#include <functional>

#include "graph/frame.h"
#include "graph/pipeline.h"
#include "graph/reconstruction_config.h"
#include "graph/sequence_runner.h"

namespace meshflow {

/// The per-scan part: source -> limiter(K) -> read -> filter -> index -> normals -> sink, in
/// input order. Each delivered frame's `cloud` is filtered and has unit normals, oriented as
/// config.normals says (auto: towards the frame's sensor where it has one).
class ScanPreparationPipeline final : public FramePipeline {
 public:
  /// Prepares up to `max_in_flight` (>= 1) scans at once with `config`'s filter and normals
  /// settings.
  explicit ScanPreparationPipeline(ReconstructionConfig config, std::size_t max_in_flight = 2);
  void run(const std::function<FramePtr()>& next,
           const std::function<void(const FramePtr&)>& sink) override;

 private:
  ReconstructionConfig config_;
  std::size_t max_in_flight_;
};

/// Appends `scan`'s points, normals and (when both have them, or `into` is empty) colours to
/// `into`; colours are dropped from the result as soon as one scan has none. The first scan's
/// origin (PointCloud::origin) becomes `into`'s; later scans' points are moved from their own
/// origin to it. O(n).
void append_scan(PointCloud& into, const PointCloud& scan);

/// The configuration of the joined cloud's pass: `config` with the per-scan filters (range
/// limits, outlier removal, downsampling) off, since every scan already went through them, and
/// the normals taken from the cloud (they were oriented per scan).
ReconstructionConfig merged_pass_config(const ReconstructionConfig& config);

}  // namespace meshflow
