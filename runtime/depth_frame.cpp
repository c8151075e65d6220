#include "runtime/depth_frame.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <string>

#include "runtime/error.h"

namespace meshflow {

void check_depth_frame(const DepthFrame& frame) {
  const auto fail = [](const std::string& field, const std::string& problem) {
    throw Error("depth frame", field, problem);
  };
  const Image& d = frame.depth;
  if (d.empty()) fail("depth", "empty image");
  if (d.format() != PixelFormat::U16 && d.format() != PixelFormat::F32)
    fail("depth", std::string("expected a U16 or F32 image, got ") + pixel_format_name(d.format()));
  if (d.format() == PixelFormat::U16 &&
      !(std::isfinite(frame.depth_scale) && frame.depth_scale > 0.0f))
    fail("depth_scale", "must be a positive number of raw units per metre");
  const PinholeIntrinsics& k = frame.intrinsics;
  if (d.cols() != k.width || d.rows() != k.height)
    fail("intrinsics", "image is " + std::to_string(d.cols()) + "x" + std::to_string(d.rows()) +
                           ", intrinsics say " + std::to_string(k.width) + "x" +
                           std::to_string(k.height));
  if (!(std::isfinite(k.fx) && k.fx > 0.0f && std::isfinite(k.fy) && k.fy > 0.0f))
    fail("intrinsics", "focal lengths must be positive numbers of pixels");
  if (!std::isfinite(k.cx) || !std::isfinite(k.cy))
    fail("intrinsics", "principal point must be finite");
  if (!frame.T_world_camera.matrix().allFinite())
    fail("T_world_camera", "pose has NaN or infinite entries");
}

void depth_in_metres(const DepthFrame& frame, Image& out) {
  check_depth_frame(frame);
  const Image& in = frame.depth;
  if (!(out.rows() == in.rows() && out.cols() == in.cols() && out.format() == PixelFormat::F32))
    out = Image(in.rows(), in.cols(), PixelFormat::F32);
  const int cols = in.cols();
  const bool raw16 = in.format() == PixelFormat::U16;
  const float metres_per_unit = static_cast<float>(1.0 / frame.depth_scale);
  tbb::parallel_for(0, in.rows(), [&](int v) {
    float* metres = out.ptr<float>(v);
    if (raw16) {
      const std::uint16_t* raw = in.ptr<std::uint16_t>(v);
      for (int u = 0; u < cols; ++u) metres[u] = static_cast<float>(raw[u]) * metres_per_unit;
    } else {
      const float* raw = in.ptr<float>(v);
      for (int u = 0; u < cols; ++u)
        metres[u] = std::isfinite(raw[u]) && raw[u] > 0.0f ? raw[u] : 0.0f;
    }
  });
}

Image depth_in_metres(const DepthFrame& frame) {
  Image out;
  depth_in_metres(frame, out);
  return out;
}

}  // namespace meshflow
