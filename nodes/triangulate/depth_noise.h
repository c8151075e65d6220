#pragma once
// Per-frame estimate of a depth sensor's noise, so that the restricted quadtree refines on
// surface shape rather than on quantisation steps and noise. Structured-light and stereo
// sensors quantise disparity, so their depth steps grow with depth^2 (a PrimeSense / Kinect v1
// camera: about 0.003 x depth^2, 12 mm at 2 m); a fixed threshold below that step refines
// almost every block of a real frame.

#include "nodes/triangulate/pixel_grid.h"

namespace meshflow {

/// The depth noise of `grid` as a coefficient of depth^2 (1/m): the 90th percentile of a
/// pixel's distance from the midpoint of its left and right neighbours, divided by its squared
/// distance from the eye, over every second pixel of every fourth row whose two neighbours are
/// valid. On a smooth surface that residual is noise (a quantisation step or a spike); depth
/// edges and creases are a few per cent of the pixels and stay above the percentile. Returns 0
/// when fewer than 500 pixels qualify. Deterministic (integer histogram, any thread count);
/// parallel over rows; O(pixels / 8).
float estimate_noise_per_depth2(const PointGrid& grid);

}  // namespace meshflow
