#include "nodes/optimize/qem_decimation.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <queue>
#include <tuple>
#include <vector>

namespace meshflow {
namespace {

using Quadric = Eigen::Matrix4d;
constexpr double kDegrees = 3.14159265358979 / 180.0;

struct Candidate {
  double cost;
  std::uint32_t u, v;    // collapse u into v
  std::uint32_t su, sv;  // stamps of u and v when queued
  bool operator>(const Candidate& o) const {
    return std::tie(cost, u, v) > std::tie(o.cost, o.u, o.v);
  }
};

class Decimator {
 public:
  Decimator(const TriangleMesh& mesh, const QemConfig& config, QemReport& report)
      : cfg_(config),
        report_(report),
        p_(mesh.vertices),
        t_(mesh.triangles),
        tri_alive_(mesh.triangles.size(), 1),
        around_(mesh.vertices.size()),
        q_(mesh.vertices.size(), Quadric::Zero()),
        stamp_(mesh.vertices.size(), 0),
        alive_(mesh.triangles.size()),
        cos_turn_(std::cos(config.max_normal_turn_deg * kDegrees)),
        cos_border_(std::cos(config.max_border_turn_deg * kDegrees)),
        cos_sharp_(std::cos(config.sharp_edge_deg * kDegrees)),
        cos2_min_angle_(
            static_cast<float>(std::pow(std::cos(config.min_angle_deg * kDegrees), 2))) {
    for (std::uint32_t t = 0; t < t_.size(); ++t) {
      for (std::uint32_t v : t_[t]) around_[v].push_back(t);
      // Area-weighted plane quadric of the face, added to its corners.
      const Eigen::Vector3d a = p_[t_[t][0]].cast<double>();
      const Eigen::Vector3d n =
          (p_[t_[t][1]].cast<double>() - a).cross(p_[t_[t][2]].cast<double>() - a);
      const double area2 = n.norm();
      if (!(area2 > 0.0)) continue;
      Eigen::Vector4d plane;
      plane << n / area2, -(n / area2).dot(a);
      const Quadric k = 0.5 * area2 * plane * plane.transpose();
      for (std::uint32_t v : t_[t]) q_[v] += k;
    }
  }

  TriangleMesh run(std::size_t target) {
    std::vector<std::uint64_t> edges;
    for (const Triangle& t : t_)
      for (int i = 0; i < 3; ++i) {
        const std::uint32_t a = t[static_cast<std::size_t>(i)],
                            b = t[static_cast<std::size_t>((i + 1) % 3)];
        edges.push_back(std::uint64_t{std::min(a, b)} << 32 | std::max(a, b));
      }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    for (std::uint64_t e : edges) {
      push(static_cast<std::uint32_t>(e >> 32), static_cast<std::uint32_t>(e));
      push(static_cast<std::uint32_t>(e), static_cast<std::uint32_t>(e >> 32));
    }
    while (alive_ > target && !heap_.empty()) {
      const Candidate c = heap_.top();
      heap_.pop();
      if (c.su != stamp_[c.u] || c.sv != stamp_[c.v] || around_[c.u].empty()) continue;
      const double cost = collapse_cost(c.u, c.v);
      if (cost > c.cost * (1.0 + 1e-9) + 1e-30) {  // penalties changed since it was queued
        heap_.push(Candidate{cost, c.u, c.v, c.su, c.sv});
        continue;
      }
      if (!valid(c.u, c.v)) continue;
      collapse(c.u, c.v);
    }
    return compact();
  }

 private:
  Eigen::Vector3f normal(const Triangle& t) const {
    return (p_[t[1]] - p_[t[0]]).cross(p_[t[2]] - p_[t[0]]);
  }
  static bool has(const Triangle& t, std::uint32_t v) {
    return t[0] == v || t[1] == v || t[2] == v;
  }
  static Triangle replaced(Triangle t, std::uint32_t u, std::uint32_t v) {
    for (auto& x : t)
      if (x == u) x = v;
    return t;
  }
  // Alive triangles around u, dropping dead entries.
  std::vector<std::uint32_t>& live(std::uint32_t u) {
    auto& list = around_[u];
    list.erase(
        std::remove_if(list.begin(), list.end(), [&](std::uint32_t t) { return !tri_alive_[t]; }),
        list.end());
    return list;
  }
  std::vector<std::uint32_t> neighbours(std::uint32_t u) {
    std::vector<std::uint32_t> n;
    for (std::uint32_t t : live(u))
      for (std::uint32_t x : t_[t])
        if (x != u) n.push_back(x);
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
    return n;
  }
  std::vector<std::uint32_t> edge_triangles(std::uint32_t u, std::uint32_t v) {
    std::vector<std::uint32_t> out;
    for (std::uint32_t t : live(u))
      if (has(t_[t], v)) out.push_back(t);
    return out;
  }
  bool border_edge(std::uint32_t u, std::uint32_t v) { return edge_triangles(u, v).size() == 1; }

  void push(std::uint32_t u, std::uint32_t v) {
    heap_.push(Candidate{collapse_cost(u, v), u, v, stamp_[u], stamp_[v]});
  }

  double collapse_cost(std::uint32_t u, std::uint32_t v) {
    Eigen::Vector4d x;
    x << p_[v].cast<double>(), 1.0;
    double cost = std::max(0.0, x.dot((q_[u] + q_[v]) * x));
    if (cfg_.divide_by_depth2)
      cost /= std::max(1e-6, static_cast<double>((p_[v] - cfg_.viewpoint).squaredNorm()));
    const auto shared = edge_triangles(u, v);
    bool penalise = false;
    if (shared.size() == 2) {
      const Eigen::Vector3f a = normal(t_[shared[0]]).normalized(),
                            b = normal(t_[shared[1]]).normalized();
      penalise = a.dot(b) < cos_sharp_;
    }
    for (std::uint32_t t : live(u)) {
      if (penalise) break;
      if (has(t_[t], v)) continue;
      const Triangle n = replaced(t_[t], u, v);
      for (int i = 0; i < 3 && !penalise; ++i) {
        const Eigen::Vector3f e1 =
            p_[n[static_cast<std::size_t>((i + 1) % 3)]] - p_[n[static_cast<std::size_t>(i)]];
        const Eigen::Vector3f e2 =
            p_[n[static_cast<std::size_t>((i + 2) % 3)]] - p_[n[static_cast<std::size_t>(i)]];
        // angle < min  <=>  cos(angle) > cos(min), compared squared (no trigonometry).
        const float dot = e1.dot(e2);
        penalise = dot > 0.0f && dot * dot > cos2_min_angle_ * e1.squaredNorm() * e2.squaredNorm();
      }
    }
    return penalise ? cost * cfg_.penalty : cost;
  }

  bool valid(std::uint32_t u, std::uint32_t v) {
    const auto shared = edge_triangles(u, v);
    if (shared.empty() || shared.size() > 2) {
      ++report_.rejected_topology;
      return false;
    }
    // Link condition: the common neighbours are exactly the edge's opposite vertices.
    const auto nu = neighbours(u), nv = neighbours(v);
    std::vector<std::uint32_t> common;
    std::set_intersection(nu.begin(), nu.end(), nv.begin(), nv.end(), std::back_inserter(common));
    if (common.size() != shared.size()) {
      ++report_.rejected_topology;
      return false;
    }
    // Borders: u on a border moves only along it, onto the next border vertex, where the
    // border runs nearly straight.
    std::vector<std::uint32_t> border_at_u;
    for (std::uint32_t n : nu)
      if (border_edge(u, n)) border_at_u.push_back(n);
    if (!border_at_u.empty()) {
      const bool along = shared.size() == 1 && border_at_u.size() == 2 &&
                         (border_at_u[0] == v || border_at_u[1] == v);
      if (!along) {
        ++report_.rejected_border;
        return false;
      }
      const std::uint32_t w = border_at_u[0] == v ? border_at_u[1] : border_at_u[0];
      const Eigen::Vector3f in = (p_[u] - p_[w]).normalized(), out = (p_[v] - p_[u]).normalized();
      if (!(in.dot(out) >= cos_border_)) {
        ++report_.rejected_border;
        return false;
      }
    }
    // Faces that stay: no flip, no degeneration, no turn beyond the limit.
    for (std::uint32_t t : live(u)) {
      if (has(t_[t], v)) continue;
      const Eigen::Vector3f before = normal(t_[t]), after = normal(replaced(t_[t], u, v));
      const float b = before.norm(), a = after.norm();
      if (!(a > 1e-12f * std::max(1.0f, b)) || !(before.dot(after) >= cos_turn_ * a * b)) {
        ++report_.rejected_normal;
        return false;
      }
    }
    return true;
  }

  void collapse(std::uint32_t u, std::uint32_t v) {
    for (std::uint32_t t : edge_triangles(u, v)) {
      tri_alive_[t] = 0;
      --alive_;
    }
    for (std::uint32_t t : live(u)) {
      t_[t] = replaced(t_[t], u, v);
      around_[v].push_back(t);
    }
    around_[u].clear();
    live(v);
    q_[v] += q_[u];
    ++report_.collapses;
    // Only candidates with u or v are stale (Q_v changed); others around v keep their entries,
    // whose costs and validity are checked again when they come up.
    ++stamp_[u];
    ++stamp_[v];
    const auto around_v = neighbours(v);
    for (std::uint32_t n : around_v) {
      push(v, n);
      push(n, v);
    }
  }

  TriangleMesh compact() const {
    TriangleMesh out;
    std::vector<std::uint32_t> id(p_.size(), UINT32_MAX);
    for (std::uint32_t t = 0; t < t_.size(); ++t)
      if (tri_alive_[t])
        for (std::uint32_t v : t_[t]) id[v] = 0;
    for (std::uint32_t v = 0; v < p_.size(); ++v) {
      if (id[v] == UINT32_MAX) continue;
      id[v] = static_cast<std::uint32_t>(out.vertices.size());
      out.vertices.push_back(p_[v]);
    }
    for (std::uint32_t t = 0; t < t_.size(); ++t)
      if (tri_alive_[t])
        out.triangles.push_back(Triangle{id[t_[t][0]], id[t_[t][1]], id[t_[t][2]]});
    return out;
  }

  const QemConfig& cfg_;
  QemReport& report_;
  std::vector<Eigen::Vector3f> p_;
  std::vector<Triangle> t_;
  std::vector<std::uint8_t> tri_alive_;
  std::vector<std::vector<std::uint32_t>>
      around_;  // vertex -> triangles (dead ones dropped lazily)
  std::vector<Quadric, Eigen::aligned_allocator<Quadric>> q_;
  std::vector<std::uint32_t> stamp_;
  std::size_t alive_;
  float cos_turn_, cos_border_, cos_sharp_;
  float cos2_min_angle_;
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<Candidate>> heap_;
};

}  // namespace

TriangleMesh qem_decimate(const TriangleMesh& mesh, const QemConfig& config, QemReport* report) {
  QemReport r;
  const auto target = static_cast<std::size_t>(std::ceil(
      static_cast<double>(mesh.triangles.size()) * static_cast<double>(config.target_ratio)));
  TriangleMesh out = Decimator(mesh, config, r).run(target);
  if (report != nullptr) *report = r;
  return out;
}

}  // namespace meshflow
