#include "runtime/depth_frame.h"

#include <cmath>
#include <mutex>
#include <string>

#include "runtime/error.h"

namespace meshflow {

void run_opencv_on_calling_thread() {
  static std::once_flag once;
  std::call_once(once, [] { cv::setNumThreads(0); });
}

void check_depth_frame(const DepthFrame& frame) {
  const auto fail = [](const std::string& field, const std::string& problem) {
    throw Error("depth frame", field, problem);
  };
  const cv::Mat& d = frame.depth;
  if (d.empty()) fail("depth", "empty image");
  if (d.type() != CV_16U && d.type() != CV_32F)
    fail("depth", "expected a single-channel CV_16U or CV_32F image, got OpenCV type " +
                      std::to_string(d.type()));
  if (d.type() == CV_16U && !(std::isfinite(frame.depth_scale) && frame.depth_scale > 0.0f))
    fail("depth_scale", "must be a positive number of raw units per metre");
  const PinholeIntrinsics& k = frame.intrinsics;
  if (d.cols != k.width || d.rows != k.height)
    fail("intrinsics", "image is " + std::to_string(d.cols) + "x" + std::to_string(d.rows) +
                           ", intrinsics say " + std::to_string(k.width) + "x" +
                           std::to_string(k.height));
  if (!(std::isfinite(k.fx) && k.fx > 0.0f && std::isfinite(k.fy) && k.fy > 0.0f))
    fail("intrinsics", "focal lengths must be positive numbers of pixels");
  if (!std::isfinite(k.cx) || !std::isfinite(k.cy))
    fail("intrinsics", "principal point must be finite");
  if (!frame.T_world_camera.matrix().allFinite())
    fail("T_world_camera", "pose has NaN or infinite entries");
}

cv::Mat depth_in_metres(const DepthFrame& frame) {
  check_depth_frame(frame);
  run_opencv_on_calling_thread();
  cv::Mat out;
  if (frame.depth.type() == CV_16U) {
    frame.depth.convertTo(out, CV_32F, 1.0 / frame.depth_scale);
  } else {
    out = frame.depth.clone();
    out.forEach<float>([](float& d, const int*) {
      if (!std::isfinite(d) || d < 0.0f) d = 0.0f;
    });
  }
  return out;
}

}  // namespace meshflow
