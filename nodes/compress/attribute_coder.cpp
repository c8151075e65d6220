#include "nodes/compress/attribute_coder.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "nodes/compress/quantizer.h"
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

}  // namespace meshflow::compress
