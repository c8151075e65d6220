#include "runtime/image.h"

#include <cstring>

namespace meshflow {

const char* pixel_format_name(PixelFormat format) {
  switch (format) {
    case PixelFormat::U8:
      return "U8";
    case PixelFormat::U16:
      return "U16";
    case PixelFormat::F32:
      return "F32";
    case PixelFormat::RGB8:
      return "RGB8";
  }
  return "?";
}

Image::Image(int rows, int cols, PixelFormat format) : format_(format) {
  if (rows <= 0 || cols <= 0) return;
  rows_ = rows;
  cols_ = cols;
  // Value-initialised: every byte zero.
  pixels_ = std::shared_ptr<std::uint8_t[]>(new std::uint8_t[pixels() * bytes_per_pixel(format)]());
}

Image::Image(int rows, int cols, PixelFormat format, const void* pixels,
             std::size_t row_stride_bytes)
    : Image(rows, cols, format) {
  assert(empty() || row_stride_bytes >= row_bytes());
  for (int r = 0; r < rows_; ++r)
    std::memcpy(
        data() + static_cast<std::size_t>(r) * row_bytes(),
        static_cast<const std::uint8_t*>(pixels) + static_cast<std::size_t>(r) * row_stride_bytes,
        row_bytes());
}

Image Image::clone() const {
  Image copy(rows_, cols_, format_);
  if (!empty()) std::memcpy(copy.data(), data(), static_cast<std::size_t>(rows_) * row_bytes());
  return copy;
}

bool Image::same_pixels(const Image& other) const {
  if (rows_ != other.rows_ || cols_ != other.cols_ || format_ != other.format_) return false;
  return empty() ||
         std::memcmp(data(), other.data(), static_cast<std::size_t>(rows_) * row_bytes()) == 0;
}

namespace {

template <class T, class IsNonzero>
std::size_t count_pixels(const Image& image, IsNonzero is_nonzero) {
  std::size_t n = 0;
  for (int r = 0; r < image.rows(); ++r) {
    const T* row = image.ptr<T>(r);
    for (int c = 0; c < image.cols(); ++c) n += is_nonzero(row[c]) ? 1 : 0;
  }
  return n;
}

}  // namespace

std::size_t count_nonzero(const Image& image) {
  const auto nonzero = [](auto value) { return value != 0; };
  switch (image.format()) {
    case PixelFormat::U8:
      return count_pixels<std::uint8_t>(image, nonzero);
    case PixelFormat::U16:
      return count_pixels<std::uint16_t>(image, nonzero);
    case PixelFormat::F32:
      return count_pixels<float>(image, [](float v) { return v != 0.0f; });
    case PixelFormat::RGB8:
      return count_pixels<Rgb8>(image, [](Rgb8 c) { return c != Rgb8{}; });
  }
  return 0;
}

}  // namespace meshflow
