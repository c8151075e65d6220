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

namespace detail {
/// -16 log2(p / 2048) for p = 0 .. 2048 (p = 0 costs as p = 1); filled before main().
extern const std::array<std::uint16_t, 2049> kBitCost;
}  // namespace detail

/// The cost of coding `bit` with `model` as it stands, in 1/16ths of a bit (-16 log2 p), for
/// encoders that choose between codings. O(1) (a table lookup, inline: encoders call it in
/// their inner loops); thread-safe.
inline std::uint32_t bit_cost(const BitModel& model, unsigned bit) {
  const std::uint32_t p0 = model.p0;
  return detail::kBitCost[bit != 0 ? 2048u - p0 : p0];
}

class RangeEncoder {
 public:
  /// Codes `bit` with the adaptive model (and adapts it). Branch-free but for renormalising.
  void encode(BitModel& model, unsigned bit) {
    const std::uint32_t bound = (range_ >> kProbabilityBits) * model.p0;
    const std::uint32_t one = 0u - static_cast<std::uint32_t>(bit & 1u);  // all ones for a 1
    low_ += bound & one;
    range_ = (bound & ~one) | ((range_ - bound) & one);
    const std::uint32_t p0 = model.p0, down = p0 >> kAdaptShift, up = (kOne - p0) >> kAdaptShift;
    model.p0 = static_cast<std::uint16_t>(p0 - down + ((up + down) & ~one));
    while (range_ < kTop) {
      range_ <<= 8;
      shift_low();
    }
  }
  /// Codes the low `count` (<= 32) bits of `value` at even odds (eight at a time).
  void encode_direct(std::uint32_t value, unsigned count);
  /// Flushes the coder and returns the bytes; the encoder is then spent.
  std::vector<unsigned char> finish();

  static constexpr unsigned kProbabilityBits = 11;
  static constexpr std::uint32_t kOne = 1u << kProbabilityBits;
  static constexpr unsigned kAdaptShift = 5;
  static constexpr std::uint32_t kTop = 1u << 24;
  static_assert(kOne == 2048, "bit_cost()'s table is in 2048ths");

 private:
  void shift_low();
  std::uint64_t low_ = 0;
  std::uint32_t range_ = 0xFFFFFFFFu;
  std::uint8_t cache_ = 0;
  std::uint64_t cache_size_ = 1;
  std::vector<unsigned char> out_;
};

/// The range decoder's working state, small enough to live in registers: the models' decode
/// loops copy it into a local, decode, and store it back (RangeDecoder::Session).
struct RangeDecoderCore {
  std::uint32_t range = 0xFFFFFFFFu;
  std::uint32_t code = 0;
  const unsigned char* data = nullptr;
  std::size_t size = 0, at = 0, overrun = 0;

  /// The next byte of the data, 0 past its end (counted in `overrun`).
  std::uint8_t next_byte() {
    if (at < size) return data[at++];
    ++overrun;
    return 0;
  }
  /// The next bit of `model` (adapted). Branch-free but for renormalising: the bits of
  /// well-compressed data are unpredictable, and a mispredicted branch costs more than both arms.
  unsigned decode(BitModel& model) {
    const std::uint32_t bound = (range >> RangeEncoder::kProbabilityBits) * model.p0;
    const unsigned bit = code >= bound ? 1u : 0u;
    const std::uint32_t one = 0u - bit;
    code -= bound & one;
    range = (bound & ~one) | ((range - bound) & one);
    // p0 - down for a 1, p0 + up for a 0, in arithmetic (a conditional here becomes a branch).
    const std::uint32_t p0 = model.p0;
    const std::uint32_t down = p0 >> RangeEncoder::kAdaptShift;
    const std::uint32_t up = (RangeEncoder::kOne - p0) >> RangeEncoder::kAdaptShift;
    model.p0 = static_cast<std::uint16_t>(p0 - down + ((up + down) & ~one));
    while (range < RangeEncoder::kTop) {
      range <<= 8;
      code = (code << 8) | next_byte();
    }
    return bit;
  }
  /// `count` (<= 32) bits at even odds, eight at a time.
  std::uint32_t decode_direct(unsigned count) {
    std::uint32_t value = 0;
    while (count > 0) {
      const unsigned k = count < 8 ? count : 8;
      count -= k;
      range >>= k;
      // A corrupt stream can put the code past the last part: clamp (RangeDecoder::check() or
      // the caller's range checks report it).
      const std::uint32_t last = (1u << k) - 1u, part = code / range;
      const std::uint32_t kept = part < last ? part : last;
      code -= kept * range;
      value = (value << k) | kept;
      while (range < RangeEncoder::kTop) {
        range <<= 8;
        code = (code << 8) | next_byte();
      }
    }
    return value;
  }
};

class RangeDecoder {
 public:
  /// Decodes from data[0, size) (which must outlive the decoder). `what` names the stream in
  /// errors ("connectivity", ...) and `source` the file.
  RangeDecoder(const unsigned char* data, std::size_t size, std::string source, std::string what);
  /// The next bit of `model` (adapted).
  unsigned decode(BitModel& model) { return core_.decode(model); }
  /// `count` (<= 32) bits at even odds.
  std::uint32_t decode_direct(unsigned count) { return core_.decode_direct(count); }
  /// Throws Error(source, what, "...") when the decoder has read more than a few bytes past
  /// the end of its data (the stream was truncated or corrupt). Cheap; call it at checkpoints.
  void check() const;

  /// The core copied into a local for a run of decodes and stored back when destroyed.
  class Session {
   public:
    /// Copies d's core; the destructor stores it back.
    explicit Session(RangeDecoder& d) : owner_(d), core(d.core_) {}
    ~Session() { owner_.core_ = core; }
    Session(const Session&) = delete;
    Session& operator=(const Session&) = delete;

   private:
    RangeDecoder& owner_;

   public:
    RangeDecoderCore core;
  };

 private:
  RangeDecoderCore core_;
  std::string source_, what_;
};

/// A symbol of an alphabet of N (<= 32) by a binary tree of adaptive bits.
template <unsigned N>
class SymbolModel {
 public:
  static_assert(N >= 2 && N <= 32);
  /// Codes `symbol` (< N).
  void encode(RangeEncoder& enc, unsigned symbol) {
    unsigned node = 1;
    for (int bit = kBits - 1; bit >= 0; --bit) {
      const unsigned b = (symbol >> bit) & 1u;
      enc.encode(tree_[node], b);
      node = node * 2 + b;
    }
  }
  /// The next symbol (< 2^kLevels: callers check it against N).
  unsigned decode(RangeDecoder& dec) {
    RangeDecoder::Session s(dec);
    return decode(s.core);
  }
  /// The same on a core a caller holds (RangeDecoder::Session).
  unsigned decode(RangeDecoderCore& dec) {
    unsigned node = 1;
    for (int bit = kBits - 1; bit >= 0; --bit) node = step(dec, node);
    return symbol(node);
  }
  /// The cost of coding `symbol` (< N) now, in 1/16ths of a bit (bit_cost()).
  std::uint32_t cost(unsigned symbol) const {
    std::uint32_t total = 0;
    unsigned node = 1;
    for (int bit = kBits - 1; bit >= 0; --bit) {
      const unsigned b = (symbol >> bit) & 1u;
      total += bit_cost(tree_[node], b);
      node = node * 2 + b;
    }
    return total;
  }
  /// Decoding one level at a time (for decoders that interleave several streams): from node 1,
  /// kLevels steps, then symbol().
  static constexpr int kLevels = N <= 2 ? 1 : N <= 4 ? 2 : N <= 8 ? 3 : N <= 16 ? 4 : 5;
  /// One level down the tree from `node`.
  unsigned step(RangeDecoderCore& dec, unsigned node) { return node * 2 + dec.decode(tree_[node]); }
  /// The symbol of the leaf `node` reached after kLevels steps.
  static unsigned symbol(unsigned node) { return node - (1u << kBits); }

 private:
  static constexpr int kBits = N <= 2 ? 1 : N <= 4 ? 2 : N <= 8 ? 3 : N <= 16 ? 4 : 5;
  std::array<BitModel, (1u << kBits)> tree_{};
};

/// Signed integers (|v| < 2^31): the bit length of |v| (0 .. 31) adaptively, then the two bits
/// below the leading one adaptively (per length), the rest at even odds, then the sign
/// adaptively. Small residuals cost a few bits; any 32-bit value round-trips.
class IntegerModel {
 public:
  /// Codes `value`.
  void encode(RangeEncoder& enc, std::int32_t value);
  /// What encode(value) would cost now, in 1/16ths of a bit (bit_cost()); changes nothing.
  std::uint32_t cost(std::int32_t value) const;
  /// The next value.
  std::int32_t decode(RangeDecoder& dec);
  /// Three values from three streams (one per model), their steps interleaved so that the three
  /// decoders' dependency chains overlap: about twice as fast as three decode() calls. The cores
  /// are those of RangeDecoder::Session objects the caller holds over its whole loop.
  static std::array<std::int32_t, 3> decode_three(IntegerModel& mx, IntegerModel& my,
                                                  IntegerModel& mz, RangeDecoderCore& dx,
                                                  RangeDecoderCore& dy, RangeDecoderCore& dz);

 private:
  std::int32_t finish(RangeDecoderCore& dec, unsigned length_symbol);
  SymbolModel<16> length_low_;   // lengths 0 .. 14, 15 = escape to length_high_
  SymbolModel<32> length_high_;  // lengths 15 .. 32 as 0 .. 17
  std::array<std::array<BitModel, 4>, 32> top_{};
  std::array<BitModel, 32> sign_{};
};

}  // namespace meshflow::compress
