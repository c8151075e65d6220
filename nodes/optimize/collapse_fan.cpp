#include "nodes/optimize/collapse_fan.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "runtime/simd.h"

namespace meshflow {
namespace {

constexpr std::size_t kLanes = 8;  // one AVX2 vector of floats

// The lanes' arrays of CollapseFan::check(): row r of `rows` starts at rows + r * count, a's
// and b's vertex numbers at ends and ends + count.
struct Lanes {
  const float* rows;
  const std::uint32_t *ends, *active;
  std::size_t count;
  const float* row(CollapseFan::Row r) const { return rows + static_cast<std::size_t>(r) * count; }
};

// Branch-free over every lane (no early exit: a fan has a handful of faces, and a vector of
// them costs what one costs). Per face (u, a, b) without v, with va = a - v, vb = b - v and the
// edge e = b - a that stays:
// - needle: an inner angle of (v, a, b) below the minimum, cos > min_angle_cos, compared
//   squared (no trigonometry);
// - turned: the new area vector va x vb makes more than the largest turn with the old one n,
//   i.e. not (n . m >= cos |n| |m|), compared squared (no square roots), or the new face is
//   degenerate: the lane form of has_area(v, a, b) in runtime/triangle_mesh.cpp.
MESHFLOW_AVX2_CLONES FanVerdict check_lanes(const Lanes& l, std::uint32_t v, float vx, float vy,
                                            float vz, float max_turn_cos, float min_angle_cos2) {
  constexpr float kFlattest = 1e-6f;  // as has_area()
  const float turn_cos2 = max_turn_cos * max_turn_cos;
  const bool acute_limit = max_turn_cos >= 0.0f, obtuse_limit = !acute_limit;
  using R = CollapseFan::Row;
  const float *pax = l.row(R::kAx), *pay = l.row(R::kAy), *paz = l.row(R::kAz);
  const float *pbx = l.row(R::kBx), *pby = l.row(R::kBy), *pbz = l.row(R::kBz);
  const float *pex = l.row(R::kEdgeX), *pey = l.row(R::kEdgeY), *pez = l.row(R::kEdgeZ);
  const float *pe2 = l.row(R::kEdge2), *pnx = l.row(R::kNx), *pny = l.row(R::kNy);
  const float *pnz = l.row(R::kNz), *pn2 = l.row(R::kN2);
  const std::uint32_t *ends_a = l.ends, *ends_b = l.ends + l.count;
  unsigned needle = 0, turned = 0, shared = 0;
  for (std::size_t k = 0; k < l.count; ++k) {
    const float ax = pax[k] - vx, ay = pay[k] - vy, az = paz[k] - vz;
    const float bx = pbx[k] - vx, by = pby[k] - vy, bz = pbz[k] - vz;
    const float ex = pex[k], ey = pey[k], ez = pez[k];
    const float la = ax * ax + ay * ay + az * az, lb = bx * bx + by * by + bz * bz;
    const float le = pe2[k];
    const float at_v = ax * bx + ay * by + az * bz;     // cos at v  ~ va . vb
    const float at_a = -(ax * ex + ay * ey + az * ez);  // cos at a  ~ -va . e
    const float at_b = bx * ex + by * ey + bz * ez;     // cos at b  ~ vb . e
    const bool is_needle = ((at_v > 0.0f) & (at_v * at_v > min_angle_cos2 * la * lb)) |
                           ((at_a > 0.0f) & (at_a * at_a > min_angle_cos2 * la * le)) |
                           ((at_b > 0.0f) & (at_b * at_b > min_angle_cos2 * lb * le));
    // m = va x vb, and the squared areas at the corners a and b (e x va, vb x e).
    const float mx = ay * bz - az * by, my = az * bx - ax * bz, mz = ax * by - ay * bx;
    const float m2 = mx * mx + my * my + mz * mz;
    const float cx = ey * az - ez * ay, cy = ez * ax - ex * az, cz = ex * ay - ey * ax;
    const float dx = by * ez - bz * ey, dy = bz * ex - bx * ez, dz = bx * ey - by * ex;
    const float area_a = cx * cx + cy * cy + cz * cz, area_b = dx * dx + dy * dy + dz * dz;
    const float longest = std::max(std::max(la, le), lb);
    const bool has_area = (m2 > 0.0f) & (area_a > 0.0f) & (area_b > 0.0f) &
                          (m2 >= kFlattest * kFlattest * longest * longest);
    const float nm = pnx[k] * mx + pny[k] * my + pnz[k] * mz;
    const float bound = turn_cos2 * m2 * pn2[k];
    const bool turn_ok = (acute_limit & (nm >= 0.0f) & (nm * nm >= bound)) |
                         (obtuse_limit & ((nm >= 0.0f) | (nm * nm <= bound)));
    const unsigned has_v = static_cast<unsigned>((ends_a[k] == v) | (ends_b[k] == v));
    shared += l.active[k] & has_v;
    const unsigned stays = l.active[k] & (has_v ^ 1u);
    needle |= stays & static_cast<unsigned>(is_needle);
    turned |= stays & static_cast<unsigned>(!(turn_ok & has_area));
  }
  return FanVerdict{needle != 0, turned != 0, shared};
}

// Per lane, from the positions a and b: the edge e = b - a and its squared length, and the area
// vector n = (a - u) x (b - u) and its squared length (the same arithmetic as Eigen's).
MESHFLOW_AVX2_CLONES void derive_lanes(const float* __restrict ax, const float* __restrict ay,
                                       const float* __restrict az, const float* __restrict bx,
                                       const float* __restrict by, const float* __restrict bz,
                                       float ux, float uy, float uz, std::size_t count,
                                       float* __restrict ex, float* __restrict ey,
                                       float* __restrict ez, float* __restrict e2,
                                       float* __restrict nx, float* __restrict ny,
                                       float* __restrict nz, float* __restrict n2) {
  for (std::size_t k = 0; k < count; ++k) {
    ex[k] = bx[k] - ax[k];
    ey[k] = by[k] - ay[k];
    ez[k] = bz[k] - az[k];
    e2[k] = ex[k] * ex[k] + ey[k] * ey[k] + ez[k] * ez[k];
    const float px = ax[k] - ux, py = ay[k] - uy, pz = az[k] - uz;
    const float qx = bx[k] - ux, qy = by[k] - uy, qz = bz[k] - uz;
    nx[k] = py * qz - pz * qy;
    ny[k] = pz * qx - px * qz;
    nz[k] = px * qy - py * qx;
    n2[k] = nx[k] * nx[k] + ny[k] * ny[k] + nz[k] * nz[k];
  }
}

}  // namespace

CollapseFan::CollapseFan(float max_turn_cos, float min_angle_cos_squared)
    : max_turn_cos_(max_turn_cos), min_angle_cos2_(min_angle_cos_squared) {}

void CollapseFan::reset(std::size_t faces, const Eigen::Vector3f& pu) {
  pu_ = pu;
  faces_ = faces;
  lanes_ = (faces + kLanes - 1) / kLanes * kLanes;
  // The arrays only grow: a padding lane keeps whatever finite values an earlier fan left
  // there (or the zeros of the growth); being inactive, it counts in no verdict.
  if (rows_.size() < kRows * lanes_) {
    rows_.resize(kRows * lanes_);
    ends_.resize(2 * lanes_);
    active_.resize(lanes_);
  }
  // The last vector's lanes inactive (set() activates the faces among them): one fixed-size
  // store, not a call per fan.
  if (lanes_ > 0) std::fill_n(active_.data() + (lanes_ - kLanes), kLanes, 0u);
}

void CollapseFan::finish() {
  derive_lanes(row(kAx), row(kAy), row(kAz), row(kBx), row(kBy), row(kBz), pu_.x(), pu_.y(),
               pu_.z(), lanes_, row(kEdgeX), row(kEdgeY), row(kEdgeZ), row(kEdge2), row(kNx),
               row(kNy), row(kNz), row(kN2));
}

Eigen::Vector3f CollapseFan::area_vector(std::size_t k) const {
  return {row(kNx)[k], row(kNy)[k], row(kNz)[k]};
}

float CollapseFan::area_vector_norm(std::size_t k) const { return std::sqrt(row(kN2)[k]); }

FanVerdict CollapseFan::check(std::uint32_t v, const Eigen::Vector3f& pv) const {
  const Lanes lanes{rows_.data(), ends_.data(), active_.data(), lanes_};
  return check_lanes(lanes, v, pv.x(), pv.y(), pv.z(), max_turn_cos_, min_angle_cos2_);
}

}  // namespace meshflow
