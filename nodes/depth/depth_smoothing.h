#pragma once
// Edge-preserving smoothing of metric depth images that knows which pixels hold no measurement:
// invalid pixels (0) neither receive a depth nor pull their neighbours towards 0 (a generic
// image filter such as OpenCV's medianBlur or bilateralFilter would mix them in as depth 0).

#include "runtime/image.h"

namespace meshflow {

/// Median of the valid depths in each valid pixel's k x k window (k = 3 or 5; the upper median
/// when the window holds an even number of them). `depth_m` is F32 metres with 0 = invalid
/// (asserted); returns a new image of the same size, invalid where the input is. Parallel over
/// rows, deterministic. O(pixels k^2).
Image median_filter_depth(const Image& depth_m, int k);

/// Bilateral filter with a 5 x 5 disc (radius 2 pixels, spatial sigma 2 pixels) and depth sigma
/// `sigma_depth_m` (metres, > 0): each valid pixel becomes the weighted mean of the valid depths
/// around it, weights exp(-r^2 / 2 sigma_s^2) exp(-(d - d_n)^2 / 2 sigma_d^2). Same contract as
/// median_filter_depth(). O(pixels).
Image bilateral_filter_depth(const Image& depth_m, float sigma_depth_m);

}  // namespace meshflow
