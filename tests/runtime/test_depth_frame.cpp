// Depth frames: what every depth consumer accepts (check_depth_frame) and the conversion to
// metres.

#include "runtime/depth_frame.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "runtime/error.h"

namespace meshflow {
namespace {

DepthFrame good_frame() {
  DepthFrame f;
  f.depth = Image::filled<std::uint16_t>(6, 8, 1500);
  f.intrinsics = PinholeIntrinsics{8, 6, 10.0f, 10.0f, 3.5f, 2.5f};
  return f;
}

TEST(DepthFrame, ConvertsToMetresAndClearsInvalidPixels) {
  DepthFrame f = good_frame();
  EXPECT_FLOAT_EQ(depth_in_metres(f).at<float>(2, 3), 1.5f);
  f.depth = Image::filled<float>(6, 8, 2.0f);
  f.depth.at<float>(0, 0) = std::numeric_limits<float>::quiet_NaN();
  f.depth.at<float>(0, 1) = std::numeric_limits<float>::infinity();
  f.depth.at<float>(0, 2) = -1.0f;
  const Image m = depth_in_metres(f);
  EXPECT_EQ(m.at<float>(0, 0), 0.0f);
  EXPECT_EQ(m.at<float>(0, 1), 0.0f);
  EXPECT_EQ(m.at<float>(0, 2), 0.0f);
  EXPECT_EQ(m.at<float>(0, 3), 2.0f);
}

// Frames a caller of the embedding API could push: each fault is an error naming its field,
// never a crash (an 8-bit image read as floats) or silent garbage (NaN points from a NaN pose).
TEST(DepthFrame, UnusableFramesAreErrorsNamingTheField) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::pair<const char*, std::function<void(DepthFrame&)>> faults[] = {
      {"depth", [](DepthFrame& f) { f.depth = Image(); }},
      {"depth", [](DepthFrame& f) { f.depth = Image::filled<std::uint8_t>(6, 8, 7); }},
      {"depth",
       [](DepthFrame& f) {
         f.depth = Image::filled<Rgb8>(6, 8, Rgb8{1, 1, 1});
       }},
      {"depth_scale", [](DepthFrame& f) { f.depth_scale = 0.0f; }},
      {"depth_scale", [nan](DepthFrame& f) { f.depth_scale = nan; }},
      {"intrinsics", [](DepthFrame& f) { f.intrinsics.width = 9; }},
      {"intrinsics", [](DepthFrame& f) { f.intrinsics.fx = 0.0f; }},
      {"intrinsics", [nan](DepthFrame& f) { f.intrinsics.fy = nan; }},
      {"intrinsics", [nan](DepthFrame& f) { f.intrinsics.cx = nan; }},
      {"T_world_camera", [nan](DepthFrame& f) { f.T_world_camera.translation().x() = nan; }},
      {"T_world_camera",
       [](DepthFrame& f) {
         f.T_world_camera.linear()(0, 0) = std::numeric_limits<float>::infinity();
       }},
  };
  for (const auto& [field, fault] : faults) {
    DepthFrame f = good_frame();
    fault(f);
    try {
      depth_in_metres(f);
      ADD_FAILURE() << "no error for a bad " << field;
    } catch (const Error& e) {
      EXPECT_EQ(e.location(), field) << e.what();
    }
  }
  EXPECT_NO_THROW(check_depth_frame(good_frame()));
}

}  // namespace
}  // namespace meshflow
