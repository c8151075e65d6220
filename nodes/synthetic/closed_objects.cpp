#include "nodes/synthetic/closed_objects.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "nodes/search/closest_point.h"
#include "nodes/synthetic/uniform_draw.h"

namespace meshflow::synthetic {
namespace {

// Offset of every object from the origin, so that no face lies on a grid plane by accident.
const Eigen::Vector3f kOffset(0.013f, -0.021f, 0.007f);

double gaussian(std::mt19937_64& rng) {  // Box-Muller
  const double u1 = std::max(uniform01(rng), 1e-300);
  const double u2 = uniform01(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

SurfacePatch triangle_patch(const Eigen::Vector3f& a, const Eigen::Vector3f& b,
                            const Eigen::Vector3f& c) {
  const Eigen::Vector3f cross = (b - a).cross(c - a);
  SurfacePatch p;
  p.area = 0.5 * static_cast<double>(cross.norm());
  const Eigen::Vector3f normal = cross.normalized();
  p.draw = [a, b, c, normal](std::mt19937_64& rng, Eigen::Vector3f& point, Eigen::Vector3f& n) {
    const float r1 = static_cast<float>(std::sqrt(uniform01(rng)));
    const float r2 = static_cast<float>(uniform01(rng));
    point = (1.0f - r1) * a + r1 * (1.0f - r2) * b + r1 * r2 * c;
    n = normal;
  };
  p.distance = [a, b, c](const Eigen::Vector3f& q) {
    return (q - closest_point_on_triangle(q, a, b, c)).norm();
  };
  return p;
}

// A convex planar polygon, vertices counter-clockwise seen from outside, as a triangle fan.
void add_convex_polygon(std::vector<SurfacePatch>& patches,
                        const std::vector<Eigen::Vector3f>& vertices) {
  for (std::size_t i = 1; i + 1 < vertices.size(); ++i)
    patches.push_back(triangle_patch(vertices[0], vertices[i], vertices[i + 1]));
}

// The face n . x = d of the polytope {x : n_j . x <= d_j for all j}: a large square in the
// plane clipped by every other half-space (Sutherland-Hodgman); counter-clockwise about n.
std::vector<Eigen::Vector3f> polytope_face(const std::vector<Eigen::Vector3f>& normals,
                                           const std::vector<float>& offsets, std::size_t face,
                                           float half_size) {
  const Eigen::Vector3f& n = normals[face];
  const Eigen::Vector3f helper =
      std::abs(n.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
  const Eigen::Vector3f u = n.cross(helper).normalized(), v = n.cross(u);
  const Eigen::Vector3f centre = n * offsets[face];
  std::vector<Eigen::Vector3f> poly = {centre + half_size * (u + v), centre + half_size * (-u + v),
                                       centre + half_size * (-u - v), centre + half_size * (u - v)};
  if ((poly[1] - poly[0]).cross(poly[2] - poly[0]).dot(n) < 0.0f)
    std::reverse(poly.begin(), poly.end());
  for (std::size_t j = 0; j < normals.size(); ++j) {
    if (j == face) continue;
    std::vector<Eigen::Vector3f> clipped;
    for (std::size_t k = 0; k < poly.size(); ++k) {
      const Eigen::Vector3f& p = poly[k];
      const Eigen::Vector3f& q = poly[(k + 1) % poly.size()];
      const float dp = normals[j].dot(p) - offsets[j], dq = normals[j].dot(q) - offsets[j];
      if (dp <= 0.0f) clipped.push_back(p);
      if ((dp < 0.0f && dq > 0.0f) || (dp > 0.0f && dq < 0.0f))
        clipped.push_back(p + (q - p) * (dp / (dp - dq)));
    }
    poly = std::move(clipped);
  }
  return poly;
}

// Every edge of a convex polytope's face is a sharp edge (shared with the face whose plane
// clipped it) and every vertex a corner; each edge is listed by both of its faces, so only
// once here (from the face where it runs in increasing order of its endpoints).
ClosedObject convex_polytope_object(std::string name, const std::vector<Eigen::Vector3f>& normals,
                                    const std::vector<float>& offsets, float half_size) {
  ClosedObject o;
  o.name = std::move(name);
  auto before = [](const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  };
  for (std::size_t f = 0; f < normals.size(); ++f) {
    const std::vector<Eigen::Vector3f> face = polytope_face(normals, offsets, f, half_size);
    add_convex_polygon(o.patches, face);
    for (std::size_t k = 0; k < face.size(); ++k) {
      const Eigen::Vector3f& a = face[k];
      const Eigen::Vector3f& b = face[(k + 1) % face.size()];
      if (before(a, b)) o.feature_edges.emplace_back(a, b);
      const bool known = std::any_of(o.corners.begin(), o.corners.end(),
                                     [&](const auto& c) { return (c - a).norm() < 1e-5f; });
      if (!known) o.corners.push_back(a);
    }
  }
  return o;
}

// Bounds from the patches' samples would be approximate; every object sets them exactly.
ClosedObject finish(ClosedObject o, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  o.bounds = Eigen::AlignedBox3f(lo + kOffset, hi + kOffset);
  return o;
}

}  // namespace

float ClosedObject::distance(const Eigen::Vector3f& p) const {
  float d = std::numeric_limits<float>::infinity();
  for (const SurfacePatch& patch : patches) d = std::min(d, patch.distance(p));
  return d;
}

double ClosedObject::area() const {
  double a = 0.0;
  for (const SurfacePatch& patch : patches) a += patch.area;
  return a;
}

PointCloud ClosedObject::sample(std::size_t count, float noise_sigma, std::uint32_t seed) const {
  std::vector<double> cumulative;
  double total = 0.0;
  for (const SurfacePatch& patch : patches) cumulative.push_back(total += patch.area);
  std::mt19937_64 rng(seed);
  PointCloud cloud;
  cloud.positions.resize(count);
  cloud.normals.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    const double pick = uniform01(rng) * total;
    const std::size_t k = static_cast<std::size_t>(std::min<std::ptrdiff_t>(
        std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin(),
        static_cast<std::ptrdiff_t>(patches.size()) - 1));
    patches[k].draw(rng, cloud.positions[i], cloud.normals[i]);
    if (noise_sigma > 0.0f) {
      const Eigen::Vector3d noise(gaussian(rng), gaussian(rng), gaussian(rng));
      cloud.positions[i] += noise_sigma * noise.cast<float>();
    }
  }
  return cloud;
}

ClosedObject sphere_object() {
  const Eigen::Vector3f c = kOffset;
  const float r = 0.5f;
  ClosedObject o;
  o.name = "sphere";
  SurfacePatch p;
  p.area = 4.0 * M_PI * r * r;
  p.draw = [c, r](std::mt19937_64& rng, Eigen::Vector3f& point, Eigen::Vector3f& n) {
    Eigen::Vector3d g;
    do g = Eigen::Vector3d(gaussian(rng), gaussian(rng), gaussian(rng));
    while (g.squaredNorm() < 1e-12);
    n = g.normalized().cast<float>();
    point = c + r * n;
  };
  p.distance = [c, r](const Eigen::Vector3f& q) { return std::abs((q - c).norm() - r); };
  o.patches.push_back(p);
  return finish(o, Eigen::Vector3f::Constant(-r), Eigen::Vector3f::Constant(r));
}

ClosedObject torus_object() {
  const Eigen::Vector3f c = kOffset;
  const float big = 0.4f, small = 0.15f;
  ClosedObject o;
  o.name = "torus";
  SurfacePatch p;
  p.area = 4.0 * M_PI * M_PI * big * small;
  p.draw = [c, big, small](std::mt19937_64& rng, Eigen::Vector3f& point, Eigen::Vector3f& n) {
    double v = 0.0;  // around the tube; accepted with probability (R + r cos v) / (R + r)
    do v = 2.0 * M_PI * uniform01(rng);
    while (uniform01(rng) * (big + small) > big + small * std::cos(v));
    const double u = 2.0 * M_PI * uniform01(rng);
    n = Eigen::Vector3d(std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v))
            .cast<float>();
    const Eigen::Vector3f ring(big * static_cast<float>(std::cos(u)),
                               big * static_cast<float>(std::sin(u)), 0.0f);
    point = c + ring + small * n;
  };
  p.distance = [c, big, small](const Eigen::Vector3f& q) {
    const Eigen::Vector3f d = q - c;
    return std::abs(std::hypot(std::hypot(d.x(), d.y()) - big, d.z()) - small);
  };
  o.patches.push_back(p);
  return finish(o, Eigen::Vector3f(-big - small, -big - small, -small),
                Eigen::Vector3f(big + small, big + small, small));
}

ClosedObject l_shape_object() {
  const float arm = 0.3f, length = 0.8f, height = 0.3f;
  const Eigen::Vector3f shift = kOffset - Eigen::Vector3f(0.4f, 0.4f, 0.15f);
  // The L in the xy plane, counter-clockwise.
  const std::vector<Eigen::Vector2f> outline = {{0, 0},     {length, 0},   {length, arm},
                                                {arm, arm}, {arm, length}, {0, length}};
  auto at = [shift](const Eigen::Vector2f& xy, float z) -> Eigen::Vector3f {
    return Eigen::Vector3f(xy.x(), xy.y(), z) + shift;
  };
  ClosedObject o;
  o.name = "l-shape";
  for (std::size_t k = 0; k < outline.size(); ++k) {  // walls
    const Eigen::Vector2f& a = outline[k];
    const Eigen::Vector2f& b = outline[(k + 1) % outline.size()];
    add_convex_polygon(o.patches, {at(a, 0), at(b, 0), at(b, height), at(a, height)});
  }
  // Caps as two rectangles each: [0, length] x [0, arm] and [0, arm] x [arm, length].
  const Eigen::Vector2f rects[2][2] = {{{0, 0}, {length, arm}}, {{0, arm}, {arm, length}}};
  for (const auto& r : rects) {
    const Eigen::Vector2f lo = r[0], hi = r[1];
    add_convex_polygon(o.patches, {at(lo, height), at({hi.x(), lo.y()}, height), at(hi, height),
                                   at({lo.x(), hi.y()}, height)});
    add_convex_polygon(o.patches,
                       {at(lo, 0), at({lo.x(), hi.y()}, 0), at(hi, 0), at({hi.x(), lo.y()}, 0)});
  }
  for (std::size_t k = 0; k < outline.size(); ++k) {  // outline at both heights, verticals
    const Eigen::Vector2f& a = outline[k];
    const Eigen::Vector2f& b = outline[(k + 1) % outline.size()];
    o.feature_edges.emplace_back(at(a, 0), at(b, 0));
    o.feature_edges.emplace_back(at(a, height), at(b, height));
    o.feature_edges.emplace_back(at(a, 0), at(a, height));
    o.corners.push_back(at(a, 0));
    o.corners.push_back(at(a, height));
  }
  return finish(o, Eigen::Vector3f(0, 0, 0) + shift - kOffset,
                Eigen::Vector3f(length, length, height) + shift - kOffset);
}

ClosedObject chamfered_cube_object() {
  const float h = 0.3f, chamfer = 0.15f;
  std::vector<Eigen::Vector3f> normals;
  std::vector<float> offsets;
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f}) {
      Eigen::Vector3f n = Eigen::Vector3f::Zero();
      n[axis] = sign;
      normals.push_back(n);
      offsets.push_back(n.dot(kOffset) + h);
    }
  const Eigen::Vector3f cut = Eigen::Vector3f(1.0f, 1.0f, 0.0f).normalized();
  normals.push_back(cut);
  offsets.push_back(cut.dot(kOffset + Eigen::Vector3f(h - chamfer, h, 0.0f)));
  ClosedObject o = convex_polytope_object("chamfered-cube", normals, offsets, 4.0f * h);
  return finish(o, Eigen::Vector3f::Constant(-h), Eigen::Vector3f::Constant(h));
}

ClosedObject box_with_hole_object() {
  const float a = 0.4f, b = 0.4f, h = 0.2f, r = 0.15f;
  const Eigen::Vector3f c = kOffset;
  ClosedObject o;
  o.name = "box-with-hole";
  auto at = [c](float x, float y, float z) -> Eigen::Vector3f {
    return c + Eigen::Vector3f(x, y, z);
  };
  // Four side walls, counter-clockwise seen from outside.
  add_convex_polygon(o.patches, {at(-a, -b, -h), at(a, -b, -h), at(a, -b, h), at(-a, -b, h)});
  add_convex_polygon(o.patches, {at(a, -b, -h), at(a, b, -h), at(a, b, h), at(a, -b, h)});
  add_convex_polygon(o.patches, {at(a, b, -h), at(-a, b, -h), at(-a, b, h), at(a, b, h)});
  add_convex_polygon(o.patches, {at(-a, b, -h), at(-a, -b, -h), at(-a, -b, h), at(-a, b, h)});
  for (float side : {-1.0f, 1.0f}) {  // top and bottom: the rectangle minus the hole's disk
    SurfacePatch p;
    p.area = 4.0 * a * b - M_PI * r * r;
    p.draw = [=](std::mt19937_64& rng, Eigen::Vector3f& point, Eigen::Vector3f& n) {
      Eigen::Vector2f xy;
      do
        xy = Eigen::Vector2f(static_cast<float>((2.0 * uniform01(rng) - 1.0) * a),
                             static_cast<float>((2.0 * uniform01(rng) - 1.0) * b));
      while (xy.norm() < r);
      point = at(xy.x(), xy.y(), side * h);
      n = Eigen::Vector3f(0, 0, side);
    };
    p.distance = [=](const Eigen::Vector3f& q) {
      const Eigen::Vector3f d = q - c;
      const Eigen::Vector2f xy(d.x(), d.y());
      const Eigen::Vector2f clamped(std::clamp(xy.x(), -a, a), std::clamp(xy.y(), -b, b));
      const float planar = xy.norm() < r ? r - xy.norm() : (xy - clamped).norm();
      return std::hypot(planar, d.z() - side * h);
    };
    o.patches.push_back(p);
  }
  SurfacePatch wall;  // the hole's wall; outward (out of the material) is towards the axis
  wall.area = 2.0 * M_PI * r * 2.0 * h;
  wall.draw = [=](std::mt19937_64& rng, Eigen::Vector3f& point, Eigen::Vector3f& n) {
    const double u = 2.0 * M_PI * uniform01(rng);
    const Eigen::Vector3f radial(static_cast<float>(std::cos(u)), static_cast<float>(std::sin(u)),
                                 0.0f);
    point = c + r * radial +
            Eigen::Vector3f(0, 0, static_cast<float>((2.0 * uniform01(rng) - 1.0) * h));
    n = -radial;
  };
  wall.distance = [=](const Eigen::Vector3f& q) {
    const Eigen::Vector3f d = q - c;
    return std::hypot(std::hypot(d.x(), d.y()) - r, std::max(std::abs(d.z()) - h, 0.0f));
  };
  o.patches.push_back(wall);
  return finish(o, Eigen::Vector3f(-a, -b, -h), Eigen::Vector3f(a, b, h));
}

namespace {

// An axis-aligned box of half sizes h (plus the common offset).
ClosedObject axis_box_object(const std::string& name, const Eigen::Vector3f& h) {
  std::vector<Eigen::Vector3f> normals;
  std::vector<float> offsets;
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f}) {
      Eigen::Vector3f n = Eigen::Vector3f::Zero();
      n[axis] = sign;
      normals.push_back(n);
      offsets.push_back(n.dot(kOffset) + h[axis]);
    }
  ClosedObject o = convex_polytope_object(name, normals, offsets, 4.0f * h.maxCoeff());
  return finish(o, -h, h);
}

}  // namespace

ClosedObject box_object() { return axis_box_object("box", Eigen::Vector3f(0.4f, 0.3f, 0.25f)); }

ClosedObject thin_plate_object() {
  return axis_box_object("thin-plate", Eigen::Vector3f(0.3f, 0.2f, 0.01f));
}

std::vector<ClosedObject> closed_test_objects() {
  return {sphere_object(),         torus_object(),         l_shape_object(),
          chamfered_cube_object(), box_with_hole_object(), box_object()};
}

std::vector<ClosedObject> all_test_objects() {
  std::vector<ClosedObject> all = closed_test_objects();
  all.push_back(thin_plate_object());
  return all;
}

std::optional<ClosedObject> closed_test_object(const std::string& name) {
  for (ClosedObject& o : all_test_objects())
    if (o.name == name) return std::move(o);
  return std::nullopt;
}

}  // namespace meshflow::synthetic
