#include "nodes/synthetic/perforated_box.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>

#include "nodes/synthetic/uniform_draw.h"

namespace meshflow::synthetic {
namespace {

// A hole in the box's own frame: its axis k, the two other axes i and j, the disk's centre (a, b)
// in the (i, j) plane and the stretch [lo, hi] of axis k it spans.
struct HoleFrame {
  int k, i, j;
  Eigen::Vector2f centre;
  float radius, lo, hi;
  bool through;
  float floor;  // blind holes: the floor's coordinate along k
};

HoleFrame hole_frame(const BoxHole& hole, const Eigen::Vector3f& half) {
  HoleFrame f;
  f.k = hole.axis;
  f.i = (hole.axis + 1) % 3;
  f.j = (hole.axis + 2) % 3;
  f.centre = Eigen::Vector2f(hole.a, hole.b);
  f.radius = hole.radius;
  const float extent = 2.0f * half[f.k];
  f.through = hole.depth >= extent;
  const float entry = hole.side * half[f.k];
  f.floor = entry - hole.side * std::min(hole.depth, extent);
  f.lo = std::min(entry, f.floor);
  f.hi = std::max(entry, f.floor);
  return f;
}

Eigen::Vector2f in_plane(const Eigen::Vector3f& d, const HoleFrame& f) {
  return Eigen::Vector2f(d[f.i], d[f.j]);
}

// The face of axis k on side s (its outward normal s e_k) minus the disks of the holes that open
// into it.
SurfacePatch face_patch(const Eigen::Vector3f& c, const Eigen::Vector3f& half, int k, float s,
                        const std::vector<HoleFrame>& disks) {
  const int i = (k + 1) % 3, j = (k + 2) % 3;
  const Eigen::Vector2f extent(half[i], half[j]);
  SurfacePatch p;
  p.area = 4.0 * static_cast<double>(extent.x()) * static_cast<double>(extent.y());
  for (const HoleFrame& d : disks) p.area -= M_PI * d.radius * d.radius;
  auto in_a_disk = [disks](const Eigen::Vector2f& uv) {
    for (const HoleFrame& d : disks)
      if ((uv - d.centre).norm() < d.radius) return &d;
    return static_cast<const HoleFrame*>(nullptr);
  };
  p.draw = [=](std::mt19937_64& rng, Eigen::Vector3f& point, Eigen::Vector3f& n) {
    Eigen::Vector2f uv;
    do
      uv = Eigen::Vector2f(static_cast<float>((2.0 * uniform01(rng) - 1.0) * extent.x()),
                           static_cast<float>((2.0 * uniform01(rng) - 1.0) * extent.y()));
    while (in_a_disk(uv) != nullptr);
    point = c;
    point[i] += uv.x();
    point[j] += uv.y();
    point[k] += s * half[k];
    n = Eigen::Vector3f::Zero();
    n[k] = s;
  };
  // The disks lie inside the face and apart, so the nearest point of the face minus the disks
  // is on the rim of the disk a point lies in, else on the rectangle.
  p.distance = [=](const Eigen::Vector3f& q) {
    const Eigen::Vector3f d = q - c;
    const Eigen::Vector2f uv(d[i], d[j]);
    float planar;
    if (const HoleFrame* disk = in_a_disk(uv)) {
      planar = disk->radius - (uv - disk->centre).norm();
    } else {
      const Eigen::Vector2f clamped(std::clamp(uv.x(), -extent.x(), extent.x()),
                                    std::clamp(uv.y(), -extent.y(), extent.y()));
      planar = (uv - clamped).norm();
    }
    return std::hypot(planar, d[k] - s * half[k]);
  };
  return p;
}

// A hole's cylindrical wall; outward (out of the material) is towards the hole's axis.
SurfacePatch wall_patch(const Eigen::Vector3f& c, const HoleFrame& f) {
  SurfacePatch p;
  p.area = 2.0 * M_PI * f.radius * (f.hi - f.lo);
  p.draw = [=](std::mt19937_64& rng, Eigen::Vector3f& point, Eigen::Vector3f& n) {
    const double angle = 2.0 * M_PI * uniform01(rng);
    const Eigen::Vector2f radial(static_cast<float>(std::cos(angle)),
                                 static_cast<float>(std::sin(angle)));
    point = c;
    point[f.i] += f.centre.x() + f.radius * radial.x();
    point[f.j] += f.centre.y() + f.radius * radial.y();
    point[f.k] += f.lo + static_cast<float>(uniform01(rng)) * (f.hi - f.lo);
    n = Eigen::Vector3f::Zero();
    n[f.i] = -radial.x();
    n[f.j] = -radial.y();
  };
  p.distance = [=](const Eigen::Vector3f& q) {
    const Eigen::Vector3f d = q - c;
    const float rho = (in_plane(d, f) - f.centre).norm();
    const float mid = 0.5f * (f.lo + f.hi), half_length = 0.5f * (f.hi - f.lo);
    return std::hypot(rho - f.radius, std::max(std::abs(d[f.k] - mid) - half_length, 0.0f));
  };
  return p;
}

// A blind hole's floor, facing the hole's opening (side s).
SurfacePatch floor_patch(const Eigen::Vector3f& c, const HoleFrame& f, float s) {
  SurfacePatch p;
  p.area = M_PI * f.radius * f.radius;
  p.draw = [=](std::mt19937_64& rng, Eigen::Vector3f& point, Eigen::Vector3f& n) {
    const double angle = 2.0 * M_PI * uniform01(rng);
    const float r = f.radius * static_cast<float>(std::sqrt(uniform01(rng)));
    point = c;
    point[f.i] += f.centre.x() + r * static_cast<float>(std::cos(angle));
    point[f.j] += f.centre.y() + r * static_cast<float>(std::sin(angle));
    point[f.k] += f.floor;
    n = Eigen::Vector3f::Zero();
    n[f.k] = s;
  };
  p.distance = [=](const Eigen::Vector3f& q) {
    const Eigen::Vector3f d = q - c;
    const float rho = (in_plane(d, f) - f.centre).norm();
    return std::hypot(std::max(rho - f.radius, 0.0f), d[f.k] - f.floor);
  };
  return p;
}

}  // namespace

ClosedObject perforated_box_object(const PerforatedBox& box, const std::string& name) {
  const Eigen::Vector3f& c = box.center;
  const Eigen::Vector3f& half = box.half_size;
  std::vector<HoleFrame> frames;
  for (const BoxHole& hole : box.holes) frames.push_back(hole_frame(hole, half));
  ClosedObject o;
  o.name = name;
  for (int k = 0; k < 3; ++k)
    for (float s : {-1.0f, 1.0f}) {
      std::vector<HoleFrame> disks;
      for (std::size_t h = 0; h < box.holes.size(); ++h) {
        const HoleFrame& f = frames[h];
        if (f.k == k && (box.holes[h].side == s || f.through)) disks.push_back(f);
      }
      for ([[maybe_unused]] const HoleFrame& d : disks) {
        assert(std::abs(d.centre.x()) + d.radius < half[(k + 1) % 3]);
        assert(std::abs(d.centre.y()) + d.radius < half[(k + 2) % 3]);
        for ([[maybe_unused]] const HoleFrame& e : disks)
          assert(&d == &e || (d.centre - e.centre).norm() > d.radius + e.radius);
      }
      o.patches.push_back(face_patch(c, half, k, s, disks));
    }
  for (std::size_t h = 0; h < box.holes.size(); ++h) {
    o.patches.push_back(wall_patch(c, frames[h]));
    if (!frames[h].through) o.patches.push_back(floor_patch(c, frames[h], box.holes[h].side));
  }
  o.bounds = Eigen::AlignedBox3f(c - half, c + half);
  return o;
}

ClosedObject perforated_box_object() {
  PerforatedBox box;
  box.center = Eigen::Vector3f(0.011f, -0.017f, 0.009f);  // no face on a grid plane
  box.half_size = Eigen::Vector3f(0.4f, 0.3f, 0.2f);
  box.holes = {
      // Six blind holes in the top (a along x, b along y), down to z = 0.02 at most.
      {2, 1.0f, -0.25f, -0.15f, 0.07f, 0.18f},
      {2, 1.0f, 0.0f, -0.15f, 0.05f, 0.15f},
      {2, 1.0f, 0.25f, -0.15f, 0.08f, 0.12f},
      {2, 1.0f, -0.25f, 0.15f, 0.06f, 0.10f},
      {2, 1.0f, 0.0f, 0.15f, 0.08f, 0.18f},
      {2, 1.0f, 0.25f, 0.15f, 0.05f, 0.16f},
      // Two through along x (a along y, b along z), below the top's holes.
      {0, 1.0f, -0.15f, -0.1f, 0.06f, 0.8f},
      {0, 1.0f, 0.15f, -0.1f, 0.05f, 0.8f},
      // Two blind in the bottom, between the through holes.
      {2, -1.0f, -0.2f, 0.0f, 0.05f, 0.14f},
      {2, -1.0f, 0.2f, 0.0f, 0.07f, 0.12f},
      // Shallow ones in the front (a along z, b along x) and the back.
      {1, -1.0f, 0.1f, -0.1f, 0.04f, 0.06f},
      {1, -1.0f, 0.1f, 0.15f, 0.05f, 0.06f},
      {1, 1.0f, -0.1f, 0.0f, 0.05f, 0.08f},
  };
  return perforated_box_object(box, "perforated-box");
}

ClosedObject pocketed_block_object() {
  PerforatedBox box;
  box.center = Eigen::Vector3f(-0.007f, 0.013f, 0.019f);
  box.half_size = Eigen::Vector3f(0.3f, 0.25f, 0.15f);
  box.holes = {
      {2, 1.0f, -0.15f, -0.1f, 0.06f, 0.2f},  // top: three pockets
      {2, 1.0f, 0.15f, -0.1f, 0.07f, 0.12f},  {2, 1.0f, 0.0f, 0.12f, 0.05f, 0.16f},
      {1, 1.0f, -0.08f, 0.15f, 0.045f, 0.5f},  // through along y (a along z, b along x)
      {0, -1.0f, 0.1f, -0.05f, 0.05f, 0.15f},  // side (a along y, b along z)
  };
  return perforated_box_object(box, "pocketed-block");
}

}  // namespace meshflow::synthetic
