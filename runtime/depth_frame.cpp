#include "runtime/depth_frame.h"

#include <cassert>
#include <cmath>
#include <mutex>

namespace meshflow {

void run_opencv_on_calling_thread() {
  static std::once_flag once;
  std::call_once(once, [] { cv::setNumThreads(0); });
}

cv::Mat depth_in_metres(const DepthFrame& frame) {
  run_opencv_on_calling_thread();
  cv::Mat out;
  if (frame.depth.type() == CV_16U) {
    frame.depth.convertTo(out, CV_32F, 1.0 / frame.depth_scale);
  } else {
    assert(frame.depth.type() == CV_32F);
    out = frame.depth.clone();
    out.forEach<float>([](float& d, const int*) {
      if (!std::isfinite(d) || d < 0.0f) d = 0.0f;
    });
  }
  return out;
}

}  // namespace meshflow
