#include "nodes/compress/attribute_coder.h"

#include <algorithm>
#include <cmath>

#include "nodes/compress/quantizer.h"

namespace meshflow::compress {
namespace {

// A signed axis permutation taking the prediction's dominant axis to +z: exact both ways.
struct Frame {
  int axis = 2;
  float sign = 1.0f;

  static Frame of(const std::array<double, 3>& p) {
    Frame f;
    const double ax = std::abs(p[0]), ay = std::abs(p[1]), az = std::abs(p[2]);
    f.axis = ax >= ay && ax >= az ? 0 : ay >= az ? 1 : 2;
    f.sign = p[static_cast<std::size_t>(f.axis)] < 0.0 ? -1.0f : 1.0f;
    return f;
  }
  Eigen::Vector3f to(const Eigen::Vector3f& n) const {
    return {n[(axis + 1) % 3], n[(axis + 2) % 3], sign * n[axis]};
  }
  Eigen::Vector3f from(const Eigen::Vector3f& m) const {
    Eigen::Vector3f n;
    n[axis] = sign * m.z();
    n[(axis + 1) % 3] = m.x();
    n[(axis + 2) % 3] = m.y();
    return n;
  }
};

// The code `predicted` + `residual`, clamped to the grid: a corrupt stream can give any
// residual (RangeDecoder::check() or the checksum reports the corruption).
std::array<std::int32_t, 2> clamped_code(const std::array<std::int32_t, 2>& predicted,
                                         const std::array<std::int32_t, 2>& residual,
                                         unsigned bits) {
  const auto top = static_cast<std::int64_t>((1u << (bits - 1)) - 1);
  std::array<std::int32_t, 2> q{};
  for (std::size_t a = 0; a < 2; ++a)
    q[a] = static_cast<std::int32_t>(
        std::clamp<std::int64_t>(std::int64_t{predicted[a]} + residual[a], -top, top));
  return q;
}

// Contexts of a normal's residual: no prediction, then flatter to rougher rings.
constexpr std::size_t kNormalContexts = 5;

struct NormalModels {
  IntegerModel first[kNormalContexts];
  IntegerModel second[kNormalContexts][2];  // [context][first residual was 0]
};

// What both sides know of vertex i's normal before its residual: the context, the frame and
// the predicted code.
struct NormalPrediction {
  std::size_t context = 0;
  Frame frame;
  std::array<std::int32_t, 2> code{};
};

// Per vertex: the ring sums and the sum of the faces' cross product lengths.
struct RingSums {
  std::vector<std::array<double, 3>> sum;
  std::vector<double> length;
};

RingSums ring_sums(const DecodedGeometry& g) {
  RingSums r;
  r.sum.assign(g.grid.size(), {0.0, 0.0, 0.0});
  r.length.assign(g.grid.size(), 0.0);
  for (const Triangle& t : g.triangles) {
    const auto& a = g.grid[t[0]];
    const auto& b = g.grid[t[1]];
    const auto& c = g.grid[t[2]];
    // In doubles: the same IEEE operations in encoder and decoder (native or WebAssembly), exact
    // up to 2^26 grid steps, and no overflow for a corrupt stream's grid (any int32, where int64
    // products would overflow).
    double e[3], f[3];
    for (std::size_t k = 0; k < 3; ++k) {
      e[k] = static_cast<double>(b[k]) - a[k];
      f[k] = static_cast<double>(c[k]) - a[k];
    }
    const double n[3] = {e[1] * f[2] - e[2] * f[1], e[2] * f[0] - e[0] * f[2],
                         e[0] * f[1] - e[1] * f[0]};
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (std::uint32_t v : t) {
      for (std::size_t k = 0; k < 3; ++k) r.sum[v][k] += n[k];
      r.length[v] += length;
    }
  }
  return r;
}

NormalPrediction predict_normal(const RingSums& r, std::size_t i, unsigned bits) {
  NormalPrediction p;
  const auto& s = r.sum[i];
  const double norm = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
  if (!(norm > 0.0)) return p;  // context 0, +z
  const double flat = norm / r.length[i];
  p.context = flat >= 0.999 ? 1 : flat >= 0.99 ? 2 : flat >= 0.95 ? 3 : 4;
  p.frame = Frame::of(s);
  const Eigen::Vector3f pf(static_cast<float>(s[0] / norm), static_cast<float>(s[1] / norm),
                           static_cast<float>(s[2] / norm));
  p.code = octahedral_encode(p.frame.to(pf), bits);
  return p;
}

// Vertex adjacency (both directions, sorted, unique) in compressed rows.
struct Adjacency {
  std::vector<std::uint32_t> first, neighbour;
};

Adjacency adjacency(const DecodedGeometry& g) {
  std::vector<std::uint64_t> edges;
  edges.reserve(6 * g.triangles.size());
  for (const Triangle& t : g.triangles)
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a == b) continue;
      edges.push_back(std::uint64_t{a} << 32 | b);
      edges.push_back(std::uint64_t{b} << 32 | a);
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  Adjacency adj;
  adj.first.assign(g.grid.size() + 1, 0);
  for (std::uint64_t e : edges) ++adj.first[(e >> 32) + 1];
  for (std::size_t v = 0; v < g.grid.size(); ++v) adj.first[v + 1] += adj.first[v];
  adj.neighbour.resize(edges.size());
  for (std::size_t k = 0; k < edges.size(); ++k)
    adj.neighbour[k] = static_cast<std::uint32_t>(edges[k] & 0xFFFFFFFFu);
  return adj;
}

// Reversible YCoCg-R lifting on integers (any range).
std::array<std::int32_t, 3> to_ycocg(std::int32_t r, std::int32_t g, std::int32_t b) {
  const std::int32_t co = r - b, t = b + (co >> 1), cg = g - t;
  return {t + (cg >> 1), co, cg};
}
std::array<std::int32_t, 3> from_ycocg(const std::array<std::int32_t, 3>& y) {
  const std::int32_t t = y[0] - (y[2] >> 1), g = y[2] + t, b = t - (y[1] >> 1);
  return {b + y[1], g, b};
}

// Colour contexts: Y by how many decoded neighbours predicted (0 .. 3+), Co and Cg by |dY|.
struct ColorModels {
  IntegerModel y[4], co[4], cg[4];
  static std::size_t chroma_context(std::int32_t dy) {
    const std::int32_t a = dy < 0 ? -dy : dy;
    return a == 0 ? 0 : a <= 2 ? 1 : a <= 8 ? 2 : 3;
  }
};

// The predicted colour of vertex i (mean of its neighbours below i, else vertex i - 1's).
std::array<std::int32_t, 3> predict_color(const Adjacency& adj, const std::vector<Rgb8>& colors,
                                          std::uint32_t i, std::size_t& count) {
  std::int32_t sum[3] = {0, 0, 0};
  count = 0;
  for (std::uint32_t k = adj.first[i]; k < adj.first[i + 1]; ++k) {
    const std::uint32_t n = adj.neighbour[k];
    if (n >= i) break;  // sorted: the rest are decoded later
    sum[0] += colors[n].r;
    sum[1] += colors[n].g;
    sum[2] += colors[n].b;
    ++count;
  }
  if (count == 0) {
    if (i == 0) return {0, 0, 0};
    const Rgb8 c = colors[i - 1];
    return {c.r, c.g, c.b};
  }
  const auto n = static_cast<std::int32_t>(count);
  return {(sum[0] + n / 2) / n, (sum[1] + n / 2) / n, (sum[2] + n / 2) / n};
}

}  // namespace

std::vector<std::array<double, 3>> ring_normal_sums(const DecodedGeometry& g) {
  return ring_sums(g).sum;
}

std::vector<Eigen::Vector3f> recomputed_normals(const DecodedGeometry& g) {
  const std::vector<std::array<double, 3>> sums = ring_normal_sums(g);
  std::vector<Eigen::Vector3f> out(sums.size(), Eigen::Vector3f::UnitZ());
  for (std::size_t i = 0; i < sums.size(); ++i) {
    const Eigen::Vector3d s(sums[i][0], sums[i][1], sums[i][2]);
    const double norm = s.norm();
    if (norm > 0.0) out[i] = (s / norm).cast<float>();
  }
  return out;
}

std::vector<Eigen::Vector3f> encode_normals(const DecodedGeometry& g,
                                            const std::vector<Eigen::Vector3f>& normals,
                                            unsigned bits, RangeEncoder& enc) {
  const RingSums r = ring_sums(g);
  NormalModels m;
  std::vector<Eigen::Vector3f> decoded(g.grid.size());
  for (std::size_t i = 0; i < g.grid.size(); ++i) {
    const NormalPrediction p = predict_normal(r, i, bits);
    const std::array<std::int32_t, 2> q = octahedral_encode(p.frame.to(normals[i]), bits);
    const std::int32_t d0 = q[0] - p.code[0], d1 = q[1] - p.code[1];
    m.first[p.context].encode(enc, d0);
    m.second[p.context][d0 == 0 ? 1 : 0].encode(enc, d1);
    decoded[i] = p.frame.from(octahedral_decode(q, bits));
  }
  return decoded;
}

std::vector<Eigen::Vector3f> decode_normals(const DecodedGeometry& g, unsigned bits,
                                            RangeDecoder& dec) {
  const RingSums r = ring_sums(g);
  NormalModels m;
  std::vector<Eigen::Vector3f> decoded(g.grid.size());
  for (std::size_t i = 0; i < g.grid.size(); ++i) {
    const NormalPrediction p = predict_normal(r, i, bits);
    const std::int32_t d0 = m.first[p.context].decode(dec);
    const std::int32_t d1 = m.second[p.context][d0 == 0 ? 1 : 0].decode(dec);
    decoded[i] = p.frame.from(octahedral_decode(clamped_code(p.code, {d0, d1}, bits), bits));
  }
  return decoded;
}

std::array<std::int32_t, 2> normal_residual(const Eigen::Vector3f& predicted,
                                            const Eigen::Vector3f& n, unsigned bits,
                                            Eigen::Vector3f& decoded) {
  const Frame f = Frame::of({predicted.x(), predicted.y(), predicted.z()});
  const std::array<std::int32_t, 2> p = octahedral_encode(f.to(predicted), bits);
  const std::array<std::int32_t, 2> q = octahedral_encode(f.to(n), bits);
  decoded = f.from(octahedral_decode(q, bits));
  return {q[0] - p[0], q[1] - p[1]};
}

Eigen::Vector3f apply_normal_residual(const Eigen::Vector3f& predicted,
                                      const std::array<std::int32_t, 2>& residual, unsigned bits) {
  const Frame f = Frame::of({predicted.x(), predicted.y(), predicted.z()});
  const std::array<std::int32_t, 2> p = octahedral_encode(f.to(predicted), bits);
  return f.from(octahedral_decode(clamped_code(p, residual, bits), bits));
}

void encode_colors(const DecodedGeometry& g, const std::vector<Rgb8>& colors, RangeEncoder& enc) {
  const Adjacency adj = adjacency(g);
  ColorModels m;
  for (std::uint32_t i = 0; i < g.grid.size(); ++i) {
    std::size_t count = 0;
    const std::array<std::int32_t, 3> p = predict_color(adj, colors, i, count);
    const Rgb8 c = colors[i];
    const std::array<std::int32_t, 3> d = to_ycocg(c.r - p[0], c.g - p[1], c.b - p[2]);
    m.y[std::min<std::size_t>(count, 3)].encode(enc, d[0]);
    const std::size_t ctx = ColorModels::chroma_context(d[0]);
    m.co[ctx].encode(enc, d[1]);
    m.cg[ctx].encode(enc, d[2]);
  }
}

std::vector<Rgb8> decode_colors(const DecodedGeometry& g, RangeDecoder& dec) {
  const Adjacency adj = adjacency(g);
  ColorModels m;
  std::vector<Rgb8> colors(g.grid.size());
  for (std::uint32_t i = 0; i < g.grid.size(); ++i) {
    std::size_t count = 0;
    const std::array<std::int32_t, 3> p = predict_color(adj, colors, i, count);
    std::array<std::int32_t, 3> d{};
    // Residuals of a valid stream are within +-1020; clamping keeps corrupt ones from
    // overflowing (the checksum reports the corruption), Y's before its context negates it.
    d[0] = std::clamp(m.y[std::min<std::size_t>(count, 3)].decode(dec), -4096, 4096);
    const std::size_t ctx = ColorModels::chroma_context(d[0]);
    d[1] = m.co[ctx].decode(dec);
    d[2] = m.cg[ctx].decode(dec);
    for (std::int32_t& x : d) x = std::clamp(x, -4096, 4096);
    const std::array<std::int32_t, 3> rgb = from_ycocg(d);
    const auto channel = [](std::int32_t v) {
      return static_cast<std::uint8_t>(std::clamp(v, 0, 255));
    };
    colors[i] = Rgb8{channel(p[0] + rgb[0]), channel(p[1] + rgb[1]), channel(p[2] + rgb[2])};
  }
  return colors;
}

}  // namespace meshflow::compress
