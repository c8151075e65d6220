#include "nodes/compress/range_coder.h"

#include <cmath>

#include "runtime/error.h"

namespace meshflow::compress {
namespace {

// The number of significant bits of v (0 for 0).
unsigned bit_length(std::uint32_t v) {
  return v == 0 ? 0u : 32u - static_cast<unsigned>(__builtin_clz(v));
}

// -16 log2(p / 2048) for p = 0 .. 2048 (p = 0, which the models never reach, as p = 1).
std::array<std::uint16_t, RangeEncoder::kOne + 1> make_cost_table() {
  std::array<std::uint16_t, RangeEncoder::kOne + 1> t{};
  for (std::uint32_t p = 1; p <= RangeEncoder::kOne; ++p)
    t[p] = static_cast<std::uint16_t>(
        std::lround(-16.0 * std::log2(static_cast<double>(p) / RangeEncoder::kOne)));
  t[0] = t[1];
  return t;
}

// 16 log2(1 + m / 256) for m = 0 .. 255.
std::array<std::uint8_t, 256> make_fraction_table() {
  std::array<std::uint8_t, 256> t{};
  for (unsigned m = 0; m < 256; ++m)
    t[m] = static_cast<std::uint8_t>(std::lround(16.0 * std::log2(1.0 + m / 256.0)));
  return t;
}

}  // namespace

namespace detail {
const std::array<std::uint16_t, RangeEncoder::kOne + 1> kBitCost = make_cost_table();
const std::array<std::uint8_t, 256> kLog2Fraction = make_fraction_table();
}  // namespace detail

void RangeEncoder::encode_direct(std::uint32_t value, unsigned count) {
  // Up to eight bits per step: the range splits into 2^k equal parts (it stays >= 2^16).
  while (count > 0) {
    const unsigned k = count < 8 ? count : 8;
    count -= k;
    range_ >>= k;
    low_ += std::uint64_t{(value >> count) & ((1u << k) - 1u)} * range_;
    while (range_ < kTop) {
      range_ <<= 8;
      shift_low();
    }
  }
}

void RangeEncoder::shift_low() {
  if (static_cast<std::uint32_t>(low_) < 0xFF000000u || (low_ >> 32) != 0) {
    const auto carry = static_cast<std::uint8_t>(low_ >> 32);
    std::uint8_t temp = cache_;
    do {
      out_.push_back(static_cast<unsigned char>(temp + carry));
      temp = 0xFF;
    } while (--cache_size_ != 0);
    cache_ = static_cast<std::uint8_t>(low_ >> 24);
  }
  ++cache_size_;
  low_ = (low_ & 0x00FFFFFFu) << 8;
}

std::vector<unsigned char> RangeEncoder::finish() {
  for (int i = 0; i < 5; ++i) shift_low();
  return std::move(out_);
}

RangeDecoder::RangeDecoder(const unsigned char* data, std::size_t size, std::string source,
                           std::string what)
    : source_(std::move(source)), what_(std::move(what)) {
  core_.data = data;
  core_.size = size;
  for (int i = 0; i < 5; ++i) core_.code = (core_.code << 8) | core_.next_byte();
}

void RangeDecoder::check() const {
  if (core_.overran()) throw Error(source_, what_, "stream ends early (truncated or corrupt)");
}

void IntegerModel::encode(RangeEncoder& enc, std::int32_t value) {
  const bool negative = value < 0;
  const std::uint32_t magnitude =
      negative ? 0u - static_cast<std::uint32_t>(value) : static_cast<std::uint32_t>(value);
  if (magnitude < 16) {
    head_.encode(enc, magnitude == 0 ? 0u : 2 * magnitude - 1 + negative);
    return;
  }
  const unsigned n = bit_length(magnitude);  // 5 .. 32 (32 only for INT32_MIN)
  if (n <= kShortLengths) {
    const unsigned t = (magnitude >> (n - 3)) & 3u;
    head_.encode(enc, 31 + 8 * (n - 5) + 2 * t + negative);
    enc.encode_direct(magnitude & ((1u << (n - 3)) - 1u), n - 3);
    return;
  }
  head_.encode(enc, kEscape);
  long_length_.encode(enc, n - (kShortLengths + 1));
  enc.encode_direct(magnitude & ((1u << (n - 1)) - 1u), n - 1);
  enc.encode_direct(negative, 1);
}

std::int32_t IntegerModel::decode_long(RangeDecoderCore& dec) {
  // A corrupt stream can name a length past 32 (the value is then garbage; the caller's checks
  // or the checksum catch it).
  unsigned n = long_length_.decode(dec) + kShortLengths + 1;
  if (n > 32) n = 32;
  const std::uint32_t magnitude = (1u << (n - 1)) | dec.decode_direct(n - 1);
  const bool negative = dec.decode_direct(1) != 0;
  return static_cast<std::int32_t>(negative ? 0u - magnitude : magnitude);
}

}  // namespace meshflow::compress
