#include "nodes/io/image_io.h"

#include <gtest/gtest.h>
#include <jpeglib.h>
#include <lzf.h>
#include <tiffio.h>

#include <cstdio>

#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::io {
namespace {

Image gradient16(int rows, int cols) {
  Image m(rows, cols, PixelFormat::U16);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      m.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(r * 1000 + c * 7 + 300);
  return m;
}

Image colours(int rows, int cols) {
  Image m(rows, cols, PixelFormat::RGB8);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      m.at<Rgb8>(r, c) =
          Rgb8{static_cast<std::uint8_t>(10 * r), static_cast<std::uint8_t>(20 * c), 200};
  return m;
}

// Writes `image` (U16 or RGB8 RGB) as an uncompressed TIFF in strips.
void write_tiff(const std::string& path, const Image& image) {
  TIFF* tiff = TIFFOpen(path.c_str(), "w");
  ASSERT_NE(tiff, nullptr);
  const bool colour = image.format() == PixelFormat::RGB8;
  TIFFSetField(tiff, TIFFTAG_IMAGEWIDTH, image.cols());
  TIFFSetField(tiff, TIFFTAG_IMAGELENGTH, image.rows());
  TIFFSetField(tiff, TIFFTAG_BITSPERSAMPLE, colour ? 8 : 16);
  TIFFSetField(tiff, TIFFTAG_SAMPLESPERPIXEL, colour ? 3 : 1);
  TIFFSetField(tiff, TIFFTAG_PHOTOMETRIC, colour ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK);
  TIFFSetField(tiff, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(tiff, TIFFTAG_COMPRESSION, COMPRESSION_PACKBITS);
  TIFFSetField(tiff, TIFFTAG_ROWSPERSTRIP, 2);
  for (int r = 0; r < image.rows(); ++r)
    ASSERT_GE(TIFFWriteScanline(tiff,
                                const_cast<std::uint8_t*>(
                                    image.data() + static_cast<std::size_t>(r) * image.row_bytes()),
                                static_cast<std::uint32_t>(r), 0),
              0);
  TIFFClose(tiff);
}

// Writes `image` (RGB8 RGB) as a JPEG of quality 100.
void write_jpeg(const std::string& path, const Image& image) {
  jpeg_compress_struct info;
  jpeg_error_mgr error;
  info.err = jpeg_std_error(&error);
  jpeg_create_compress(&info);
  std::FILE* file = std::fopen(path.c_str(), "wb");
  ASSERT_NE(file, nullptr);
  jpeg_stdio_dest(&info, file);
  info.image_width = static_cast<JDIMENSION>(image.cols());
  info.image_height = static_cast<JDIMENSION>(image.rows());
  info.input_components = 3;
  info.in_color_space = JCS_RGB;
  jpeg_set_defaults(&info);
  jpeg_set_quality(&info, 100, TRUE);
  jpeg_start_compress(&info, TRUE);
  while (info.next_scanline < info.image_height) {
    JSAMPROW row = const_cast<JSAMPLE*>(image.data() + info.next_scanline * image.row_bytes());
    jpeg_write_scanlines(&info, &row, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  std::fclose(file);
}

TEST(ImageIo, PngRoundTripsDepthAndColourExactly) {
  const std::string dir = test::temp_dir();
  const Image depth = gradient16(7, 9), rgb = colours(5, 6);
  write_png(dir + "/d.png", depth);
  write_png(dir + "/c.png", rgb);
  EXPECT_EQ(test::max_abs_difference(read_depth_image_file(dir + "/d.png"), depth), 0.0);
  EXPECT_EQ(test::max_abs_difference(read_color_image_file(dir + "/c.png"), rgb), 0.0);
  // A grey 16-bit PNG read as colour: scaled to 8 bits and replicated.
  const Image as_colour = read_color_image_file(dir + "/d.png");
  EXPECT_EQ(as_colour.format(), PixelFormat::RGB8);
  EXPECT_THROW(read_depth_image_file(dir + "/c.png"), Error) << "colour is no depth image";
}

TEST(ImageIo, TiffAndJpegAreRead) {
  const std::string dir = test::temp_dir();
  const Image depth = gradient16(6, 8), rgb = colours(6, 8);
  write_tiff(dir + "/d.tiff", depth);
  write_tiff(dir + "/c.tiff", rgb);
  write_jpeg(dir + "/c.jpg", rgb);
  EXPECT_EQ(test::max_abs_difference(read_depth_image_file(dir + "/d.tiff"), depth), 0.0);
  EXPECT_EQ(test::max_abs_difference(read_color_image_file(dir + "/c.tiff"), rgb), 0.0);
  const Image jpeg = read_color_image_file(dir + "/c.jpg");
  ASSERT_TRUE(jpeg.same_size(rgb));
  EXPECT_LE(test::max_abs_difference(jpeg, rgb), 16.0) << "quality 100, subsampled chroma";
  EXPECT_THROW(read_depth_image_file(dir + "/c.jpg"), Error);
}

// A PCLZF file as PCL's image grabber writes it: the 37-byte header, then the LZF stream of the
// raw bytes (depth16 row-major, rgb24 planar).
std::string pclzf(const std::string& type, std::uint32_t width, std::uint32_t height,
                  const std::vector<std::uint8_t>& raw) {
  std::vector<std::uint8_t> packed(raw.size() + raw.size() / 16 + 64);
  const unsigned n = lzf_compress(raw.data(), static_cast<unsigned>(raw.size()), packed.data(),
                                  static_cast<unsigned>(packed.size()));
  std::string out = "PCLZF";
  const auto put = [&out](std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  put(width);
  put(height);
  out += type + std::string(16 - type.size(), ' ');
  put(n);
  put(static_cast<std::uint32_t>(raw.size()));
  out.append(reinterpret_cast<const char*>(packed.data()), n);
  return out;
}

TEST(ImageIo, PclzfDepthAndPlanarColourAreRead) {
  const std::string dir = test::temp_dir();
  const Image depth = gradient16(12, 20);
  std::vector<std::uint8_t> raw(depth.data(), depth.data() + depth.pixels() * 2);
  test::write_file(dir + "/d.pclzf", pclzf("depth16", 20, 12, raw));
  EXPECT_EQ(test::max_abs_difference(read_depth_image_file(dir + "/d.pclzf"), depth), 0.0);
  const Image rgb = colours(12, 20);
  std::vector<std::uint8_t> planar(rgb.pixels() * 3);
  for (std::size_t i = 0; i < rgb.pixels(); ++i)
    for (std::size_t c = 0; c < 3; ++c) planar[c * rgb.pixels() + i] = rgb.data()[3 * i + c];
  test::write_file(dir + "/c.pclzf", pclzf("rgb24", 20, 12, planar));
  EXPECT_EQ(test::max_abs_difference(read_color_image_file(dir + "/c.pclzf"), rgb), 0.0);
  EXPECT_THROW(read_depth_image_file(dir + "/c.pclzf"), Error) << "rgb24 is not depth";
  // Hostile headers: sizes that do not match, a type it does not know, a giant image.
  const std::string good = pclzf("depth16", 20, 12, raw);
  std::string wrong_size = good;
  wrong_size[33] = 1;  // uncompressed size
  std::string giant = pclzf("depth16", 1u << 20, 1u << 20, raw);
  const std::pair<std::string, std::string> bad[] = {
      {"wrong_size.pclzf", wrong_size},
      {"short.pclzf", good.substr(0, 30)},
      {"truncated.pclzf", good.substr(0, good.size() - 5)},
      {"bayer.pclzf", pclzf("bayer8", 20, 12, raw)},
      {"giant.pclzf", giant}};
  for (const auto& [name, bytes] : bad) {
    test::write_file(dir + "/" + name, bytes);
    try {
      read_depth_image_file(dir + "/" + name);
      ADD_FAILURE() << name;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

// The shared Kinect grabber frames: PCLZF and TIFF hold the same pixels.
TEST(ImageIo, SharedGrabberPclzfEqualsItsTiff) {
  const std::string base = "kinect_pcl/grabber_sequences/";
  if (!test::has_data(base + "pclzf")) GTEST_SKIP() << "shared data not found (MESHFLOW_DATA)";
  const std::string frame = "frame_20121214T142256.068683";
  const Image a = read_depth_image_file(test::data_path(base + "pclzf/" + frame + "_depth.pclzf"));
  const Image b = read_depth_image_file(test::data_path(base + "tiff/" + frame + "_depth.tiff"));
  EXPECT_EQ(test::max_abs_difference(a, b), 0.0);
  const Image c = read_color_image_file(test::data_path(base + "pclzf/" + frame + "_rgb.pclzf"));
  const Image d = read_color_image_file(test::data_path(base + "tiff/" + frame + "_rgb.tiff"));
  EXPECT_EQ(test::max_abs_difference(c, d), 0.0);
}

TEST(ImageIo, BrokenFilesAreOneClearErrorNamingTheFile) {
  const std::string dir = test::temp_dir();
  write_png(dir + "/d.png", gradient16(16, 16));
  const std::string good = test::read_file(dir + "/d.png");
  std::uint32_t state = 5;
  const std::vector<std::pair<std::string, std::string>> files = {
      {"empty.png", ""},
      {"text.png", "not an image"},
      {"truncated.png", good.substr(0, good.size() / 2)},
      {"flipped.png", test::flip_bytes(good, 6, state)},
      {"truncated.jpg", std::string("\xff\xd8\xff\xe0", 4) + std::string(20, 'x')},
      {"truncated.tiff", std::string("II*\0", 4) + std::string(4, '\xff')}};
  for (const auto& [name, bytes] : files) {
    const std::string path = dir + "/" + name;
    test::write_file(path, bytes);
    for (bool depth : {true, false}) {
      try {
        depth ? read_depth_image_file(path) : read_color_image_file(path);
        // A flip that happens to keep the file valid decodes; that is fine.
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      }
    }
  }
  EXPECT_THROW(read_depth_image_file(dir + "/missing.png"), Error);
}

}  // namespace
}  // namespace meshflow::io
