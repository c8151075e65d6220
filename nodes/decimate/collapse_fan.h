#pragma once
// The faces around a vertex u that a half-edge collapse u -> v moves, eight faces per block, so
// that the geometric checks of every candidate v run as straight vector code (one AVX2
// instruction per operation and block where the CPU has it): the needle test of the
// decimation's penalty and the turn / degeneracy test of its validity. Used by
// qem_decimation.cpp.

#include <Eigen/Core>
#include <cmath>
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
  /// Faces per block (one AVX2 vector of floats).
  static constexpr std::size_t kBlock = 8;
  /// The rows of a block, kBlock lanes each: a, b, the edge b - a and its squared length, the
  /// area vector and its squared length.
  enum Row { kAx, kAy, kAz, kBx, kBy, kBz, kEdgeX, kEdgeY, kEdgeZ, kEdge2, kNx, kNy, kNz, kN2 };
  static constexpr std::size_t kRows = kN2 + 1;
  /// The vertex rows of a block, kBlock lanes each: a's and b's numbers, 1 for a face and 0 for
  /// padding.
  enum EndRow { kA, kB, kActive };
  static constexpr std::size_t kEndRows = kActive + 1;

  /// `max_turn_cos`: cosine of the largest turn a face may make; `min_angle_cos_squared`: the
  /// squared cosine of the smallest inner angle that is not a needle.
  CollapseFan(float max_turn_cos, float min_angle_cos_squared);

  /// Starts the fan of the vertex at `pu` with room for `faces` faces.
  void reset(std::size_t faces, const Eigen::Vector3f& pu);
  /// Sets face k (< the room) to (u, a, b); faces 0 .. count - 1 must be set, then
  /// finish(count) called.
  void set(std::size_t k, std::uint32_t a, const Eigen::Vector3f& pa, std::uint32_t b,
           const Eigen::Vector3f& pb) {
    float* lane = lanes_.data() + lane_index(kRows, kAx, k);
    lane[kAx * kBlock] = pa.x();
    lane[kAy * kBlock] = pa.y();
    lane[kAz * kBlock] = pa.z();
    lane[kBx * kBlock] = pb.x();
    lane[kBy * kBlock] = pb.y();
    lane[kBz * kBlock] = pb.z();
    std::uint32_t* ends = ends_.data() + lane_index(kEndRows, kA, k);
    ends[kA * kBlock] = a;
    ends[kB * kBlock] = b;
  }

  /// Faces in the fan (the count given to finish()).
  std::size_t size() const { return faces_; }
  /// Face k's second corner (u, a, b).
  std::uint32_t a(std::size_t k) const { return end(kA, k); }
  /// Face k's third corner (u, a, b).
  std::uint32_t b(std::size_t k) const { return end(kB, k); }
  /// Ends the fan at `count` faces (at most the room of reset()) and computes what check()
  /// reads from them. O(faces).
  void finish(std::size_t count);

  /// The faces not containing v, with v in u's place. O(faces), vectorised.
  FanVerdict check(std::uint32_t v, const Eigen::Vector3f& pv) const;
  /// Whether faces `first` < `second` (an edge's two faces around u) differ by more than the
  /// angle whose cosine is `min_cos`: the cosine between their area vectors is below it. O(1).
  bool bent_between(std::size_t first, std::size_t second, float min_cos) const {
    return area_vector(first).dot(area_vector(second)) <
           min_cos * area_vector_norm(first) * area_vector_norm(second);
  }
  /// Face k's area vector (a - u) x (b - u) (twice its area, along its normal) and its length.
  Eigen::Vector3f area_vector(std::size_t k) const {
    return {lane(kNx, k), lane(kNy, k), lane(kNz, k)};
  }
  /// The length of area_vector(k).
  float area_vector_norm(std::size_t k) const { return std::sqrt(lane(kN2, k)); }

 private:
  // Where face k's entry of row `row` is in an array of blocks of `rows` rows.
  static constexpr std::size_t lane_index(std::size_t rows, std::size_t row, std::size_t k) {
    return (k / kBlock * rows + row) * kBlock + k % kBlock;
  }
  std::uint32_t end(EndRow r, std::size_t k) const { return ends_[lane_index(kEndRows, r, k)]; }
  float lane(Row r, std::size_t k) const { return lanes_[lane_index(kRows, r, k)]; }

  float max_turn_cos_, min_angle_cos2_;
  Eigen::Vector3f pu_ = Eigen::Vector3f::Zero();
  std::size_t faces_ = 0, blocks_ = 0;
  std::vector<float> lanes_;         ///< kRows x kBlock floats per block
  std::vector<std::uint32_t> ends_;  ///< kEndRows x kBlock numbers per block
};

}  // namespace meshflow
