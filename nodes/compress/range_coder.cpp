#include "nodes/compress/range_coder.h"

#include "runtime/error.h"

namespace meshflow::compress {
namespace {

constexpr unsigned kProbabilityBits = 11;
constexpr unsigned kAdaptShift = 5;
constexpr std::uint32_t kTop = 1u << 24;
// A decoder reads up to four bytes ahead of what the encoder flushed; more means the stream
// was cut or corrupt.
constexpr std::size_t kAllowedOverrun = 4;

unsigned bit_length(std::uint32_t v) {
  unsigned n = 0;
  while (v != 0) {
    ++n;
    v >>= 1;
  }
  return n;
}

}  // namespace

void RangeEncoder::encode(BitModel& model, unsigned bit) {
  const std::uint32_t bound = (range_ >> kProbabilityBits) * model.p0;
  if (bit == 0) {
    range_ = bound;
    model.p0 = static_cast<std::uint16_t>(model.p0 +
                                          (((1u << kProbabilityBits) - model.p0) >> kAdaptShift));
  } else {
    low_ += bound;
    range_ -= bound;
    model.p0 = static_cast<std::uint16_t>(model.p0 - (model.p0 >> kAdaptShift));
  }
  while (range_ < kTop) {
    range_ <<= 8;
    shift_low();
  }
}

void RangeEncoder::encode_direct(std::uint32_t value, unsigned count) {
  for (int bit = static_cast<int>(count) - 1; bit >= 0; --bit) {
    range_ >>= 1;
    if ((value >> bit) & 1u) low_ += range_;
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
    : data_(data), size_(size), source_(std::move(source)), what_(std::move(what)) {
  for (int i = 0; i < 5; ++i) code_ = (code_ << 8) | next_byte();
}

std::uint8_t RangeDecoder::next_byte() {
  if (at_ < size_) return data_[at_++];
  ++overrun_;
  return 0;
}

void RangeDecoder::normalize() {
  while (range_ < kTop) {
    range_ <<= 8;
    code_ = (code_ << 8) | next_byte();
  }
}

unsigned RangeDecoder::decode(BitModel& model) {
  const std::uint32_t bound = (range_ >> kProbabilityBits) * model.p0;
  unsigned bit;
  if (code_ < bound) {
    range_ = bound;
    model.p0 = static_cast<std::uint16_t>(model.p0 +
                                          (((1u << kProbabilityBits) - model.p0) >> kAdaptShift));
    bit = 0;
  } else {
    code_ -= bound;
    range_ -= bound;
    model.p0 = static_cast<std::uint16_t>(model.p0 - (model.p0 >> kAdaptShift));
    bit = 1;
  }
  normalize();
  return bit;
}

std::uint32_t RangeDecoder::decode_direct(unsigned count) {
  std::uint32_t value = 0;
  for (unsigned i = 0; i < count; ++i) {
    range_ >>= 1;
    unsigned bit = 0;
    if (code_ >= range_) {
      code_ -= range_;
      bit = 1;
    }
    value = (value << 1) | bit;
    normalize();
  }
  return value;
}

void RangeDecoder::check() const {
  if (overrun_ > kAllowedOverrun)
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

std::int32_t IntegerModel::decode(RangeDecoder& dec) {
  unsigned n = length_low_.decode(dec);
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

}  // namespace meshflow::compress
