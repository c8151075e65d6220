#include "nodes/io/image_io.h"

#include <jpeglib.h>
#include <lzf.h>
#include <spng.h>
#include <tiffio.h>

#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>

#include "nodes/io/atomic_file.h"
#include "nodes/io/byte_buffer.h"
#include "nodes/io/parse_util.h"
#include "runtime/error.h"

namespace meshflow::io {
namespace {

constexpr std::uint64_t kMaxPixels = std::uint64_t{1} << 28;  // 16 k x 16 k

enum class Kind { kPng, kJpeg, kTiff, kPclzf, kOther };

Kind kind_of(const std::vector<std::uint8_t>& b) {
  if (b.size() >= 8 && std::memcmp(b.data(), "\x89PNG\r\n\x1a\n", 8) == 0) return Kind::kPng;
  if (b.size() >= 3 && b[0] == 0xff && b[1] == 0xd8 && b[2] == 0xff) return Kind::kJpeg;
  if (b.size() >= 4 &&
      (std::memcmp(b.data(), "II*\0", 4) == 0 || std::memcmp(b.data(), "MM\0*", 4) == 0))
    return Kind::kTiff;
  if (b.size() >= 5 && std::memcmp(b.data(), "PCLZF", 5) == 0) return Kind::kPclzf;
  return Kind::kOther;
}

// The most pixels one byte of a file can decode to: deflate (PNG, TIFF) expands at most 1032:1
// and a pixel takes at least one bit; JPEG, LZW and LZF expand less.
constexpr std::uint64_t kMaxPixelsPerFileByte = 8 * 1032;

// Throws unless a width x height image is non-empty, at most kMaxPixels, and could be held in a
// file of `file_bytes`: a header claiming more lies, and must not make the reader allocate it.
void check_size(std::uint64_t width, std::uint64_t height, std::uint64_t file_bytes,
                const std::string& path) {
  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  if (width == 0 || height == 0 || width * height > kMaxPixels)
    throw Error(
        path, "",
        "image size " + size + " is empty or over " + std::to_string(kMaxPixels) + " pixels");
  if (width * height > kMaxPixelsPerFileByte * file_bytes)
    throw Error(path, "",
                "image size " + size + " cannot be held in a file of " +
                    std::to_string(file_bytes) + " bytes (the header is corrupt)");
}

// ---- PNG (libspng) -------------------------------------------------------------------------

using SpngContext = std::unique_ptr<spng_ctx, decltype(&spng_ctx_free)>;

SpngContext png_decoder(const std::vector<std::uint8_t>& bytes, const std::string& path,
                        spng_ihdr& ihdr) {
  SpngContext ctx(spng_ctx_new(0), spng_ctx_free);
  if (!ctx) throw Error(path, "", "cannot create a PNG decoder");
  spng_set_crc_action(ctx.get(), SPNG_CRC_USE, SPNG_CRC_USE);
  spng_set_image_limits(ctx.get(), 1u << 16, 1u << 16);
  int err = spng_set_png_buffer(ctx.get(), bytes.data(), bytes.size());
  if (err == 0) err = spng_get_ihdr(ctx.get(), &ihdr);
  if (err != 0) throw Error(path, "PNG header", spng_strerror(err));
  check_size(ihdr.width, ihdr.height, bytes.size(), path);
  return ctx;
}

Image decode_png(const std::vector<std::uint8_t>& bytes, const std::string& path, bool depth) {
  spng_ihdr ihdr{};
  SpngContext ctx = png_decoder(bytes, path, ihdr);
  const int rows = static_cast<int>(ihdr.height), cols = static_cast<int>(ihdr.width);
  if (depth) {
    if (ihdr.color_type != SPNG_COLOR_TYPE_GRAYSCALE || ihdr.bit_depth != 16)
      throw Error(path, "", "expected a 16-bit single-channel depth image");
    Image image(rows, cols, PixelFormat::U16);
    const int err = spng_decode_image(ctx.get(), image.data(), image.pixels() * 2, SPNG_FMT_PNG,
                                      0);  // host-endian 16-bit samples
    if (err != 0) throw Error(path, "PNG data", spng_strerror(err));
    return image;
  }
  Image image(rows, cols, PixelFormat::RGB8);
  const int err = spng_decode_image(ctx.get(), image.data(), image.pixels() * 3, SPNG_FMT_RGB8, 0);
  if (err != 0) throw Error(path, "PNG data", spng_strerror(err));
  return image;
}

// ---- JPEG (libjpeg-turbo) ------------------------------------------------------------------

struct JpegError {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void jpeg_fail(j_common_ptr info) {
  auto* e = reinterpret_cast<JpegError*>(info->err);
  (*info->err->format_message)(info, e->message);
  std::longjmp(e->jump, 1);
}

void jpeg_silent(j_common_ptr, int) {}

// Decodes into `out` (allocated here once the size is known); returns false with `message`
// set on failure. No C++ objects with destructors live across the setjmp.
bool decode_jpeg_into(const std::vector<std::uint8_t>& bytes, Image& out, char* message,
                      const std::string& path) {
  jpeg_decompress_struct info;
  JpegError error;
  info.err = jpeg_std_error(&error.manager);
  error.manager.error_exit = jpeg_fail;
  error.manager.emit_message = jpeg_silent;
  if (setjmp(error.jump)) {
    std::strcpy(message, error.message);
    jpeg_destroy_decompress(&info);
    return false;
  }
  jpeg_create_decompress(&info);
  jpeg_mem_src(&info, bytes.data(), static_cast<unsigned long>(bytes.size()));
  jpeg_read_header(&info, TRUE);
  // Checked before jpeg_start_decompress(), which allocates whole-image buffers (progressive).
  const std::uint64_t pixels = std::uint64_t{info.image_width} * info.image_height;
  if (pixels == 0 || pixels > kMaxPixels || pixels > kMaxPixelsPerFileByte * bytes.size()) {
    std::snprintf(message, JMSG_LENGTH_MAX,
                  "image size %ux%u is empty, too large or more than %zu bytes can hold",
                  info.image_width, info.image_height, bytes.size());
    jpeg_destroy_decompress(&info);
    return false;
  }
  info.out_color_space = JCS_RGB;
  jpeg_start_decompress(&info);
  (void)path;
  out = Image(static_cast<int>(info.output_height), static_cast<int>(info.output_width),
              PixelFormat::RGB8);
  while (info.output_scanline < info.output_height) {
    JSAMPROW row = out.data() + std::size_t{info.output_scanline} * out.row_bytes();
    jpeg_read_scanlines(&info, &row, 1);
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return true;
}

Image decode_jpeg(const std::vector<std::uint8_t>& bytes, const std::string& path) {
  Image image;
  char message[JMSG_LENGTH_MAX] = {0};
  if (!decode_jpeg_into(bytes, image, message, path))
    throw Error(path, "JPEG", message[0] != '\0' ? message : "cannot decode");
  return image;
}

// ---- TIFF (libtiff) ------------------------------------------------------------------------

thread_local std::string tiff_message;

void tiff_error(const char*, const char* format, va_list args) {
  char text[512];
  std::vsnprintf(text, sizeof text, format, args);
  tiff_message = text;
}

void tiff_warning(const char*, const char*, va_list) {}

// libtiff reports through process-wide handlers: installed once, they keep the message of the
// calling thread instead of printing it.
void install_tiff_handlers() {
  static const bool installed = [] {
    TIFFSetErrorHandler(tiff_error);
    TIFFSetWarningHandler(tiff_warning);
    return true;
  }();
  (void)installed;
}

using Tiff = std::unique_ptr<TIFF, decltype(&TIFFClose)>;

Image decode_tiff(const std::string& path, bool depth) {
  install_tiff_handlers();
  tiff_message.clear();
  Tiff tiff(TIFFOpen(path.c_str(), "r"), TIFFClose);
  if (!tiff) throw Error(path, "TIFF", tiff_message.empty() ? "cannot open" : tiff_message);
  std::uint32_t width = 0, height = 0;
  std::uint16_t bits = 0, samples = 1;
  TIFFGetField(tiff.get(), TIFFTAG_IMAGEWIDTH, &width);
  TIFFGetField(tiff.get(), TIFFTAG_IMAGELENGTH, &height);
  TIFFGetFieldDefaulted(tiff.get(), TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(tiff.get(), TIFFTAG_SAMPLESPERPIXEL, &samples);
  std::error_code size_error;
  const std::uintmax_t file_size = std::filesystem::file_size(path, size_error);
  check_size(width, height, size_error ? 0 : file_size, path);
  const int rows = static_cast<int>(height), cols = static_cast<int>(width);
  if (depth) {
    if (bits != 16 || samples != 1 || TIFFIsTiled(tiff.get()))
      throw Error(path, "", "expected a 16-bit single-channel depth image (in strips)");
    Image image(rows, cols, PixelFormat::U16);
    if (static_cast<std::size_t>(TIFFScanlineSize(tiff.get())) != image.row_bytes())
      throw Error(path, "TIFF", "unexpected scanline size");
    for (int r = 0; r < rows; ++r)
      if (TIFFReadScanline(tiff.get(), image.ptr<std::uint16_t>(r), static_cast<std::uint32_t>(r),
                           0) < 0)
        throw Error(path, "TIFF row " + std::to_string(r),
                    tiff_message.empty() ? "cannot decode" : tiff_message);
    return image;
  }
  // Any colour layout through libtiff's RGBA conversion (rows bottom-up, ABGR words).
  std::vector<std::uint32_t> rgba(static_cast<std::size_t>(width) * height);
  if (!TIFFReadRGBAImageOriented(tiff.get(), width, height, rgba.data(), ORIENTATION_TOPLEFT, 0))
    throw Error(path, "TIFF", tiff_message.empty() ? "cannot decode" : tiff_message);
  Image image(rows, cols, PixelFormat::RGB8);
  for (int r = 0; r < rows; ++r) {
    Rgb8* out = image.ptr<Rgb8>(r);
    for (int c = 0; c < cols; ++c) {
      const std::uint32_t p =
          rgba[static_cast<std::size_t>(r) * width + static_cast<std::size_t>(c)];
      out[c] = Rgb8{static_cast<std::uint8_t>(TIFFGetR(p)), static_cast<std::uint8_t>(TIFFGetG(p)),
                    static_cast<std::uint8_t>(TIFFGetB(p))};
    }
  }
  return image;
}

// ---- PCLZF (PCL's LZF image grabber, liblzf) ------------------------------------------------

// Header (37 bytes, little-endian): "PCLZF", uint32 width, uint32 height, a 16-character
// space-padded type ("depth16" or "rgb24"), uint32 compressed size, uint32 uncompressed size;
// an LZF stream follows. depth16 is row-major uint16 millimetres; rgb24 is planar (all R, then
// all G, then all B).
Image decode_pclzf(const std::vector<std::uint8_t>& bytes, const std::string& path, bool depth) {
  constexpr std::size_t kHeader = 37;
  if (bytes.size() < kHeader)
    throw Error(path, "PCLZF header", "the file is shorter than its header");
  std::uint32_t width = 0, height = 0, compressed = 0, uncompressed = 0;
  std::memcpy(&width, bytes.data() + 5, 4);
  std::memcpy(&height, bytes.data() + 9, 4);
  std::string type(reinterpret_cast<const char*>(bytes.data() + 13), 16);
  type.erase(type.find_last_not_of(" \0") + 1);
  std::memcpy(&compressed, bytes.data() + 29, 4);
  std::memcpy(&uncompressed, bytes.data() + 33, 4);
  check_size(width, height, bytes.size(), path);
  const bool is_depth = type == "depth16";
  if (!is_depth && type != "rgb24")
    throw Error(path, "PCLZF header", "image type '" + type + "': expected depth16 or rgb24");
  if (is_depth != depth)
    throw Error(path, "PCLZF header",
                std::string("expected a ") + (depth ? "depth16" : "rgb24") + " image, got " + type);
  const std::uint64_t expected = std::uint64_t{width} * height * (is_depth ? 2 : 3);
  if (uncompressed != expected)
    throw Error(path, "PCLZF header",
                "uncompressed size " + std::to_string(uncompressed) + " does not match " +
                    std::to_string(width) + "x" + std::to_string(height) + " " + type + " (" +
                    std::to_string(expected) + " bytes)");
  if (compressed != bytes.size() - kHeader)
    throw Error(path, "PCLZF header",
                "compressed size " + std::to_string(compressed) + " but the file holds " +
                    std::to_string(bytes.size() - kHeader) + " bytes after the header");
  std::vector<std::uint8_t> raw(uncompressed);
  if (lzf_decompress(bytes.data() + kHeader, compressed, raw.data(), uncompressed) != uncompressed)
    throw Error(path, "PCLZF data", "the LZF stream is corrupt");
  const int rows = static_cast<int>(height), cols = static_cast<int>(width);
  if (is_depth) {
    Image image(rows, cols, PixelFormat::U16);
    std::memcpy(image.data(), raw.data(), raw.size());
    return image;
  }
  Image image(rows, cols, PixelFormat::RGB8);
  const std::size_t plane = std::size_t{width} * height;
  for (std::size_t i = 0; i < plane; ++i)
    for (std::size_t c = 0; c < 3; ++c) image.data()[3 * i + c] = raw[c * plane + i];
  return image;
}

Image read_image(const std::string& path, bool depth) {
  const std::vector<std::uint8_t> bytes = read_file_bytes(path);
  switch (kind_of(bytes)) {
    case Kind::kPng:
      return decode_png(bytes, path, depth);
    case Kind::kJpeg:
      if (depth) throw Error(path, "", "expected a 16-bit single-channel depth image, got JPEG");
      return decode_jpeg(bytes, path);
    case Kind::kTiff:
      return decode_tiff(path, depth);
    case Kind::kPclzf:
      return decode_pclzf(bytes, path, depth);
    case Kind::kOther:
      break;
  }
  throw Error(
      path, "",
      bytes.empty() ? "empty file" : "not a PNG, JPEG, TIFF or PCLZF image (unknown signature)");
}

}  // namespace

Image read_depth_image_file(const std::string& path) { return read_image(path, true); }

Image read_color_image_file(const std::string& path) { return read_image(path, false); }

std::vector<std::uint8_t> encode_png(const Image& image) {
  spng_ihdr ihdr{};
  ihdr.width = static_cast<std::uint32_t>(image.cols());
  ihdr.height = static_cast<std::uint32_t>(image.rows());
  switch (image.format()) {
    case PixelFormat::RGB8:
      ihdr.bit_depth = 8;
      ihdr.color_type = SPNG_COLOR_TYPE_TRUECOLOR;
      break;
    case PixelFormat::U8:
      ihdr.bit_depth = 8;
      ihdr.color_type = SPNG_COLOR_TYPE_GRAYSCALE;
      break;
    case PixelFormat::U16:
      ihdr.bit_depth = 16;
      ihdr.color_type = SPNG_COLOR_TYPE_GRAYSCALE;
      break;
    case PixelFormat::F32:
      throw Error("PNG", "image type", "expected 8-bit RGB or grey, or 16-bit grey, got F32");
  }
  // 16-bit samples big-endian as PNG stores them.
  std::vector<std::uint8_t> raw(image.data(),
                                image.data() + image.pixels() * bytes_per_pixel(image.format()));
  if (ihdr.bit_depth == 16)
    for (std::size_t i = 0; i + 1 < raw.size(); i += 2) std::swap(raw[i], raw[i + 1]);
  SpngContext ctx(spng_ctx_new(SPNG_CTX_ENCODER), spng_ctx_free);
  if (!ctx) throw Error("PNG", "", "cannot create an encoder");
  spng_set_option(ctx.get(), SPNG_ENCODE_TO_BUFFER, 1);
  int err = spng_set_ihdr(ctx.get(), &ihdr);
  if (err == 0)
    err = spng_encode_image(ctx.get(), raw.data(), raw.size(), SPNG_FMT_RAW, SPNG_ENCODE_FINALIZE);
  std::size_t length = 0;
  void* png = err == 0 ? spng_get_png_buffer(ctx.get(), &length, &err) : nullptr;
  if (err != 0 || png == nullptr) throw Error("PNG", "encoding", spng_strerror(err));
  std::vector<std::uint8_t> bytes(static_cast<std::uint8_t*>(png),
                                  static_cast<std::uint8_t*>(png) + length);
  std::free(png);
  return bytes;
}

void write_png(const std::string& path, const Image& image) {
  const std::vector<std::uint8_t> bytes = encode_png(image);
  AtomicOutputFile file(path);
  file.stream().write(reinterpret_cast<const char*>(bytes.data()),
                      static_cast<std::streamsize>(bytes.size()));
  file.commit();
}

}  // namespace meshflow::io
