#include "nodes/search/closest_point.h"

namespace meshflow {

Eigen::Vector3f closest_point_on_triangle(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                                          const Eigen::Vector3f& b, const Eigen::Vector3f& c) {
  const Eigen::Vector3f ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return a;
  const Eigen::Vector3f bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0f && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
    const float denom = d1 - d3;
    return denom > 0.0f ? Eigen::Vector3f(a + ab * (d1 / denom)) : a;
  }
  const Eigen::Vector3f cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0f && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
    const float denom = d2 - d6;
    return denom > 0.0f ? Eigen::Vector3f(a + ac * (d2 / denom)) : a;
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
    const float denom = (d4 - d3) + (d5 - d6);
    return denom > 0.0f ? Eigen::Vector3f(b + (c - b) * ((d4 - d3) / denom)) : b;
  }
  const float sum = va + vb + vc;
  if (!(sum > 0.0f)) {  // degenerate triangle: nearest of its three edges
    auto on_segment = [&](const Eigen::Vector3f& s, const Eigen::Vector3f& e) -> Eigen::Vector3f {
      const Eigen::Vector3f d = e - s;
      const float len2 = d.squaredNorm();
      if (!(len2 > 0.0f)) return s;
      return s + d * std::min(1.0f, std::max(0.0f, d.dot(p - s) / len2));
    };
    Eigen::Vector3f best = on_segment(a, b);
    for (const Eigen::Vector3f& q : {on_segment(b, c), on_segment(c, a)})
      if ((q - p).squaredNorm() < (best - p).squaredNorm()) best = q;
    return best;
  }
  const float v = vb / sum, w = vc / sum;
  return a + ab * v + ac * w;
}

}  // namespace meshflow
