#include "runtime/image.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace meshflow {
namespace {

TEST(Image, NewImagesAreZeroAndCopiesSharePixels) {
  Image a(3, 4, PixelFormat::U16);
  EXPECT_EQ(a.rows(), 3);
  EXPECT_EQ(a.cols(), 4);
  EXPECT_EQ(a.row_bytes(), 8u);
  EXPECT_EQ(count_nonzero(a), 0u);
  Image shared = a;
  shared.at<std::uint16_t>(2, 3) = 7;
  EXPECT_EQ(a.at<std::uint16_t>(2, 3), 7) << "copies share the pixels";
  Image deep = a.clone();
  deep.at<std::uint16_t>(0, 0) = 9;
  EXPECT_EQ(a.at<std::uint16_t>(0, 0), 0) << "clone() does not";
  EXPECT_FALSE(deep.same_pixels(a));
  EXPECT_EQ(count_nonzero(deep), 2u);
}

TEST(Image, EmptyImagesAndFormats) {
  EXPECT_TRUE(Image().empty());
  EXPECT_TRUE(Image(0, 5, PixelFormat::F32).empty());
  EXPECT_TRUE(Image().same_pixels(Image()));
  EXPECT_EQ(bytes_per_pixel(PixelFormat::RGB8), 3u);
  EXPECT_STREQ(pixel_format_name(PixelFormat::F32), "F32");
  EXPECT_FALSE(Image(2, 2, PixelFormat::U8).same_pixels(Image(2, 2, PixelFormat::U16)));
}

TEST(Image, CopiesAStridedBufferRowByRow) {
  // Two rows of three RGB pixels with two bytes of padding per row (e.g. a cv::Mat ROI).
  const std::vector<std::uint8_t> buffer = {1,  2,  3,  4,  5,  6,  7,  8,  9,  0xAA, 0xAA,  //
                                            10, 11, 12, 13, 14, 15, 16, 17, 18, 0xAA, 0xAA};
  const Image image(2, 3, PixelFormat::RGB8, buffer.data(), 11);
  EXPECT_EQ(image.at<Rgb8>(0, 2), (Rgb8{7, 8, 9}));
  EXPECT_EQ(image.at<Rgb8>(1, 0), (Rgb8{10, 11, 12}));
  EXPECT_EQ(image.at<Rgb8>(1, 2), (Rgb8{16, 17, 18}));
}

TEST(Image, FilledSetsEveryPixel) {
  const Image wall = Image::filled<float>(4, 5, 1.5f);
  EXPECT_EQ(wall.format(), PixelFormat::F32);
  EXPECT_EQ(count_nonzero(wall), 20u);
  for (int v = 0; v < 4; ++v)
    for (int u = 0; u < 5; ++u) EXPECT_EQ(wall.at<float>(v, u), 1.5f);
}

}  // namespace
}  // namespace meshflow
