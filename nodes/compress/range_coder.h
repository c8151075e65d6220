#pragma once
// Adaptive binary range coding (the scheme of LZMA: 11-bit probabilities that adapt by 1/32 per
// bit, a 32-bit range, carries propagated through a cached byte) and the models built on it
// that meshflow's mesh compression uses: symbols of a small alphabet by a binary tree of
// adaptive bits, and signed integers by their bit length (adaptive) and mantissa (the top bits
// adaptive, the rest at even odds). Encoder and decoder must make the same calls in the same
// order with equally fresh models. Not thread-safe: one coder and one set of models per stream.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace meshflow::compress {

/// The probability that the next bit is 0, in 1/2048ths; starts at even odds.
struct BitModel {
  std::uint16_t p0 = 1024;
};

class RangeEncoder {
 public:
  /// Codes `bit` with the adaptive model (and adapts it).
  void encode(BitModel& model, unsigned bit);
  /// Codes the low `count` (<= 32) bits of `value`, most significant first, at even odds.
  void encode_direct(std::uint32_t value, unsigned count);
  /// Flushes the coder and returns the bytes; the encoder is then spent.
  std::vector<unsigned char> finish();

 private:
  void shift_low();
  std::uint64_t low_ = 0;
  std::uint32_t range_ = 0xFFFFFFFFu;
  std::uint8_t cache_ = 0;
  std::uint64_t cache_size_ = 1;
  std::vector<unsigned char> out_;
};

class RangeDecoder {
 public:
  /// Decodes from data[0, size) (which must outlive the decoder). `what` names the stream in
  /// errors ("connectivity", ...) and `source` the file.
  RangeDecoder(const unsigned char* data, std::size_t size, std::string source, std::string what);
  unsigned decode(BitModel& model);
  std::uint32_t decode_direct(unsigned count);
  /// Throws Error(source, what, "...") when the decoder has read more than a few bytes past
  /// the end of its data (the stream was truncated or corrupt). Cheap; call it at checkpoints.
  void check() const;

 private:
  std::uint8_t next_byte();
  void normalize();
  const unsigned char* data_;
  std::size_t size_;
  std::size_t at_ = 0;
  std::size_t overrun_ = 0;
  std::uint32_t range_ = 0xFFFFFFFFu;
  std::uint32_t code_ = 0;
  std::string source_, what_;
};

/// A symbol of an alphabet of N (<= 32) by a binary tree of adaptive bits.
template <unsigned N>
class SymbolModel {
 public:
  static_assert(N >= 2 && N <= 32);
  void encode(RangeEncoder& enc, unsigned symbol) {
    unsigned node = 1;
    for (int bit = kBits - 1; bit >= 0; --bit) {
      const unsigned b = (symbol >> bit) & 1u;
      enc.encode(tree_[node], b);
      node = node * 2 + b;
    }
  }
  unsigned decode(RangeDecoder& dec) {
    unsigned node = 1;
    for (int bit = kBits - 1; bit >= 0; --bit) node = node * 2 + dec.decode(tree_[node]);
    return node - (1u << kBits);
  }

 private:
  static constexpr int kBits = N <= 2 ? 1 : N <= 4 ? 2 : N <= 8 ? 3 : N <= 16 ? 4 : 5;
  std::array<BitModel, (1u << kBits)> tree_{};
};

/// Signed integers (|v| < 2^31): the bit length of |v| (0 .. 31) adaptively, then the two bits
/// below the leading one adaptively (per length), the rest at even odds, then the sign
/// adaptively. Small residuals cost a few bits; any 32-bit value round-trips.
class IntegerModel {
 public:
  void encode(RangeEncoder& enc, std::int32_t value);
  std::int32_t decode(RangeDecoder& dec);

 private:
  SymbolModel<16> length_low_;   // lengths 0 .. 14, 15 = escape to length_high_
  SymbolModel<32> length_high_;  // lengths 15 .. 32 as 0 .. 17
  std::array<std::array<BitModel, 4>, 32> top_{};
  std::array<BitModel, 32> sign_{};
};

}  // namespace meshflow::compress
