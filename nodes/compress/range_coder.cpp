#include "nodes/compress/range_coder.h"

#include <cmath>

#include "runtime/error.h"

namespace meshflow::compress {
namespace {

// A decoder reads up to four bytes ahead of what the encoder flushed; more means the stream
// was cut or corrupt.
constexpr std::size_t kAllowedOverrun = 4;

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

}  // namespace

namespace detail {
const std::array<std::uint16_t, RangeEncoder::kOne + 1> kBitCost = make_cost_table();
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
  if (core_.overrun > kAllowedOverrun)
    throw Error(source_, what_, "stream ends early (truncated or corrupt)");
}

void IntegerModel::encode(RangeEncoder& enc, std::int32_t value) {
  const std::uint32_t magnitude =
      value < 0 ? 0u - static_cast<std::uint32_t>(value) : static_cast<std::uint32_t>(value);
  const unsigned n = bit_length(magnitude);  // 0 .. 32 (32 only for INT32_MIN)
  if (n < 15) {
    length_low_.encode(enc, n);
  } else {
    length_low_.encode(enc, 15);
    length_high_.encode(enc, n - 15);
  }
  if (n == 0) return;
  // Bits below the leading one: the top two adaptive, the rest direct.
  unsigned below = n - 1;
  unsigned node = 1;
  for (unsigned k = 0; k < 2 && below > 0; ++k) {
    --below;
    const unsigned b = (magnitude >> below) & 1u;
    enc.encode(top_[n - 1][node], b);
    node = node * 2 + b;
  }
  if (below > 0) enc.encode_direct(magnitude & ((1u << below) - 1u), below);
  enc.encode(sign_[n - 1], value < 0 ? 1u : 0u);
}

std::uint32_t IntegerModel::cost(std::int32_t value) const {
  const std::uint32_t magnitude =
      value < 0 ? 0u - static_cast<std::uint32_t>(value) : static_cast<std::uint32_t>(value);
  const unsigned n = bit_length(magnitude);
  std::uint32_t total =
      n < 15 ? length_low_.cost(n) : length_low_.cost(15) + length_high_.cost(n - 15);
  if (n == 0) return total;
  unsigned below = n - 1;
  unsigned node = 1;
  for (unsigned k = 0; k < 2 && below > 0; ++k) {
    --below;
    const unsigned b = (magnitude >> below) & 1u;
    total += bit_cost(top_[n - 1][node], b);
    node = node * 2 + b;
  }
  return total + 16 * below + bit_cost(sign_[n - 1], value < 0 ? 1u : 0u);
}

std::int32_t IntegerModel::decode(RangeDecoder& decoder) {
  RangeDecoder::Session session(decoder);
  return finish(session.core, length_low_.decode(session.core));
}

// Inlined into decode_three(), where the three calls then overlap.
[[gnu::always_inline]] inline std::int32_t IntegerModel::finish(RangeDecoderCore& dec,
                                                                unsigned length_symbol) {
  unsigned n = length_symbol;
  if (n == 15) n = 15 + length_high_.decode(dec);
  if (n == 0) return 0;
  if (n > 32) n = 32;  // a corrupt stream; the value is garbage, the caller's checks catch it
  std::uint32_t magnitude = 1;
  unsigned below = n - 1;
  unsigned node = 1;
  for (unsigned k = 0; k < 2 && below > 0; ++k) {
    --below;
    const unsigned b = dec.decode(top_[n - 1][node]);
    node = node * 2 + b;
    magnitude = (magnitude << 1) | b;
  }
  if (below > 0) magnitude = (magnitude << below) | dec.decode_direct(below);
  const bool negative = dec.decode(sign_[n - 1]) != 0;
  return static_cast<std::int32_t>(negative ? 0u - magnitude : magnitude);
}

std::array<std::int32_t, 3> IntegerModel::decode_three(IntegerModel& mx, IntegerModel& my,
                                                       IntegerModel& mz, RangeDecoderCore& dx,
                                                       RangeDecoderCore& dy, RangeDecoderCore& dz) {
  unsigned nx = 1, ny = 1, nz = 1;
  for (int level = 0; level < SymbolModel<16>::kLevels; ++level) {
    nx = mx.length_low_.step(dx, nx);
    ny = my.length_low_.step(dy, ny);
    nz = mz.length_low_.step(dz, nz);
  }
  return {mx.finish(dx, SymbolModel<16>::symbol(nx)), my.finish(dy, SymbolModel<16>::symbol(ny)),
          mz.finish(dz, SymbolModel<16>::symbol(nz))};
}

}  // namespace meshflow::compress
