#include "nodes/synthetic/solids.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace meshflow::synthetic {
namespace {

void add_sample(PointCloud& out, const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
  out.positions.push_back(p);
  out.normals.push_back(n);
}

// Two unit vectors orthogonal to n and to each other.
std::pair<Eigen::Vector3f, Eigen::Vector3f> plane_basis(const Eigen::Vector3f& n) {
  const Eigen::Vector3f helper =
      std::abs(n.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
  const Eigen::Vector3f u = n.cross(helper).normalized();
  return {u, n.cross(u)};
}

}  // namespace

ConvexPolytope box_polytope(const Eigen::Vector3f& c, const Eigen::Vector3f& h) {
  ConvexPolytope p;
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f}) {
      Eigen::Vector3f n = Eigen::Vector3f::Zero();
      n[axis] = sign;
      p.normals.push_back(n);
      p.offsets.push_back(n.dot(c) + h[axis]);
    }
  p.bound = c.norm() + h.norm() + 1e-3f;
  return p;
}

ConvexPolytope chamfered_box(const Eigen::Vector3f& c, const Eigen::Vector3f& h, float chamfer) {
  ConvexPolytope p = box_polytope(c, h);
  const Eigen::Vector3f n = Eigen::Vector3f(1.0f, 1.0f, 0.0f).normalized();
  const Eigen::Vector3f on_cut = c + Eigen::Vector3f(h.x() - chamfer, h.y(), 0.0f);
  p.normals.push_back(n);
  p.offsets.push_back(n.dot(on_cut));
  return p;
}

Solid make_solid(const ConvexPolytope& polytope, float spacing) {
  Solid s;
  s.sdf = [polytope](const Eigen::Vector3f& q) {
    float d = -std::numeric_limits<float>::infinity();
    for (std::size_t i = 0; i < polytope.normals.size(); ++i)
      d = std::max(d, polytope.normals[i].dot(q) - polytope.offsets[i]);
    return d;
  };
  const int steps = static_cast<int>(std::ceil(polytope.bound / spacing));
  for (std::size_t f = 0; f < polytope.normals.size(); ++f) {
    const Eigen::Vector3f n = polytope.normals[f];
    const auto [u, v] = plane_basis(n);
    const Eigen::Vector3f origin = n * polytope.offsets[f];
    for (int j = -steps; j <= steps; ++j)
      for (int i = -steps; i <= steps; ++i) {
        const Eigen::Vector3f q =
            origin + u * (static_cast<float>(i) * spacing) + v * (static_cast<float>(j) * spacing);
        bool inside_others = true;
        for (std::size_t g = 0; g < polytope.normals.size() && inside_others; ++g)
          if (g != f) inside_others = polytope.normals[g].dot(q) - polytope.offsets[g] <= 1e-6f;
        if (inside_others) add_sample(s.samples, q, n);
      }
  }
  return s;
}

Solid make_solid(const Cylinder& cyl, float spacing) {
  Solid s;
  s.sdf = [cyl](const Eigen::Vector3f& q) {
    const Eigen::Vector3f p = q - cyl.center;
    const Eigen::Vector2f d(std::hypot(p.x(), p.y()) - cyl.radius,
                            std::abs(p.z()) - cyl.half_height);
    return std::min(std::max(d.x(), d.y()), 0.0f) + d.cwiseMax(0.0f).norm();
  };
  const int around = std::max(8, static_cast<int>(std::ceil(2.0 * M_PI * cyl.radius / spacing)));
  const int along = std::max(1, static_cast<int>(std::ceil(2.0f * cyl.half_height / spacing)));
  for (int j = 0; j <= along; ++j)
    for (int i = 0; i < around; ++i) {
      const float a = static_cast<float>(2.0 * M_PI * i / around);
      const Eigen::Vector3f n(std::cos(a), std::sin(a), 0.0f);
      const float z = -cyl.half_height + 2.0f * cyl.half_height * static_cast<float>(j) / along;
      add_sample(s.samples, cyl.center + n * cyl.radius + Eigen::Vector3f(0, 0, z), n);
    }
  const int steps = static_cast<int>(std::ceil(cyl.radius / spacing));
  for (float sign : {-1.0f, 1.0f})
    for (int j = -steps; j <= steps; ++j)
      for (int i = -steps; i <= steps; ++i) {
        const Eigen::Vector2f xy(static_cast<float>(i) * spacing, static_cast<float>(j) * spacing);
        if (xy.norm() > cyl.radius) continue;
        add_sample(s.samples, cyl.center + Eigen::Vector3f(xy.x(), xy.y(), sign * cyl.half_height),
                   Eigen::Vector3f(0, 0, sign));
      }
  return s;
}

Solid make_union(const Solid& a, const Solid& b) {
  Solid s;
  s.sdf = [fa = a.sdf, fb = b.sdf](const Eigen::Vector3f& q) { return std::min(fa(q), fb(q)); };
  auto keep_outside = [&](const Solid& from, const Solid& other) {
    for (std::size_t i = 0; i < from.samples.size(); ++i)
      if (other.sdf(from.samples.positions[i]) > 1e-6f)
        add_sample(s.samples, from.samples.positions[i], from.samples.normals[i]);
  };
  keep_outside(a, b);
  keep_outside(b, a);
  return s;
}

}  // namespace meshflow::synthetic
