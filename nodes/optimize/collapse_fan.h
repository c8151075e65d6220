#pragma once
// The faces around a vertex u that a half-edge collapse u -> v moves, one lane per face, so that
// the geometric checks of every candidate v run as one straight loop the compiler vectorises
// (8 faces per AVX2 instruction where the CPU has it): the needle test of the decimation's
// penalty and the turn / degeneracy test of its validity. Used by qem_decimation.cpp.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace meshflow {

/// What moving u onto v does to the faces around u: those containing v vanish, the others stay
/// with v in u's place.
struct FanVerdict {
  bool needle = false;  ///< a face gets an inner angle below the minimum
  bool turned = false;  ///< a face turns by more than the limit, flips, or loses its area
  unsigned shared = 0;  ///< the faces containing v (they vanish): 2 inside, 1 on a border
};

/// The fan of one vertex u: faces (u, a, b), counter-clockwise from u. Not thread-safe: one
/// per thread, refilled for every vertex.
class CollapseFan {
 public:
  /// `max_turn_cos`: cosine of the largest turn a face may make; `min_angle_cos_squared`: the
  /// squared cosine of the smallest inner angle that is not a needle.
  CollapseFan(float max_turn_cos, float min_angle_cos_squared);

  /// Starts the fan of the vertex at `pu` with room for `faces` faces.
  void reset(std::size_t faces, const Eigen::Vector3f& pu);
  /// Sets face k (< faces) to (u, a, b); every face must be set, then finish() called.
  void set(std::size_t k, std::uint32_t a, const Eigen::Vector3f& pa, std::uint32_t b,
           const Eigen::Vector3f& pb) {
    row(kAx)[k] = pa.x();
    row(kAy)[k] = pa.y();
    row(kAz)[k] = pa.z();
    row(kBx)[k] = pb.x();
    row(kBy)[k] = pb.y();
    row(kBz)[k] = pb.z();
    ends_[k] = a;
    ends_[lanes_ + k] = b;
    active_[k] = 1;
  }

  std::size_t size() const { return faces_; }
  std::uint32_t a(std::size_t k) const { return ends_[k]; }
  std::uint32_t b(std::size_t k) const { return ends_[lanes_ + k]; }
  /// Computes what check() reads from the faces set (call after the last set()). O(faces).
  void finish();

  /// The faces not containing v, with v in u's place. O(faces), vectorised.
  FanVerdict check(std::uint32_t v, const Eigen::Vector3f& pv) const;
  /// Face k's area vector (a - u) x (b - u) (twice its area, along its normal) and its length.
  Eigen::Vector3f area_vector(std::size_t k) const;
  float area_vector_norm(std::size_t k) const;

  /// Rows of the lane arrays, each lanes long (faces rounded up to the vector width; the extra
  /// lanes are inactive): a, b, the edge b - a and its squared length, the area vector and its
  /// squared length.
  enum Row { kAx, kAy, kAz, kBx, kBy, kBz, kEdgeX, kEdgeY, kEdgeZ, kEdge2, kNx, kNy, kNz, kN2 };

 private:
  static constexpr std::size_t kRows = kN2 + 1;
  float* row(Row r) { return rows_.data() + static_cast<std::size_t>(r) * lanes_; }
  const float* row(Row r) const { return rows_.data() + static_cast<std::size_t>(r) * lanes_; }

  float max_turn_cos_, min_angle_cos2_;
  Eigen::Vector3f pu_ = Eigen::Vector3f::Zero();
  std::size_t faces_ = 0, lanes_ = 0;
  std::vector<float> rows_;
  std::vector<std::uint32_t> ends_;    ///< a of every lane, then b of every lane
  std::vector<std::uint32_t> active_;  ///< 1 for a face, 0 for padding
};

}  // namespace meshflow
