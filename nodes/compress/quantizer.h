#pragma once
// Position quantisation on a cubic grid over a bounding box, and the octahedral mapping of unit
// normals to two integers, for the mesh coders.

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>

namespace meshflow::compress {

/// Integer grid coordinates q = round((p - origin) / step), each in [0, 2^bits).
struct Quantizer {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double step = 1.0;  ///< metres per grid unit; a position moves by at most step / 2 per axis
  unsigned bits = 16;

  /// std::round(x) (halves away from zero) without its library call where 0 <= x < 2^52: the
  /// truncation c of x + 0.5, less one where that sum rounded up to c past x + 0.5 (c - 0.5 is
  /// exact there, so the test is). O(1).
  static double round_half_away(double x) {
    if (!(x >= 0.0 && x < 4503599627370496.0)) return std::round(x);
    auto c = static_cast<std::int64_t>(x + 0.5);
    if (static_cast<double>(c) - 0.5 > x) --c;
    return static_cast<double>(c);
  }
  /// The grid coordinates of p, each clamped to [0, 2^bits).
  std::array<std::int32_t, 3> quantize(const Eigen::Vector3f& p) const {
    const double top = static_cast<double>((std::uint64_t{1} << bits) - 1);
    std::array<std::int32_t, 3> q{};
    for (int a = 0; a < 3; ++a) {
      const double g = round_half_away((static_cast<double>(p[a]) - origin[a]) / step);
      q[static_cast<std::size_t>(a)] = static_cast<std::int32_t>(std::min(std::max(g, 0.0), top));
    }
    return q;
  }
  /// The position of grid coordinates q (metres).
  Eigen::Vector3f position(const std::array<std::int32_t, 3>& q) const {
    return Eigen::Vector3f(static_cast<float>(origin.x() + q[0] * step),
                           static_cast<float>(origin.y() + q[1] * step),
                           static_cast<float>(origin.z() + q[2] * step));
  }
};

/// Bits per octahedral normal coordinate by default: the grid of Draco's default (-qn 10: 2^10 - 1
/// steps across [-1, 1]); decoded normals are within 0.26 degrees of the input's (measured over
/// 2 x 10^6 random directions: 0.237; tests/nodes/compress).
inline constexpr unsigned kDefaultNormalBits = 10;
/// The largest angle (degrees) between a unit input normal and its decoded normal at `bits`
/// (kMinNormalBits .. kMaxNormalBits): 0.25 degrees at 10 bits, doubling per bit fewer. The
/// single-rate coder meets it exactly (normal_step_for()); the octahedral grid of the progressive
/// splits at these bits stays within it (0.237 degrees measured at 10 bits).
inline double normal_error_degrees(unsigned bits) {
  return std::ldexp(0.25, 10 - static_cast<int>(bits));
}
/// The residual grid step (radians) of the single-rate normal coder for a largest error of
/// `error_degrees` (step / sqrt(2), less a thousandth for float rounding).
inline float normal_step_for(double error_degrees) {
  return static_cast<float>(std::sqrt(2.0) * error_degrees * (3.14159265358979323846 / 180.0) *
                            0.999);
}
/// The steps a file may state (radians): largest errors of about 0.0004 .. 40 degrees.
inline constexpr float kMinNormalStep = 1e-5f, kMaxNormalStep = 1.0f;
/// The range of octahedral bits a file may state.
inline constexpr unsigned kMinNormalBits = 4, kMaxNormalBits = 20;

/// A unit normal (zero allowed) as two integers in [-(2^(bits-1) - 1), 2^(bits-1) - 1] on the
/// octahedron (bits in kMinNormalBits .. kMaxNormalBits). Float arithmetic without fused
/// operations, so an encoder and a decoder (native or WebAssembly) agree bit for bit. O(1).
inline std::array<std::int32_t, 2> octahedral_encode(const Eigen::Vector3f& n, unsigned bits) {
  const float l1 = std::abs(n.x()) + std::abs(n.y()) + std::abs(n.z());
  if (!(l1 > 0.0f) || !std::isfinite(l1)) return {0, 0};
  float u = n.x() / l1, v = n.y() / l1;
  if (n.z() < 0.0f) {
    const float pu = u, pv = v;
    u = (1.0f - std::abs(pv)) * (pu >= 0.0f ? 1.0f : -1.0f);
    v = (1.0f - std::abs(pu)) * (pv >= 0.0f ? 1.0f : -1.0f);
  }
  const float top = static_cast<float>((1 << (bits - 1)) - 1);
  return {static_cast<std::int32_t>(std::lround(u * top)),
          static_cast<std::int32_t>(std::lround(v * top))};
}

/// The unit normal of octahedral coordinates at `bits` ({0, 0} decodes to +z). O(1).
inline Eigen::Vector3f octahedral_decode(const std::array<std::int32_t, 2>& q, unsigned bits) {
  const float top = static_cast<float>((1 << (bits - 1)) - 1);
  float u = static_cast<float>(q[0]) / top, v = static_cast<float>(q[1]) / top;
  const float z = 1.0f - std::abs(u) - std::abs(v);
  if (z < 0.0f) {
    const float pu = u, pv = v;
    u = (1.0f - std::abs(pv)) * (pu >= 0.0f ? 1.0f : -1.0f);
    v = (1.0f - std::abs(pu)) * (pv >= 0.0f ? 1.0f : -1.0f);
  }
  return Eigen::Vector3f(u, v, z).normalized();
}

}  // namespace meshflow::compress
