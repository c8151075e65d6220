#include "nodes/io/byte_buffer.h"

#include <cstring>
#include <fstream>
#include <iterator>

#include "nodes/io/atomic_file.h"
#include "nodes/io/parse_util.h"
#include "runtime/error.h"

namespace meshflow::io {

std::uint64_t fnv1a64(const unsigned char* data, std::size_t n) {
  std::uint64_t h = 14695981039346656037ull;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= data[i];
    h *= 1099511628211ull;
  }
  return h;
}

void reseal_fnv1a64(unsigned char* data, std::size_t size) {
  if (size < 8) return;
  const std::uint64_t hash = fnv1a64(data, size - 8);
  for (std::size_t i = 0; i < 8; ++i)
    data[size - 8 + i] = static_cast<unsigned char>(hash >> (8 * i));
}

std::vector<unsigned char> read_file_bytes(const std::string& path) {
  std::ifstream in = open_input(path);
  return std::vector<unsigned char>((std::istreambuf_iterator<char>(in)),
                                    std::istreambuf_iterator<char>());
}

void write_file_bytes(const std::string& path, const std::vector<unsigned char>& bytes) {
  AtomicOutputFile file(path);
  file.stream().write(reinterpret_cast<const char*>(bytes.data()),
                      static_cast<std::streamsize>(bytes.size()));
  file.commit();
}

void ByteWriter::bytes(const void* p, std::size_t n) {
  const auto* b = static_cast<const unsigned char*>(p);
  out.insert(out.end(), b, b + n);
}

void ByteWriter::u32(std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<unsigned char>(v >> (8 * i)));
}

void ByteWriter::u64(std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<unsigned char>(v >> (8 * i)));
}

void ByteWriter::f32(float v) {
  std::uint32_t bits;
  std::memcpy(&bits, &v, 4);
  u32(bits);
}

void ByteWriter::f64(double v) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, 8);
  u64(bits);
}

void ByteReader::need(std::size_t n, const char* field) const {
  if (n > size_ - at_) fail(field, "file ends early (truncated)");
}

void ByteReader::fail(const std::string& field, const std::string& problem) const {
  throw Error(path_, field + " at byte " + std::to_string(at_), problem);
}

std::uint8_t ByteReader::u8(const char* field) {
  need(1, field);
  return data_[at_++];
}

std::uint32_t ByteReader::u32(const char* field) {
  need(4, field);
  std::uint32_t v = 0;
  for (std::size_t i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(data_[at_ + i]) << (8 * i);
  at_ += 4;
  return v;
}

std::uint64_t ByteReader::u64(const char* field) {
  need(8, field);
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(data_[at_ + i]) << (8 * i);
  at_ += 8;
  return v;
}

float ByteReader::f32(const char* field) {
  const std::uint32_t bits = u32(field);
  float v;
  std::memcpy(&v, &bits, 4);
  return v;
}

double ByteReader::f64(const char* field) {
  const std::uint64_t bits = u64(field);
  double v;
  std::memcpy(&v, &bits, 8);
  return v;
}

const unsigned char* ByteReader::bytes(std::size_t n, const char* field) {
  need(n, field);
  const unsigned char* p = data_ + at_;
  at_ += n;
  return p;
}

}  // namespace meshflow::io
