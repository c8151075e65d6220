#pragma once
// Adaptive range coding (the scheme of LZMA: a 32-bit range, carries propagated through a cached
// byte) and the models built on it that meshflow's mesh compression uses: adaptive bits (11-bit
// probabilities that adapt by 1/32 per bit), symbols of a small alphabet in one step from
// adaptive counts (FrequencyModel), and signed integers by one such symbol (their bit length,
// sign and top bit) and a mantissa (the next bit adaptive, the rest at even odds). Encoder and
// decoder must make the same calls in the same order with equally fresh models. Not thread-safe:
// one coder and one set of models per stream.

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
/// 16 log2(1 + m / 256) rounded, m = 0 .. 255; filled before main().
extern const std::array<std::uint8_t, 256> kLog2Fraction;
}  // namespace detail

/// The cost of coding `bit` with `model` as it stands, in 1/16ths of a bit (-16 log2 p), for
/// encoders that choose between codings. O(1) (a table lookup, inline: encoders call it in
/// their inner loops); thread-safe.
inline std::uint32_t bit_cost(const BitModel& model, unsigned bit) {
  const std::uint32_t p0 = model.p0;
  return detail::kBitCost[bit != 0 ? 2048u - p0 : p0];
}

/// The cost of a symbol holding `parts` (1 .. 2^15) of 2^15, in 1/16ths of a bit
/// (16 (15 - log2 parts), within 1/16). O(1); thread-safe.
inline std::uint32_t part_cost(std::uint32_t parts) {
  const unsigned n = 31u - static_cast<unsigned>(__builtin_clz(parts | 1u));
  const std::uint32_t m = (n >= 8 ? parts >> (n - 8) : parts << (8 - n)) & 0xFFu;
  return 16u * (15u - n) - detail::kLog2Fraction[m];
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
  /// Codes the parts [low, high) of the range split into 2^15 (FrequencyModel); `last`: the
  /// part is the last one, which also takes the remainder of the range past r * 2^15.
  void encode_part(std::uint32_t low, std::uint32_t high, bool last) {
    const std::uint32_t r = range_ >> 15;
    low_ += std::uint64_t{r} * low;
    range_ = last ? range_ - r * low : r * (high - low);
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

  /// A decoder reads up to this many bytes past what the encoder flushed; more means the
  /// stream was cut or corrupt.
  static constexpr std::size_t kAllowedOverrun = 4;
  /// Whether the decoder has read past kAllowedOverrun (RangeDecoder::check() throws then).
  bool overran() const { return overrun > kAllowedOverrun; }
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
  /// Takes the parts [low, high) of 2^15 parts of r = range >> 15 each (FrequencyModel::decode());
  /// `last`: the last part, which also takes the range's remainder.
  void take_part(std::uint32_t r, std::uint32_t low, std::uint32_t high, bool last) {
    const std::uint32_t start = r * low;
    code -= start;
    range = last ? range - start : r * (high - low);
    while (range < RangeEncoder::kTop) {
      range <<= 8;
      code = (code << 8) | next_byte();
    }
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

/// An adaptive distribution over N symbols (N a power of two, 2 .. 64), coded in one step: the
/// coder's range is split into 2^15 parts, each symbol holding at least Floor of them (so a
/// symbol costs at least -log2(1 - (N - 1) Floor / 2^15) bits: a decoder can bound how many
/// symbols a stream holds) and the rest in proportion to its count (each symbol seen adds
/// kIncrement; the counts halve past kLimit). The parts are recomputed from the counts after 1, 2,
/// 4, ... symbols, then every kMaxInterval; a decoder finds its symbol by a branch-free binary
/// search. Replaces log2(N) binary decisions (one range step and one model update each) by one
/// range step and a counter increment.
template <unsigned N, std::uint32_t Floor = 2>
class FrequencyModel {
 public:
  static_assert(N >= 2 && N <= 64 && (N & (N - 1)) == 0, "N is a power of two");
  static_assert(Floor >= 1 && Floor * N < (1u << 14), "the floors leave most parts to counts");
  static constexpr unsigned kPartBits = 15;
  static constexpr std::uint32_t kParts = 1u << kPartBits;
  static constexpr std::uint32_t kFloor = Floor, kIncrement = 32, kLimit = 1u << 15;
  static constexpr std::uint16_t kMaxInterval = 32;

  /// Every symbol counted once.
  FrequencyModel() {
    count_.fill(1);
    total_ = N;
    rebuild();
  }
  /// Starting from `counts` (each >= 1, summing to at most kLimit): a prior that makes the
  /// first occurrences of likely symbols cheap.
  explicit FrequencyModel(const std::array<std::uint16_t, N>& counts) : count_(counts) {
    for (std::uint16_t c : count_) total_ += c;
    rebuild();
  }

  /// Codes `symbol` (< N) and counts it.
  void encode(RangeEncoder& enc, unsigned symbol) {
    enc.encode_part(part_[symbol], part_[symbol + 1], symbol == N - 1);
    update(symbol);
  }
  /// The next symbol (< N), counted.
  unsigned decode(RangeDecoder& dec) {
    RangeDecoder::Session s(dec);
    return decode(s.core);
  }
  /// The same on a core a caller holds (RangeDecoder::Session).
  [[gnu::always_inline]] unsigned decode(RangeDecoderCore& dec) {
    const std::uint32_t r = dec.range >> kPartBits;
    // The last symbol also takes the range's remainder past r * 2^15.
    const std::uint32_t top = r * kParts - 1u;
    const std::uint32_t code = dec.code < top ? dec.code : top;
    unsigned s = 0;
    for (unsigned step = N / 2; step > 0; step /= 2) s += r * part_[s + step] <= code ? step : 0u;
    dec.take_part(r, part_[s], part_[s + 1], s == N - 1);
    update(s);
    return s;
  }
  /// The cost of coding `symbol` (< N) now, in 1/16ths of a bit (as bit_cost()).
  std::uint32_t cost(unsigned symbol) const {
    return part_cost(static_cast<std::uint32_t>(part_[symbol + 1]) - part_[symbol]);
  }

 private:
  void update(unsigned symbol) {
    count_[symbol] = static_cast<std::uint16_t>(count_[symbol] + kIncrement);
    total_ += kIncrement;
    if (--until_rebuild_ == 0) rebuild();
  }
  void rebuild() {
    if (total_ > kLimit) {
      total_ = 0;
      for (std::uint16_t& c : count_) {
        c = static_cast<std::uint16_t>((c + 1u) / 2u);
        total_ += c;
      }
    }
    // Symbol i's parts: kFloor, and its share of the rest (the last gets what rounding leaves).
    const std::uint64_t scale = (std::uint64_t{kParts - kFloor * N} << 32) / total_;
    std::uint32_t sum = 0;
    for (unsigned i = 0; i < N; ++i) {
      part_[i] = static_cast<std::uint16_t>(kFloor * i + ((sum * scale) >> 32));
      sum += count_[i];
    }
    part_[N] = static_cast<std::uint16_t>(kParts);
    interval_ = static_cast<std::uint16_t>(interval_ < kMaxInterval ? 2 * interval_ : interval_);
    until_rebuild_ = interval_;
  }

  std::array<std::uint16_t, N + 1> part_{};  // symbol i: parts [part_[i], part_[i + 1])
  std::array<std::uint16_t, N> count_{};
  std::uint32_t total_ = 0;
  std::uint16_t interval_ = 1, until_rebuild_ = 1;
};

namespace detail {
/// IntegerModel's head symbols below kIntegerEscape: the magnitude's bits they give (shifted
/// into place), the count of bits below them (at even odds) and the sign.
struct IntegerHead {
  std::uint32_t magnitude;
  std::uint8_t below, negative;
};
inline constexpr unsigned kIntegerHeads = 64, kIntegerEscape = 63;
/// Head symbol 0: 0; 2 m - 1 + negative: +-m for m = 1 .. 15; 31 + 8 (n - 5) + 2 t + negative
/// for bit lengths n = 5 .. 8 of |v| whose two bits below the leading one are t.
constexpr std::array<IntegerHead, kIntegerEscape> integer_heads() {
  std::array<IntegerHead, kIntegerEscape> h{};
  h[0] = {0, 0, 0};
  for (unsigned m = 1; m < 16; ++m)
    for (unsigned negative = 0; negative < 2; ++negative)
      h[2 * m - 1 + negative] = {m, 0, static_cast<std::uint8_t>(negative)};
  for (unsigned n = 5; n <= 8; ++n)
    for (unsigned t = 0; t < 4; ++t)
      for (unsigned negative = 0; negative < 2; ++negative)
        h[31 + 8 * (n - 5) + 2 * t + negative] = {(4u | t) << (n - 3),
                                                  static_cast<std::uint8_t>(n - 3),
                                                  static_cast<std::uint8_t>(negative)};
  return h;
}
/// IntegerModel's prior counts per head symbol: small magnitudes likelier (a residual's
/// distribution before its context has seen any).
constexpr std::array<std::uint16_t, kIntegerHeads> integer_prior() {
  std::array<std::uint16_t, kIntegerHeads> c{};
  c[0] = 24;
  for (unsigned m = 1; m < 16; ++m)
    c[2 * m - 1] = c[2 * m] = static_cast<std::uint16_t>(m < 2 ? 20 : m < 4 ? 12 : m < 8 ? 6 : 3);
  for (unsigned s = 31; s < kIntegerHeads; ++s)
    c[s] = static_cast<std::uint16_t>(s < 39 ? 3 : s < 47 ? 2 : 1);
  return c;
}
}  // namespace detail

/// Signed integers (|v| < 2^31) by one adaptive choice of 64 (FrequencyModel): the values
/// -15 .. 15 exactly, and for bit lengths n = 5 .. 8 of |v| the sign and the two bits below the
/// leading one (the rest at even odds). Lengths 9 .. 32 escape to a second choice of length,
/// their bits and sign at even odds. Residuals within +-15 cost one step; any 32-bit value
/// round-trips.
class IntegerModel {
 public:
  /// Codes `value`.
  void encode(RangeEncoder& enc, std::int32_t value);
  /// What encode(value) would cost now, in 1/16ths of a bit (bit_cost()); changes nothing.
  /// Inline: encoders price several candidate residuals per value.
  std::uint32_t cost(std::int32_t value) const {
    const bool negative = value < 0;
    const std::uint32_t magnitude =
        negative ? 0u - static_cast<std::uint32_t>(value) : static_cast<std::uint32_t>(value);
    if (magnitude < 16) return head_.cost(magnitude == 0 ? 0u : 2 * magnitude - 1 + negative);
    const unsigned n = 32u - static_cast<unsigned>(__builtin_clz(magnitude));
    if (n > kShortLengths)
      return head_.cost(kEscape) + long_length_.cost(n - (kShortLengths + 1)) + 16 * n;
    const unsigned t = (magnitude >> (n - 3)) & 3u;
    return head_.cost(31 + 8 * (n - 5) + 2 * t + negative) + 16 * (n - 3);
  }
  /// The next value.
  std::int32_t decode(RangeDecoder& dec) {
    RangeDecoder::Session s(dec);
    return decode(s.core);
  }
  /// The same on a core a caller holds (RangeDecoder::Session).
  [[gnu::always_inline]] std::int32_t decode(RangeDecoderCore& dec) {
    const unsigned s = head_.decode(dec);
    if (s < kEscape) {
      const Head h = kHeads[s];
      std::uint32_t magnitude = h.magnitude;
      if (h.below > 0) magnitude |= dec.decode_direct(h.below);
      return static_cast<std::int32_t>(h.negative ? 0u - magnitude : magnitude);
    }
    return decode_long(dec);
  }
  /// Three values from three streams (one per model): the three decodes inline, so that the
  /// three decoders' dependency chains overlap. The cores are those of RangeDecoder::Session
  /// objects the caller holds over its whole loop.
  static std::array<std::int32_t, 3> decode_three(IntegerModel& mx, IntegerModel& my,
                                                  IntegerModel& mz, RangeDecoderCore& dx,
                                                  RangeDecoderCore& dy, RangeDecoderCore& dz) {
    return {mx.decode(dx), my.decode(dy), mz.decode(dz)};
  }

 private:
  using Head = detail::IntegerHead;
  static constexpr unsigned kEscape = detail::kIntegerEscape, kShortLengths = 8;
  static constexpr std::array<Head, kEscape> kHeads = detail::integer_heads();

  std::int32_t decode_long(RangeDecoderCore& dec);
  FrequencyModel<detail::kIntegerHeads> head_{detail::integer_prior()};
  FrequencyModel<32> long_length_;  // lengths 9 .. 32 as 0 .. 23
};

}  // namespace meshflow::compress
