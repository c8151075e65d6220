// CollapseFan's vectorised checks against a direct oracle: angles by acos, turns by the angle
// between normals, degeneracy by has_area(), on random fans of every size around the vector
// width (padding lanes must never count, whatever an earlier fan left in them, nor lanes reserved
// by reset() and left unset).

#include "nodes/decimate/collapse_fan.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow {
namespace {

constexpr double kDegrees = 3.14159265358979 / 180.0;

struct Face {
  std::uint32_t a, b;
};

// The smallest inner angle of triangle (p, q, r), degrees.
double min_angle_deg(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
  auto angle = [](const Eigen::Vector3d& at, const Eigen::Vector3d& x, const Eigen::Vector3d& y) {
    const Eigen::Vector3d u = (x - at).normalized(), w = (y - at).normalized();
    return std::acos(std::clamp(u.dot(w), -1.0, 1.0)) / kDegrees;
  };
  return std::min({angle(p, q, r), angle(q, r, p), angle(r, p, q)});
}

// The oracle: what moving u onto v does, face by face.
FanVerdict oracle(const std::vector<Eigen::Vector3f>& points, std::uint32_t u,
                  const std::vector<Face>& faces, std::uint32_t v, double max_turn_deg,
                  double min_angle) {
  FanVerdict verdict;
  const Eigen::Vector3f &pu = points[u], &pv = points[v];
  for (const Face& f : faces) {
    if (f.a == v || f.b == v) {
      ++verdict.shared;
      continue;
    }
    const Eigen::Vector3f &pa = points[f.a], &pb = points[f.b];
    const Eigen::Vector3d before = (pa - pu).cross(pb - pu).cast<double>();
    const Eigen::Vector3d after = (pa - pv).cross(pb - pv).cast<double>();
    if (min_angle_deg(pv.cast<double>(), pa.cast<double>(), pb.cast<double>()) < min_angle)
      verdict.needle = true;
    const double turn =
        std::acos(std::clamp(before.normalized().dot(after.normalized()), -1.0, 1.0)) / kDegrees;
    if (!(turn <= max_turn_deg) || !has_area(pv, pa, pb)) verdict.turned = true;
  }
  return verdict;
}

TEST(CollapseFan, MatchesTheOracleOnRandomFans) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.6f, 0.6f);
  const double min_angle = 13.0;
  std::size_t needles = 0, turns = 0, bends = 0, checks = 0;
  for (double max_turn : {60.0, 120.0}) {
    const float max_turn_cos = static_cast<float>(std::cos(max_turn * kDegrees));
    const auto min_cos2 = static_cast<float>(std::pow(std::cos(min_angle * kDegrees), 2));
    CollapseFan fan(max_turn_cos, min_cos2);
    // One fan reused, sizes up and down: a smaller fan's padding lanes hold what a larger one
    // left there (its faces, vertex numbers that are neighbours now), which must not count.
    for (std::size_t size : {17u, 1u, 9u, 3u, 16u, 5u, 8u, 7u, 15u}) {
      for (int trial = 0; trial < 40; ++trial) {
        // u at the origin, a ring of `size` + 1 neighbours around it (jittered, some lifted),
        // faces (u, ring[k], ring[k + 1]).
        std::vector<Eigen::Vector3f> points{Eigen::Vector3f::Zero()};
        for (std::size_t k = 0; k <= size; ++k) {
          const double angle =
              2.0 * 3.14159265358979 * static_cast<double>(k) / static_cast<double>(size + 1);
          points.emplace_back(static_cast<float>(std::cos(angle)) + jitter(rng),
                              static_cast<float>(std::sin(angle)) + jitter(rng), jitter(rng));
        }
        std::vector<Face> faces;
        for (std::size_t k = 0; k < size; ++k)
          faces.push_back({static_cast<std::uint32_t>(k + 1), static_cast<std::uint32_t>(k + 2)});
        // Room for up to two more faces than are set, as for a vertex with removed faces.
        fan.reset(faces.size() + static_cast<std::size_t>(trial % 3), points[0]);
        for (std::size_t k = 0; k < faces.size(); ++k)
          fan.set(k, faces[k].a, points[faces[k].a], faces[k].b, points[faces[k].b]);
        fan.finish(faces.size());
        ASSERT_EQ(fan.size(), faces.size());
        for (std::size_t k = 0; k < faces.size(); ++k) {
          const Eigen::Vector3f& pa = points[faces[k].a];
          const Eigen::Vector3f& pb = points[faces[k].b];
          const Eigen::Vector3f area = (pa - points[0]).cross(pb - points[0]);
          EXPECT_EQ(fan.a(k), faces[k].a);
          EXPECT_EQ(fan.b(k), faces[k].b);
          EXPECT_NEAR((fan.area_vector(k) - area).norm(), 0.0f, 1e-5f * area.norm());
          EXPECT_NEAR(fan.area_vector_norm(k), area.norm(), 1e-5f * area.norm());
        }
        for (std::uint32_t v = 1; v < points.size(); ++v) {
          const FanVerdict got = fan.check(v, points[v]);
          const FanVerdict want = oracle(points, 0, faces, v, max_turn, min_angle);
          SCOPED_TRACE(testing::Message() << "fan of " << size << ", trial " << trial << ", v " << v
                                          << ", turn limit " << max_turn);
          EXPECT_EQ(got.shared, want.shared);
          EXPECT_EQ(got.needle, want.needle);
          EXPECT_EQ(got.turned, want.turned);
          // The edge u-v is bent where its two faces' normals differ by more than 40 degrees.
          std::vector<Eigen::Vector3d> normals;
          std::vector<std::size_t> with_v;
          for (std::size_t k = 0; k < faces.size(); ++k)
            if (faces[k].a == v || faces[k].b == v) {
              normals.push_back((points[faces[k].a] - points[0])
                                    .cross(points[faces[k].b] - points[0])
                                    .cast<double>());
              with_v.push_back(k);
            }
          if (normals.size() >= 2) {
            const bool bent =
                normals[0].normalized().dot(normals[1].normalized()) < std::cos(40.0 * kDegrees);
            EXPECT_EQ(fan.bent_between(with_v[0], with_v[1],
                                       static_cast<float>(std::cos(40.0 * kDegrees))),
                      bent);
            bends += bent ? 1 : 0;
          }
          needles += want.needle ? 1 : 0;
          turns += want.turned ? 1 : 0;
          ++checks;
        }
      }
    }
  }
  // Both outcomes of both tests occur (the fans exercise every branch).
  EXPECT_GT(needles, checks / 10);
  EXPECT_LT(needles, checks * 9 / 10);
  EXPECT_GT(turns, checks / 10);
  EXPECT_LT(turns, checks * 9 / 10);
  EXPECT_GT(bends, checks / 20);
}

TEST(CollapseFan, DegenerateNewFacesAreTurned) {
  // u above the middle of segment (a, b) collinear with v: the face (v, a, b) has no area.
  const std::vector<Eigen::Vector3f> points{{0, 1, 0}, {-1, 0, 0}, {1, 0, 0}, {0.5f, 0, 0}};
  CollapseFan fan(0.5f, 0.0f);
  fan.reset(1, points[0]);
  fan.set(0, 1, points[1], 2, points[2]);
  fan.finish(1);
  const FanVerdict verdict = fan.check(3, points[3]);
  EXPECT_TRUE(verdict.turned);
  EXPECT_EQ(verdict.shared, 0u);
  // Onto a, the face vanishes instead.
  EXPECT_EQ(fan.check(1, points[1]).shared, 1u);
  EXPECT_FALSE(fan.check(1, points[1]).turned);
}

}  // namespace
}  // namespace meshflow
