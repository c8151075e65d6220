#pragma once
// Image: a 2D pixel array of one of the four pixel formats meshflow reads, filters and writes
// (depth in raw sensor units or metres, masks, RGB colour). Row-major, rows contiguous.

#include <cassert>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <type_traits>

#include "runtime/rgb8.h"

namespace meshflow {

enum class PixelFormat : std::uint8_t {
  U8,   ///< one std::uint8_t per pixel (masks, 8-bit grey)
  U16,  ///< one std::uint16_t per pixel (raw depth in sensor units)
  F32,  ///< one float per pixel (depth in metres)
  RGB8  ///< one Rgb8 per pixel (colour, R first)
};

/// Bytes one pixel of `format` takes. O(1); inline, as every ptr() and at() calls it.
constexpr std::size_t bytes_per_pixel(PixelFormat format) {
  switch (format) {
    case PixelFormat::U8:
      return 1;
    case PixelFormat::U16:
      return 2;
    case PixelFormat::F32:
      return 4;
    case PixelFormat::RGB8:
      return 3;
  }
  return 1;
}

/// The format's name as written in error messages ("U8", "U16", "F32", "RGB8"). O(1).
const char* pixel_format_name(PixelFormat format);

/// The pixel format a C++ pixel type stands for; ptr<T>() and at<T>() accept only that type.
template <class T>
struct PixelFormatOf;
template <>
struct PixelFormatOf<std::uint8_t> {
  static constexpr PixelFormat kFormat = PixelFormat::U8;
};
template <>
struct PixelFormatOf<std::uint16_t> {
  static constexpr PixelFormat kFormat = PixelFormat::U16;
};
template <>
struct PixelFormatOf<float> {
  static constexpr PixelFormat kFormat = PixelFormat::F32;
};
template <>
struct PixelFormatOf<Rgb8> {
  static constexpr PixelFormat kFormat = PixelFormat::RGB8;
};

/// A rows x cols image. Copies share the pixels (like a shared_ptr: cheap to pass through the
/// graph; clone() for a deep copy). A default-constructed image is empty. Reading one image
/// from several threads is safe; writing needs the caller's synchronisation, as for any array.
class Image {
 public:
  Image() = default;
  /// A rows x cols image of `format` with every byte zero (0 depth = no measurement, black).
  /// Throws std::bad_alloc when the pixels do not fit in memory; rows or cols <= 0 give an
  /// empty image. O(rows cols).
  Image(int rows, int cols, PixelFormat format);
  /// A rows x cols image of `format` copied from `pixels`, whose rows start `row_stride_bytes`
  /// apart (>= cols * bytes_per_pixel(format)); for embedders handing meshflow their own
  /// buffers (an OpenCV cv::Mat's data and step, a camera driver's frame). O(rows cols).
  Image(int rows, int cols, PixelFormat format, const void* pixels, std::size_t row_stride_bytes);
  /// A rows x cols image of T's format with every pixel `value`, e.g.
  /// Image::filled<std::uint16_t>(480, 640, 1000) for a flat wall 1 m away. O(rows cols).
  template <class T>
  static Image filled(int rows, int cols, const T& value) {
    Image image(rows, cols, PixelFormatOf<T>::kFormat);
    image.fill(value);
    return image;
  }

  /// Height in pixels.
  int rows() const { return rows_; }
  /// Width in pixels.
  int cols() const { return cols_; }
  /// The pixel format.
  PixelFormat format() const { return format_; }
  /// Whether the image has no pixels.
  bool empty() const { return rows_ == 0 || cols_ == 0; }
  /// Same rows and cols as `other` (formats may differ).
  bool same_size(const Image& other) const { return rows_ == other.rows_ && cols_ == other.cols_; }
  /// rows * cols.
  std::size_t pixels() const {
    return static_cast<std::size_t>(rows_) * static_cast<std::size_t>(cols_);
  }
  /// Bytes of one row (rows are contiguous: row r starts at data() + r * row_bytes()).
  std::size_t row_bytes() const {
    return static_cast<std::size_t>(cols_) * bytes_per_pixel(format_);
  }
  /// The first pixel's bytes (rows contiguous, row_bytes() apart).
  std::uint8_t* data() { return pixels_.get(); }
  /// The first pixel's bytes, read-only.
  const std::uint8_t* data() const { return pixels_.get(); }

  /// The first pixel of row `row` (0 <= row < rows()); T must be the format's pixel type.
  template <class T>
  T* ptr(int row) {
    check_access<T>(row);
    return reinterpret_cast<T*>(pixels_.get() + static_cast<std::size_t>(row) * row_bytes());
  }
  /// The same, read-only.
  template <class T>
  const T* ptr(int row) const {
    check_access<T>(row);
    return reinterpret_cast<const T*>(pixels_.get() + static_cast<std::size_t>(row) * row_bytes());
  }
  /// Pixel (row, col); bounds and type are asserted in debug builds.
  template <class T>
  T& at(int row, int col) {
    assert(col >= 0 && col < cols_);
    return ptr<T>(row)[col];
  }
  /// The same, read-only.
  template <class T>
  const T& at(int row, int col) const {
    assert(col >= 0 && col < cols_);
    return ptr<T>(row)[col];
  }
  /// Sets every pixel to `value`. O(rows cols).
  template <class T>
  void fill(const T& value) {
    for (int r = 0; r < rows_; ++r) {
      T* p = ptr<T>(r);
      for (int c = 0; c < cols_; ++c) p[c] = value;
    }
  }

  /// A deep copy (pixels not shared). O(rows cols).
  Image clone() const;
  /// True when both have the same size, format and bytes. O(rows cols).
  bool same_pixels(const Image& other) const;

 private:
  template <class T>
  void check_access(int row) const {
    static_assert(sizeof(T) == sizeof(typename std::remove_cv<T>::type), "plain pixel type");
    assert(PixelFormatOf<typename std::remove_cv<T>::type>::kFormat == format_ &&
           "pixel type does not match the image's format");
    assert(row >= 0 && row < rows_);
    (void)row;
  }

  std::shared_ptr<std::uint8_t[]> pixels_;
  int rows_ = 0, cols_ = 0;
  PixelFormat format_ = PixelFormat::U8;
};

/// Pixels that are not zero (0, 0.0f or black). O(rows cols).
std::size_t count_nonzero(const Image& image);

}  // namespace meshflow
