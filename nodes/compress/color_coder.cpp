#include "nodes/compress/color_coder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "nodes/compress/vertex_adjacency.h"
#include "runtime/error.h"

namespace meshflow::compress {
namespace {

using Channels = std::array<std::int32_t, 3>;

// The channel orders a stream may choose: coded first, second, third (0 red, 1 green, 2 blue).
constexpr std::array<std::array<std::uint8_t, 3>, 6> kOrders = {
    {{1, 0, 2}, {1, 2, 0}, {0, 1, 2}, {0, 2, 1}, {2, 0, 1}, {2, 1, 0}}};
// Inter-channel coefficients are in 1/2^kCoefficientShift, each an int8 in the stream.
constexpr unsigned kCoefficientShift = 6;

std::int32_t scaled(std::int32_t v) {
  return (v + (1 << (kCoefficientShift - 1))) >> kCoefficientShift;
}

// A reversible map from an RGB residual to the three coded ones: the channels in `order`, the
// second less a times the first, the third less b times the first and c times the second.
struct ColorTransform {
  std::uint8_t order = 0;
  std::int32_t a = 0, b = 0, c = 0;

  // The coded residuals of RGB residual `e`.
  Channels forward(const Channels& e) const {
    const auto& o = kOrders[order];
    const std::int32_t x0 = e[o[0]], x1 = e[o[1]], x2 = e[o[2]];
    return {x0, x1 - scaled(a * x0), x2 - scaled(b * x0 + c * x1)};
  }
  Channels inverse(const Channels& r) const {
    const auto& o = kOrders[order];
    const std::int32_t x1 = r[1] + scaled(a * r[0]);
    Channels e{};
    e[o[0]] = r[0];
    e[o[1]] = x1;
    e[o[2]] = r[2] + scaled(b * r[0] + c * x1);
    return e;
  }
};

// Squared grid distance, each axis's difference clamped to 2^23 (a corrupt stream's grid can
// hold any int32; a valid one far apart only loses weight): below 2^48.
std::uint64_t distance2(const std::array<std::int32_t, 3>& p,
                        const std::array<std::int32_t, 3>& q) {
  constexpr std::int64_t kMaxAxis = std::int64_t{1} << 23;
  std::uint64_t d = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    const std::int64_t t = std::min(std::abs(std::int64_t{p[k]} - q[k]), kMaxAxis);
    d += static_cast<std::uint64_t>(t * t);
  }
  return d;
}

unsigned bit_length(std::uint64_t v) {
  return v == 0 ? 0u : 64u - static_cast<unsigned>(__builtin_clzll(v));
}

// The weight ratio ((nearest + 1) << 16) / (d + 1) (d >= nearest, so at most 2^16): 2^16 for
// the nearest itself, a 32-bit division while the dividend fits (any grid closer than 2^8
// steps), the 64-bit one otherwise; the same quotient in every case.
std::uint32_t weight_ratio(std::uint64_t nearest, std::uint64_t d) {
  if (d == nearest) return 1u << 16;
  if (nearest < 0xFFFFu) {
    if (d >= 0xFFFFFFFFu) return 0;  // the dividend is below 2^32 <= d + 1
    return static_cast<std::uint32_t>(((nearest + 1) << 16)) / static_cast<std::uint32_t>(d + 1);
  }
  return static_cast<std::uint32_t>(((nearest + 1) << 16) / (d + 1));
}

}  // namespace

ColorNeighbourhood color_neighbourhood(VertexAdjacency adjacency,
                                       const std::vector<std::array<std::int32_t, 3>>& grid) {
  ColorNeighbourhood n;
  n.adj = std::move(adjacency);
  const auto vertices = static_cast<std::uint32_t>(grid.size());
  n.decoded_end.resize(vertices);
  n.distance_bits.resize(vertices);
  n.weight.resize(n.adj.neighbour.size());
  std::vector<std::uint64_t> d2;  // the row's squared distances
  for (std::uint32_t i = 0; i < vertices; ++i) {
    const std::uint32_t begin = n.adj.first[i];
    std::uint32_t end = begin;
    std::uint64_t nearest = ~std::uint64_t{0};
    d2.clear();
    // Sorted rows: the neighbours decoded before i come first.
    for (; end < n.adj.first[i + 1] && n.adj.neighbour[end] < i; ++end) {
      d2.push_back(distance2(grid[n.adj.neighbour[end]], grid[i]));
      nearest = std::min(nearest, d2.back());
    }
    n.decoded_end[i] = end;
    if (end == begin) continue;
    n.distance_bits[i] = static_cast<std::uint8_t>(bit_length(nearest + 1));
    for (std::uint32_t k = begin; k < end; ++k) {
      const std::uint64_t r = weight_ratio(nearest, d2[k - begin]);
      n.weight[k] = static_cast<std::uint32_t>((r * r) >> 16);  // r <= 2^16
    }
  }
  return n;
}

namespace {

// What both sides know of vertex i's colour before its residuals: the predicted RGB, the
// decoded neighbours (adjacency row entries [begin, end)) and the bit length of the squared
// distance to the nearest of them plus one.
struct ColorPrediction {
  Channels rgb{};
  std::uint32_t begin = 0, end = 0;
  unsigned distance_bits = 0;
  std::uint32_t count() const { return end - begin; }
};

// The neighbours' colours weighted by (nearest distance^2 + 1)^2 / (distance^2 + 1)^2 in
// 1/2^16 (the nearest weighs 2^16; color_neighbourhood()), rounded; vertex i - 1's colour
// without any, black first.
ColorPrediction predict_color(const ColorNeighbourhood& nb, const std::vector<Rgb8>& colors,
                              std::uint32_t i) {
  ColorPrediction p;
  p.begin = nb.adj.first[i];
  p.end = nb.decoded_end[i];
  if (p.count() == 0) {
    if (i > 0) p.rgb = {colors[i - 1].r, colors[i - 1].g, colors[i - 1].b};
    return p;
  }
  p.distance_bits = nb.distance_bits[i];
  std::uint64_t sum[3] = {0, 0, 0}, total = 0;
  for (std::uint32_t k = p.begin; k < p.end; ++k) {
    const Rgb8 c = colors[nb.adj.neighbour[k]];
    const std::uint64_t w = nb.weight[k];
    sum[0] += w * c.r;
    sum[1] += w * c.g;
    sum[2] += w * c.b;
    total += w;  // >= 2^16: the nearest's
  }
  for (std::size_t k = 0; k < 3; ++k)
    p.rgb[k] = static_cast<std::int32_t>((sum[k] + total / 2) / total);
  return p;
}

// Contexts. Each channel's expected residual size s (in 1/16) is the mean over the decoded
// neighbours of how far each is from the prediction and of the residual it was coded with, plus
// the mean residual so far at vertices whose nearest decoded neighbour is as far (by
// distance_bits, halved past kLearntWindow vertices); the second and third add half the first's
// residual. Classes of s: two per factor of 2 in 1 + s (kScaleClasses). The first channel's
// models also by the distance (kDistanceClasses); the second by the first's residual size, the
// third by the first's and the second's (kMagnitudeClasses each).
constexpr std::size_t kScaleClasses = 12, kDistanceClasses = 4, kMagnitudeClasses = 4;
constexpr std::size_t kDistanceBits = 50;  // distance_bits <= 49 (distance2() < 2^48)
constexpr std::uint32_t kLearntWindow = 64;

struct ColorContexts {
  std::vector<IntegerModel> first = std::vector<IntegerModel>(kScaleClasses * kDistanceClasses);
  std::vector<IntegerModel> second = std::vector<IntegerModel>(kScaleClasses * kMagnitudeClasses);
  std::vector<IntegerModel> third =
      std::vector<IntegerModel>(kScaleClasses * kMagnitudeClasses * kMagnitudeClasses);
  // Per distance_bits: the channels' residual magnitude sums and the vertex count.
  std::array<std::array<std::uint32_t, 4>, kDistanceBits> learnt{};
  // Per vertex: the magnitudes its channels were coded with (capped).
  std::vector<std::array<std::uint16_t, 3>> magnitude;
};

std::uint32_t magnitude(std::int32_t v) {
  return static_cast<std::uint32_t>(v < 0 ? -std::int64_t{v} : v);
}

// |v|'s class: 0, 1, 2-3, 4+ (kMagnitudeClasses).
std::size_t magnitude_class(std::int32_t v) {
  return std::min<std::size_t>(bit_length(magnitude(v)), kMagnitudeClasses - 1);
}

// The class of an expected size s16 (1/16ths): floor(2 log2(1 + s)), capped.
std::size_t scale_class(std::uint64_t s16) {
  const std::uint64_t x = 16 + std::min<std::uint64_t>(s16, std::uint64_t{1} << 24);
  const unsigned n = bit_length(x) - 1;  // >= 4
  const std::size_t c = 2 * n + (x * x >= (std::uint64_t{1} << (2 * n + 1)) ? 1 : 0) - 8;
  return std::min(c, kScaleClasses - 1);
}

// The channels' expected sizes s16 (before the later ones' share of the first residual), and
// the first channel's model index.
struct ColorScales {
  std::uint64_t s16[3] = {0, 0, 0};
  std::size_t first = 0;
};

ColorScales color_scales(const VertexAdjacency& adj, const std::vector<Rgb8>& colors,
                         const ColorContexts& m, const ColorTransform& t,
                         const ColorPrediction& p) {
  ColorScales s;
  if (p.count() == 0) return s;
  std::uint64_t sum[3] = {0, 0, 0};
  for (std::uint32_t k = p.begin; k < p.end; ++k) {
    const std::uint32_t n = adj.neighbour[k];
    const Channels f =
        t.forward({colors[n].r - p.rgb[0], colors[n].g - p.rgb[1], colors[n].b - p.rgb[2]});
    for (std::size_t c = 0; c < 3; ++c) sum[c] += magnitude(f[c]) + m.magnitude[n][c];
  }
  const auto& learnt = m.learnt[std::min<std::size_t>(p.distance_bits, kDistanceBits - 1)];
  for (std::size_t c = 0; c < 3; ++c)
    s.s16[c] = 16 * sum[c] / p.count() + (learnt[3] > 0 ? 16u * learnt[c] / learnt[3] : 0u);
  const std::size_t distance =
      std::clamp<std::size_t>(p.distance_bits / 2, 2, kDistanceClasses + 1) - 2;
  s.first = scale_class(s.s16[0]) * kDistanceClasses + distance;
  return s;
}

std::size_t second_context(const ColorPrediction& p, const ColorScales& s, std::int32_t r0) {
  const std::size_t scale = p.count() == 0 ? 0 : scale_class(s.s16[1] + 8 * magnitude(r0));
  return scale * kMagnitudeClasses + magnitude_class(r0);
}

std::size_t third_context(const ColorPrediction& p, const ColorScales& s, std::int32_t r0,
                          std::int32_t r1) {
  const std::size_t scale = p.count() == 0 ? 0 : scale_class(s.s16[2] + 8 * magnitude(r0));
  return (scale * kMagnitudeClasses + magnitude_class(r0)) * kMagnitudeClasses +
         magnitude_class(r1);
}

// After vertex i's residuals r: its magnitudes, and what its distance class has needed.
void learn(ColorContexts& m, const ColorPrediction& p, std::uint32_t i, const Channels& r) {
  for (std::size_t c = 0; c < 3; ++c)
    m.magnitude[i][c] = static_cast<std::uint16_t>(std::min<std::uint32_t>(magnitude(r[c]), 65535));
  if (p.count() == 0) return;
  auto& learnt = m.learnt[std::min<std::size_t>(p.distance_bits, kDistanceBits - 1)];
  for (std::size_t c = 0; c < 3; ++c) learnt[c] += m.magnitude[i][c];
  if (++learnt[3] > kLearntWindow)
    for (std::uint32_t& v : learnt) v >>= 1;
}

// The encoder's choice of transform: per order, least-squares coefficients (the second channel's
// residual on the first's, the third's on both; clamped to int8) and the order whose coded
// residuals have the smallest sum of log2(1 + |r|).
ColorTransform choose_transform(const std::vector<Channels>& residuals) {
  double moment[3][3] = {};
  for (const Channels& e : residuals)
    for (std::size_t a = 0; a < 3; ++a)
      for (std::size_t b = 0; b < 3; ++b) moment[a][b] += static_cast<double>(e[a]) * e[b];
  const auto coefficient = [](double v) {
    return static_cast<std::int32_t>(
        std::clamp(std::lround(v * (1 << kCoefficientShift)), -128L, 127L));
  };
  // log2(1 + m) for the residuals of valid streams (|r| <= 1275), looked up.
  static const std::array<double, 2048> log2_one_plus = [] {
    std::array<double, 2048> t{};
    for (std::size_t m = 0; m < t.size(); ++m) t[m] = std::log2(1.0 + static_cast<double>(m));
    return t;
  }();
  ColorTransform best;
  double best_cost = -1.0;
  for (std::size_t o = 0; o < kOrders.size(); ++o) {
    const auto& ord = kOrders[o];
    const auto s = [&](std::size_t a, std::size_t b) { return moment[ord[a]][ord[b]]; };
    ColorTransform t;
    t.order = static_cast<std::uint8_t>(o);
    if (s(0, 0) > 0.0) t.a = coefficient(s(0, 1) / s(0, 0));
    const double det = s(0, 0) * s(1, 1) - s(0, 1) * s(0, 1);
    if (det > 1e-9 * s(0, 0) * s(1, 1)) {
      t.b = coefficient((s(0, 2) * s(1, 1) - s(1, 2) * s(0, 1)) / det);
      t.c = coefficient((s(1, 2) * s(0, 0) - s(0, 2) * s(0, 1)) / det);
    } else if (s(0, 0) > 0.0) {
      t.b = coefficient(s(0, 2) / s(0, 0));
    }
    double cost = 0.0;
    for (const Channels& e : residuals)
      for (std::int32_t r : t.forward(e)) {
        const std::uint32_t m = magnitude(r);
        cost += m < log2_one_plus.size() ? log2_one_plus[m] : std::log2(1.0 + m);
      }
    if (best_cost < 0.0 || cost < best_cost) {
      best = t;
      best_cost = cost;
    }
  }
  return best;
}

}  // namespace

void encode_colors(const DecodedGeometry& g, const std::vector<Rgb8>& colors, RangeEncoder& enc) {
  const ColorNeighbourhood nb =
      color_neighbourhood(vertex_adjacency(g.grid.size(), g.triangles), g.grid);
  const VertexAdjacency& adj = nb.adj;
  const auto vertices = static_cast<std::uint32_t>(g.grid.size());
  std::vector<ColorPrediction> predictions(vertices);
  std::vector<Channels> residuals;
  residuals.reserve(vertices);
  for (std::uint32_t i = 0; i < vertices; ++i) {
    predictions[i] = predict_color(nb, colors, i);
    const Channels& p = predictions[i].rgb;
    if (predictions[i].count() > 0)
      residuals.push_back({colors[i].r - p[0], colors[i].g - p[1], colors[i].b - p[2]});
  }
  const ColorTransform t = choose_transform(residuals);
  enc.encode_direct(t.order, 3);
  for (std::int32_t v : {t.a, t.b, t.c}) enc.encode_direct(static_cast<std::uint8_t>(v), 8);
  ColorContexts m;
  m.magnitude.resize(vertices);
  for (std::uint32_t i = 0; i < vertices; ++i) {
    const ColorPrediction& p = predictions[i];
    const ColorScales s = color_scales(adj, colors, m, t, p);
    const Channels r =
        t.forward({colors[i].r - p.rgb[0], colors[i].g - p.rgb[1], colors[i].b - p.rgb[2]});
    m.first[s.first].encode(enc, r[0]);
    const std::size_t second = second_context(p, s, r[0]);
    m.second[second].encode(enc, r[1]);
    m.third[third_context(p, s, r[0], r[1])].encode(enc, r[2]);
    learn(m, p, i, r);
  }
}

std::vector<Rgb8> decode_colors(const ColorNeighbourhood& nb, RangeDecoder& dec,
                                const std::string& source) {
  const VertexAdjacency& adj = nb.adj;
  const auto vertices = static_cast<std::uint32_t>(nb.decoded_end.size());
  ColorTransform t;
  const std::uint32_t order = dec.decode_direct(3);
  if (order >= kOrders.size())
    throw Error(source, "attribute section: colour channel order",
                std::to_string(order) + " is not 0 .. " + std::to_string(kOrders.size() - 1));
  t.order = static_cast<std::uint8_t>(order);
  for (std::int32_t* v : {&t.a, &t.b, &t.c})
    *v = static_cast<std::int32_t>(dec.decode_direct(8) ^ 0x80u) - 128;  // the int8's byte
  ColorContexts m;
  m.magnitude.resize(vertices);
  std::vector<Rgb8> colors(vertices);
  RangeDecoder::Session session(dec);
  for (std::uint32_t i = 0; i < vertices; ++i) {
    const ColorPrediction p = predict_color(nb, colors, i);
    const ColorScales s = color_scales(adj, colors, m, t, p);
    // Residuals of a valid stream are within +-1275; clamping keeps corrupt ones from
    // overflowing (the checksum reports the corruption), each before a context uses it.
    Channels r{};
    r[0] = std::clamp(m.first[s.first].decode(session.core), -4096, 4096);
    const std::size_t second = second_context(p, s, r[0]);
    r[1] = std::clamp(m.second[second].decode(session.core), -4096, 4096);
    r[2] = std::clamp(m.third[third_context(p, s, r[0], r[1])].decode(session.core), -4096, 4096);
    const Channels e = t.inverse(r);
    const auto channel = [](std::int32_t v) {
      return static_cast<std::uint8_t>(std::clamp(v, 0, 255));
    };
    colors[i] = Rgb8{channel(p.rgb[0] + e[0]), channel(p.rgb[1] + e[1]), channel(p.rgb[2] + e[2])};
    learn(m, p, i, r);
  }
  return colors;
}

}  // namespace meshflow::compress
