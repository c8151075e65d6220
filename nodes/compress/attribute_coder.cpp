#include "nodes/compress/attribute_coder.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "nodes/compress/quantizer.h"
#include "nodes/compress/vertex_adjacency.h"
#include "runtime/error.h"

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

// The single-rate normal coder's residual contexts: how flat the vertex's ring of decoded faces
// is (no ring, then flatter to rougher: the faces' normals agreeing or not) times how large the
// position grid's noise on the ring's normal is against the step (kNoiseClasses, from the ring's
// mean face size: small faces on a fine grid give noisy predictions).
constexpr std::size_t kFlatnessClasses = 5, kNoiseClasses = 10;
constexpr std::size_t kNormalContexts = kFlatnessClasses * kNoiseClasses;

struct NormalModels {
  IntegerModel first[kNormalContexts];
  IntegerModel second[kNormalContexts][2];  // [context][first residual was 0]
};

// Per vertex: the ring sums, the sum of the faces' cross product lengths and the face count.
struct RingSums {
  std::vector<std::array<double, 3>> sum;
  std::vector<double> length;
  std::vector<std::uint32_t> faces;
};

RingSums ring_sums(const DecodedGeometry& g) {
  RingSums r;
  r.sum.assign(g.grid.size(), {0.0, 0.0, 0.0});
  r.length.assign(g.grid.size(), 0.0);
  r.faces.assign(g.grid.size(), 0);
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
      ++r.faces[v];
    }
  }
  return r;
}

// A unit normal's frame: the normal and two unit tangents.
struct TangentFrame {
  Eigen::Vector3d normal, t1, t2;
  static TangentFrame of(const Eigen::Vector3d& n) {
    TangentFrame f;
    f.normal = n;
    const Eigen::Vector3d helper =
        std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    f.t1 = n.cross(helper).normalized();
    f.t2 = n.cross(f.t1);
    return f;
  }
};

// The residual of unit normal `n` around the prediction: its azimuthal equidistant coordinates in
// the frame (the angle from the prediction along the direction towards n) in steps, rounded.
// The projection's inverse moves no two points further apart than in the plane, so the decoded
// normal is within step / sqrt(2) of n.
std::array<std::int32_t, 2> tangent_code(const TangentFrame& f, const Eigen::Vector3f& input,
                                         double step) {
  const Eigen::Vector3d n = input.cast<double>();
  const double norm = n.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return {0, 0};  // no direction: the prediction
  const double x = f.t1.dot(n), y = f.t2.dot(n), z = f.normal.dot(n);
  const double r = std::hypot(x, y), angle = std::atan2(r, z);
  // Straight opposite the prediction (r = 0, angle = pi) any direction will do.
  const double ux = r > 0.0 ? x / r : 1.0, uy = r > 0.0 ? y / r : 0.0;
  return {static_cast<std::int32_t>(std::lround(angle * ux / step)),
          static_cast<std::int32_t>(std::lround(angle * uy / step))};
}

// The unit normal of a residual from tangent_code() (any code: a corrupt stream's too).
Eigen::Vector3f tangent_normal(const TangentFrame& f, const std::array<std::int32_t, 2>& code,
                               double step) {
  const double a = code[0] * step, b = code[1] * step, angle = std::hypot(a, b);
  if (!(angle > 0.0)) return f.normal.cast<float>();
  const Eigen::Vector3d n =
      std::cos(angle) * f.normal + (std::sin(angle) / angle) * (a * f.t1 + b * f.t2);
  return n.normalized().cast<float>();
}

// What both sides know of vertex i's normal before its residual: the context and the predicted
// unit normal (the ring's area-weighted normal; without a ring the previous vertex's decoded
// normal, +z for the first). The context comes from exactly rounded operations on the ring sums
// and the step (no library functions), so encoder and decoder agree on every platform; the
// prediction itself may differ in its last bits between platforms, which moves a decoded
// normal by as much and desynchronises nothing.
struct NormalPrediction {
  std::size_t context = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

NormalPrediction predict_normal(const RingSums& r, std::size_t i, double step,
                                const Eigen::Vector3f& previous) {
  NormalPrediction p;
  const auto& s = r.sum[i];
  const double norm = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
  if (!(norm > 0.0) || !std::isfinite(norm)) {
    const Eigen::Vector3d prev = previous.cast<double>();
    if (prev.norm() > 0.5) p.normal = prev.normalized();
    return p;  // context 0
  }
  const double flat = norm / r.length[i];
  const std::size_t flatness = flat >= 0.999 ? 1 : flat >= 0.99 ? 2 : flat >= 0.95 ? 3 : 4;
  // The ring normal's noise from positions within half a grid step is about 1 / edge, the edge
  // about sqrt(mean cross product length): in steps, 1 / (step^2 mean length) is its square.
  // Classes by the binary exponent of that (exact), two per factor of 2 in the noise.
  const double inverse_noise = step * step * (r.length[i] / r.faces[i]);
  int exponent = 0;
  std::frexp(inverse_noise, &exponent);
  const int noise = std::clamp(6 - exponent, 0, static_cast<int>(kNoiseClasses) - 1);
  p.context = flatness * kNoiseClasses + static_cast<std::size_t>(noise);
  p.normal = Eigen::Vector3d(s[0] / norm, s[1] / norm, s[2] / norm);
  return p;
}

// Vertex adjacency (both directions, sorted, unique) in compressed rows.
using Adjacency = VertexAdjacency;

Adjacency adjacency(const DecodedGeometry& g) {
  return vertex_adjacency(g.grid.size(), g.triangles);
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

// Colour contexts (LOCO-I style: the neighbourhood's activity predicts the residual's size).
// Y by how much the decoded neighbours' Y differ from the prediction (kActivityClasses) and how
// many there are (0 .. 3+); Co by the neighbours' chroma activity and |dY| (kLumaClasses); Cg by
// those and |dCo| (kCoClasses): a residual at an edge is large on every channel.
constexpr std::size_t kActivityClasses = 10, kLumaClasses = 7, kCoClasses = 4;
// Activity class k: the mean absolute difference is above kActivityEdge[k - 1].
constexpr std::array<std::int32_t, kActivityClasses - 1> kActivityEdge = {1,  2,  3,  5, 8,
                                                                          12, 20, 32, 50};

struct ColorModels {
  std::vector<IntegerModel> y = std::vector<IntegerModel>(kActivityClasses * 4);
  std::vector<IntegerModel> co = std::vector<IntegerModel>(kActivityClasses * kLumaClasses);
  std::vector<IntegerModel> cg =
      std::vector<IntegerModel>(kActivityClasses * kLumaClasses * kCoClasses);
};

// The class of a sum of absolute differences over `count` neighbours (integers only).
std::size_t activity_class(std::int64_t sum, std::int64_t count) {
  std::size_t k = 0;
  while (k < kActivityEdge.size() && kActivityEdge[k] * count < sum) ++k;
  return k;
}

// The class of |v| for the chroma contexts: 0, 1, 2-3, 4-7, 8-15, 16-31, 32+ (capped at `n`).
std::size_t magnitude_class(std::int32_t v, std::size_t n) {
  const std::uint32_t a = static_cast<std::uint32_t>(v < 0 ? -std::int64_t{v} : v);
  const std::size_t bits = a == 0 ? 0 : 32u - static_cast<std::size_t>(__builtin_clz(a));
  return std::min(bits, n - 1);
}

// What both sides know of vertex i's colour: the prediction (the mean of its neighbours below
// i, else vertex i - 1's) and the contexts of its Y residual and chroma activity.
struct ColorPrediction {
  std::array<std::int32_t, 3> rgb{};
  std::size_t y_context = 0, chroma_activity = 0;
};

ColorPrediction predict_color(const Adjacency& adj, const std::vector<Rgb8>& colors,
                              const std::vector<std::array<std::int32_t, 3>>& ycocg,
                              std::uint32_t i) {
  ColorPrediction p;
  std::int32_t sum[3] = {0, 0, 0};
  std::uint32_t count = 0;
  const std::uint32_t begin = adj.first[i];
  std::uint32_t end = begin;
  for (; end < adj.first[i + 1]; ++end) {
    const std::uint32_t n = adj.neighbour[end];
    if (n >= i) break;  // sorted: the rest are decoded later
    sum[0] += colors[n].r;
    sum[1] += colors[n].g;
    sum[2] += colors[n].b;
    ++count;
  }
  if (count == 0) {
    if (i > 0) p.rgb = {colors[i - 1].r, colors[i - 1].g, colors[i - 1].b};
    return p;
  }
  const auto c = static_cast<std::int32_t>(count);
  p.rgb = {(sum[0] + c / 2) / c, (sum[1] + c / 2) / c, (sum[2] + c / 2) / c};
  const std::array<std::int32_t, 3> q = to_ycocg(p.rgb[0], p.rgb[1], p.rgb[2]);
  std::int64_t luma = 0, chroma = 0;
  for (std::uint32_t k = begin; k < end; ++k) {
    const std::array<std::int32_t, 3>& n = ycocg[adj.neighbour[k]];
    luma += std::abs(n[0] - q[0]);
    chroma += std::abs(n[1] - q[1]) + std::abs(n[2] - q[2]);
  }
  p.y_context = activity_class(luma, c) * 4 + std::min<std::size_t>(count, 3);
  p.chroma_activity = activity_class(chroma, c);
  return p;
}

// The Co and Cg model indices of a vertex from its prediction and the residuals before them.
std::size_t co_context(const ColorPrediction& p, std::int32_t dy) {
  return p.chroma_activity * kLumaClasses + magnitude_class(dy, kLumaClasses);
}
std::size_t cg_context(const ColorPrediction& p, std::int32_t dy, std::int32_t dco) {
  return co_context(p, dy) * kCoClasses + magnitude_class(dco, kCoClasses);
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
                                            const std::vector<Eigen::Vector3f>& normals, float step,
                                            RangeEncoder& enc) {
  std::uint32_t step_bits = 0;
  std::memcpy(&step_bits, &step, sizeof step);
  enc.encode_direct(step_bits, 32);
  const RingSums r = ring_sums(g);
  NormalModels m;
  std::vector<Eigen::Vector3f> decoded(g.grid.size());
  Eigen::Vector3f previous = Eigen::Vector3f::Zero();
  for (std::size_t i = 0; i < g.grid.size(); ++i) {
    const NormalPrediction p = predict_normal(r, i, step, previous);
    const TangentFrame f = TangentFrame::of(p.normal);
    const std::array<std::int32_t, 2> q = tangent_code(f, normals[i], step);
    m.first[p.context].encode(enc, q[0]);
    m.second[p.context][q[0] == 0 ? 1 : 0].encode(enc, q[1]);
    decoded[i] = previous = tangent_normal(f, q, step);
  }
  return decoded;
}

std::vector<Eigen::Vector3f> decode_normals(const DecodedGeometry& g, RangeDecoder& dec,
                                            const std::string& source) {
  const std::uint32_t step_bits = dec.decode_direct(32);
  float step = 0.0f;
  std::memcpy(&step, &step_bits, sizeof step);
  if (!(step >= kMinNormalStep && step <= kMaxNormalStep))
    throw Error(source, "attribute section: normal step",
                std::to_string(step) + " radians is outside " + std::to_string(kMinNormalStep) +
                    " .. " + std::to_string(kMaxNormalStep));
  const RingSums r = ring_sums(g);
  NormalModels m;
  std::vector<Eigen::Vector3f> decoded(g.grid.size());
  Eigen::Vector3f previous = Eigen::Vector3f::Zero();
  RangeDecoder::Session session(dec);
  for (std::size_t i = 0; i < g.grid.size(); ++i) {
    const NormalPrediction p = predict_normal(r, i, step, previous);
    std::array<std::int32_t, 2> q{};
    q[0] = m.first[p.context].decode(session.core);
    q[1] = m.second[p.context][q[0] == 0 ? 1 : 0].decode(session.core);
    // A zero residual is the prediction itself (tangent_normal()'s first case, without the frame).
    decoded[i] = previous = q[0] == 0 && q[1] == 0
                                ? p.normal.cast<float>()
                                : tangent_normal(TangentFrame::of(p.normal), q, step);
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
  std::vector<std::array<std::int32_t, 3>> ycocg(g.grid.size());
  for (std::uint32_t i = 0; i < g.grid.size(); ++i) {
    const ColorPrediction p = predict_color(adj, colors, ycocg, i);
    const Rgb8 c = colors[i];
    const std::array<std::int32_t, 3> d = to_ycocg(c.r - p.rgb[0], c.g - p.rgb[1], c.b - p.rgb[2]);
    m.y[p.y_context].encode(enc, d[0]);
    m.co[co_context(p, d[0])].encode(enc, d[1]);
    m.cg[cg_context(p, d[0], d[1])].encode(enc, d[2]);
    ycocg[i] = to_ycocg(c.r, c.g, c.b);
  }
}

std::vector<Rgb8> decode_colors(const DecodedGeometry& g, RangeDecoder& dec) {
  const Adjacency adj = adjacency(g);
  ColorModels m;
  std::vector<Rgb8> colors(g.grid.size());
  std::vector<std::array<std::int32_t, 3>> ycocg(g.grid.size());
  RangeDecoder::Session session(dec);
  for (std::uint32_t i = 0; i < g.grid.size(); ++i) {
    const ColorPrediction p = predict_color(adj, colors, ycocg, i);
    std::array<std::int32_t, 3> d{};
    // Residuals of a valid stream are within +-1020; clamping keeps corrupt ones from
    // overflowing (the checksum reports the corruption), each before a context uses it.
    d[0] = std::clamp(m.y[p.y_context].decode(session.core), -4096, 4096);
    d[1] = std::clamp(m.co[co_context(p, d[0])].decode(session.core), -4096, 4096);
    d[2] = std::clamp(m.cg[cg_context(p, d[0], d[1])].decode(session.core), -4096, 4096);
    const std::array<std::int32_t, 3> rgb = from_ycocg(d);
    const auto channel = [](std::int32_t v) {
      return static_cast<std::uint8_t>(std::clamp(v, 0, 255));
    };
    const Rgb8 c{channel(p.rgb[0] + rgb[0]), channel(p.rgb[1] + rgb[1]),
                 channel(p.rgb[2] + rgb[2])};
    colors[i] = c;
    ycocg[i] = to_ycocg(c.r, c.g, c.b);
  }
  return colors;
}

}  // namespace meshflow::compress
