#pragma once
// Per-frame estimate of a depth sensor's noise from the image itself. Structured-light and
// stereo sensors quantise disparity, so their depth steps grow with depth^2 (a PrimeSense /
// Kinect v1 camera: about 0.003 x depth^2, 12 mm at 2 m). Used where a threshold must stay above
// a real sensor's noise: the restricted quadtree's refinement, fusion's band behind a surface.

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <array>
#include <cstdint>

#include "runtime/image.h"

namespace meshflow {

/// Residuals per depth^2 (1/m) binned linearly up to 0.05 /m, for their 90th percentile.
class ResidualHistogram {
 public:
  /// Counts one residual (larger ones share the last bin). O(1).
  void add(float residual_per_depth2);
  /// Adds another histogram's counts. O(bins).
  void merge(const ResidualHistogram& other);
  /// The 90th percentile (nearest rank, bin centre), or 0 with fewer than 500 residuals.
  float percentile90() const;

 private:
  static constexpr int kBins = 2048;
  static constexpr float kRange = 0.05f;
  std::array<std::uint32_t, kBins + 1> bins_{};
};

/// Every kNoiseRowStep-th row and kNoiseColumnStep-th pixel are sampled: tens of thousands of
/// residuals for a 640 x 480 frame, plenty for a percentile, at a tenth of a millisecond.
constexpr int kNoiseRowStep = 4;
constexpr int kNoiseColumnStep = 2;

/// The 90th percentile of the residuals `add_row(v, histogram)` bins for rows v = 0, 4, 8, ...
/// below `height`, the rows in parallel. Deterministic (integer counts, any thread count).
template <class AddRow>
float residual_percentile(int height, const AddRow& add_row) {
  const int rows = (height + kNoiseRowStep - 1) / kNoiseRowStep;
  return tbb::parallel_reduce(
             tbb::blocked_range<int>(0, rows, 16), ResidualHistogram{},
             [&](const tbb::blocked_range<int>& range, ResidualHistogram h) {
               for (int i = range.begin(); i != range.end(); ++i) add_row(kNoiseRowStep * i, h);
               return h;
             },
             [](ResidualHistogram a, const ResidualHistogram& b) {
               a.merge(b);
               return a;
             })
      .percentile90();
}

/// The depth noise of a metric depth image (F32 metres, 0 or NaN = invalid; asserted F32) as a
/// coefficient of depth^2 (1/m): the 90th percentile of a pixel's depth residual from the mean
/// of its left and right neighbours, divided by its depth^2, over the sampled pixels whose
/// neighbours are valid. On a smooth surface that residual is noise (a quantisation step or a
/// spike); depth edges and creases are a few per cent of the pixels and stay above the
/// percentile. 0 when fewer than 500 pixels qualify. Parallel over rows; O(pixels / 8).
float estimate_noise_per_depth2(const Image& depth_m);

}  // namespace meshflow
