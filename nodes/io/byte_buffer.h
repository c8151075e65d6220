#pragma once
// Little-endian binary encoding for meshflow's own file formats (the TSDF map, the compressed
// mesh): a writer into a byte vector, a reader that names the file and the field in every
// error, and the FNV-1a 64 checksum both formats end with.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace meshflow::io {

/// FNV-1a 64-bit hash of data[0, n). O(n).
std::uint64_t fnv1a64(const unsigned char* data, std::size_t n);

/// Rewrites the last 8 bytes of data[0, size) as the FNV-1a 64 hash (little-endian) of the
/// bytes before them: the checksum meshflow's own formats end with, for programs that edit a
/// file's image on purpose (fuzzers, tests). No effect below 8 bytes. O(size).
void reseal_fnv1a64(unsigned char* data, std::size_t size);

/// The whole file at `path`. Throws Error naming the file and the system's reason. O(size).
std::vector<unsigned char> read_file_bytes(const std::string& path);

/// Writes `bytes` to `path` atomically (complete file or none). Throws Error. O(size).
void write_file_bytes(const std::string& path, const std::vector<unsigned char>& bytes);

/// Appends little-endian values to `out`. Not thread-safe.
class ByteWriter {
 public:
  /// Appends n raw bytes from p.
  void bytes(const void* p, std::size_t n);
  /// Appends one byte.
  void u8(std::uint8_t v) { out.push_back(v); }
  /// Appends 4 bytes, little-endian.
  void u32(std::uint32_t v);
  /// Appends 8 bytes, little-endian.
  void u64(std::uint64_t v);
  /// Appends v's two's complement as u32.
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  /// Appends v's IEEE-754 bits as u32.
  void f32(float v);
  /// Appends v's IEEE-754 bits as u64.
  void f64(double v);
  std::vector<unsigned char> out;  ///< everything written so far
};

/// Reads little-endian values from `data` (which must outlive it) from the start. Every read
/// names its field: reading past the end throws Error(path, "FIELD at byte N", "file ends early
/// (truncated)"). Not thread-safe.
class ByteReader {
 public:
  /// Reads data[0, size); `path` (which must outlive the reader) names the data in errors.
  ByteReader(const std::string& path, const unsigned char* data, std::size_t size)
      : path_(path), data_(data), size_(size) {}
  /// Reads all of `data`.
  ByteReader(const std::string& path, const std::vector<unsigned char>& data)
      : ByteReader(path, data.data(), data.size()) {}
  /// The next byte.
  std::uint8_t u8(const char* field);
  /// The next 4 bytes, little-endian.
  std::uint32_t u32(const char* field);
  /// The next 8 bytes, little-endian.
  std::uint64_t u64(const char* field);
  /// The next u32 as two's complement.
  std::int32_t i32(const char* field) { return static_cast<std::int32_t>(u32(field)); }
  /// The next u32 as IEEE-754 bits.
  float f32(const char* field);
  /// The next u64 as IEEE-754 bits.
  double f64(const char* field);
  /// The next n bytes (a pointer into the data), after checking they exist.
  const unsigned char* bytes(std::size_t n, const char* field);
  /// Bytes read so far.
  std::size_t position() const { return at_; }
  /// Bytes left.
  std::size_t remaining() const { return size_ - at_; }
  /// Throws Error(path, "FIELD at byte N", problem) at the current position.
  [[noreturn]] void fail(const std::string& field, const std::string& problem) const;

 private:
  void need(std::size_t n, const char* field) const;
  const std::string& path_;
  const unsigned char* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

}  // namespace meshflow::io
