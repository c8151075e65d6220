#pragma once
// Image files without OpenCV's codec library: 16-bit depth images (PNG, TIFF) and colour images
// (PNG, JPEG, TIFF) read with libspng, libjpeg-turbo and libtiff, PNG written with libspng.
// OpenCV's imgcodecs module links about 120 shared libraries (GDAL, Poppler, HDF5, ...) that
// every meshflow process paid for at start-up, 80-220 ms, before it read a single point.

#include <cstdint>
#include <string>
#include <vector>
#include "runtime/image.h"

namespace meshflow::io {

/// The 16-bit single-channel image in a PNG, TIFF or PCLZF (PCL grabber, depth16) file
/// (recognised by its signature), as
/// U16. Throws meshflow::Error naming the file when it is missing, corrupt, of another
/// kind (e.g. 8-bit or colour: "expected a 16-bit single-channel depth image") or larger than
/// 2^28 pixels. O(pixels).
Image read_depth_image_file(const std::string& path);

/// The colour image in a PNG, JPEG, TIFF or PCLZF (rgb24, planar) file as RGB8 in RGB order
/// (grey images are replicated, alpha dropped, 16-bit samples scaled to 8 bits). Throws
/// meshflow::Error naming the file on failure. O(pixels).
Image read_color_image_file(const std::string& path);

/// The PNG encoding of `image`: RGB8 (RGB order), U8 or U16 (16-bit grey).
/// Throws meshflow::Error for other types. O(pixels).
std::vector<std::uint8_t> encode_png(const Image& image);

/// encode_png() written to `path` atomically (a temporary name, then renamed). Throws
/// meshflow::Error on I/O failure.
void write_png(const std::string& path, const Image& image);

}  // namespace meshflow::io
