#include "nodes/optimize/planar/sharp_edges.h"

#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <utility>
#include <vector>

#include "runtime/half_edge_mesh.h"

namespace meshflow {
namespace {

constexpr std::int32_t kNoRegion = -1;
constexpr int kMaxCandidates = 3;

struct Plane {
  Eigen::Vector3f n;
  float d;
  float at(const Eigen::Vector3f& p) const { return n.dot(p) - d; }
  Eigen::Vector3f project(const Eigen::Vector3f& p) const { return p - at(p) * n; }
};

struct Line {
  Eigen::Vector3f point, direction;  // direction unit
  Eigen::Vector3f closest(const Eigen::Vector3f& p) const {
    return point + direction * direction.dot(p - point);
  }
};

// The intersection line of two planes (false when they are nearly parallel).
bool intersect(const Plane& a, const Plane& b, Line& line) {
  const Eigen::Vector3f u = a.n.cross(b.n);
  const float u2 = u.squaredNorm();
  if (u2 < 1e-6f) return false;
  line.point = (a.d * b.n.cross(u) + b.d * u.cross(a.n)) / u2;
  line.direction = u / std::sqrt(u2);
  return true;
}

// The meeting point of three planes (false when their normals are nearly dependent).
bool intersect(const Plane& a, const Plane& b, const Plane& c, Eigen::Vector3f& point) {
  const float det = a.n.dot(b.n.cross(c.n));
  if (std::abs(det) < 1e-3f) return false;
  point = (a.d * b.n.cross(c.n) + b.d * c.n.cross(a.n) + c.d * a.n.cross(b.n)) / det;
  return true;
}

// A large region near a vertex: how many edges away, and a point of the region's own faces
// there (the centroid of the face the region was found through), which tells on which side of
// a crease the region lies.
struct NearRegion {
  std::int32_t region = kNoRegion;
  int rings = 0;
  Eigen::Vector3f reference = Eigen::Vector3f::Zero();
};

struct NearRegions {
  std::array<NearRegion, kMaxCandidates> items;
  int count = 0;
  // Keeps the nearest candidates (fewest rings, then lowest region index).
  void add(const NearRegion& c) {
    for (int i = 0; i < count; ++i)
      if (items[static_cast<std::size_t>(i)].region == c.region) return;
    auto before = [](const NearRegion& x, const NearRegion& y) {
      return x.rings != y.rings ? x.rings < y.rings : x.region < y.region;
    };
    if (count == kMaxCandidates && !before(c, items[kMaxCandidates - 1])) return;
    int i = std::min(count, kMaxCandidates - 1);
    while (i > 0 && before(c, items[static_cast<std::size_t>(i - 1)])) {
      items[static_cast<std::size_t>(i)] = items[static_cast<std::size_t>(i - 1)];
      --i;
    }
    items[static_cast<std::size_t>(i)] = c;
    count = std::min(count + 1, kMaxCandidates);
  }
};

// Where a vertex goes: onto plane a, the line of a and b, or the corner of a, b and c.
struct Label {
  enum Kind : std::uint8_t { kStay, kPlane, kLine, kCorner } kind = kStay;
  std::array<std::int32_t, 3> regions{kNoRegion, kNoRegion, kNoRegion};
};

class CreaseSharpener {
 public:
  CreaseSharpener(const TriangleMesh& mesh, const PlanarSegmentation& s,
                  const SharpEdgeConfig& config)
      : mesh_(mesh), seg_(s), cfg_(config), h_(mesh) {
    for (const PlanarRegion& r : s.regions) planes_.push_back(Plane{r.normal, r.offset});
    const float edge = median_edge_length(mesh);
    max_move_ = config.max_move > 0.0f ? config.max_move : 2.0f * edge;
    const float min_width = config.min_region_width > 0.0f ? config.min_region_width : 4.0f * edge;
    large_.resize(s.regions.size());
    tbb::parallel_for(std::size_t{0}, s.regions.size(), [&](std::size_t r) {
      large_[r] = s.regions[r].faces.size() >= config.min_region_faces &&
                  region_width(s.regions[r]) >= min_width;
    });
    refit_planes();
  }

  TriangleMesh run(SharpEdgeReport& report) {
    const std::size_t original_faces = h_.face_count();
    original_normals_.resize(original_faces);
    parent_.resize(original_faces);
    for (std::uint32_t f = 0; f < original_faces; ++f) {
      original_normals_[f] = normal(f);
      parent_[f] = f;
    }
    const std::vector<NearRegions> near = find_candidates();
    labels_.assign(h_.vertex_count(), Label{});
    std::vector<Eigen::Vector3f> target(h_.vertex_count());
    tbb::parallel_for(std::size_t{0}, h_.vertex_count(), [&](std::size_t v) {
      target[v] = h_.position(static_cast<std::uint32_t>(v));
      labels_[v] = choose_target(near[v], target[v]);
    });
    move_without_flips(target);
    cut_along_lines(report);
    count_results(report);
    return output();
  }

 private:
  // Fits each taking-part region's plane again through its inner vertices only (those whose
  // faces all lie along it): the segmentation's fit includes the bevel's vertices, which tilt
  // and shift a plane by a good part of the bevel's height.
  void refit_planes() {
    const std::size_t regions = planes_.size();
    std::vector<Eigen::Vector3d> sum(regions, Eigen::Vector3d::Zero());
    std::vector<Eigen::Matrix3d> second(regions, Eigen::Matrix3d::Zero());
    std::vector<std::size_t> count(regions, 0);
    std::vector<std::int32_t> inner(h_.vertex_count(), kNoRegion);
    tbb::parallel_for(std::size_t{0}, h_.vertex_count(), [&](std::size_t v) {
      const std::vector<std::uint32_t> ring = h_.ring(static_cast<std::uint32_t>(v));
      if (ring.empty()) return;
      const std::int32_t r = large_region(HalfEdgeMesh::face(ring.front()));
      for (std::uint32_t e : ring)
        if (large_region(HalfEdgeMesh::face(e)) != r) return;
      inner[v] = r;
    });
    for (std::uint32_t v = 0; v < h_.vertex_count(); ++v) {
      if (inner[v] == kNoRegion) continue;
      const auto r = static_cast<std::size_t>(inner[v]);
      const Eigen::Vector3d p = h_.position(v).cast<double>();
      sum[r] += p;
      second[r] += p * p.transpose();
      ++count[r];
    }
    for (std::size_t r = 0; r < regions; ++r) {
      if (count[r] < 3) continue;
      const Eigen::Vector3d mean = sum[r] / static_cast<double>(count[r]);
      const Eigen::Matrix3d covariance =
          second[r] / static_cast<double>(count[r]) - mean * mean.transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
      Eigen::Vector3f n = eigen.eigenvectors().col(0).cast<float>().normalized();
      if (n.dot(planes_[r].n) < 0.0f) n = -n;
      planes_[r] = Plane{n, n.dot(mean.cast<float>())};
    }
  }

  // Whether a face around v faces against its input face.
  bool turns_around(std::uint32_t v) const {
    for (std::uint32_t e : h_.ring(v)) {
      const std::uint32_t f = HalfEdgeMesh::face(e);
      if (turned(f, original_normals_[parent_[f]])) return true;
    }
    return false;
  }

  // Whether face f now faces against `before` (its normal then) or lost its area (has_area:
  // a sliver flatter than a millionth counts as lost); faces that had no area to begin with do
  // not count.
  bool turned(std::uint32_t f, const Eigen::Vector3f& before) const {
    return before.squaredNorm() > 0.0f &&
           (normal(f).dot(before) <= 0.0f ||
            !has_area(h_.position(h_.from(3 * f)), h_.position(h_.from(3 * f + 1)),
                      h_.position(h_.from(3 * f + 2))));
  }

  // The width of a strip with the same spread across the region's main direction as its face
  // centroids: sqrt(12 x the middle eigenvalue of their covariance).
  float region_width(const PlanarRegion& r) const {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
    for (std::uint32_t f : r.faces) {
      const Eigen::Vector3d c = centroid(f).cast<double>();
      mean += c;
      second += c * c.transpose();
    }
    const double n = static_cast<double>(r.faces.size());
    mean /= n;
    const Eigen::Matrix3d covariance = second / n - mean * mean.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance, Eigen::EigenvaluesOnly);
    return static_cast<float>(std::sqrt(std::max(0.0, 12.0 * eigen.eigenvalues()(1))));
  }

  Eigen::Vector3f centroid(std::uint32_t f) const {
    return (h_.position(h_.from(3 * f)) + h_.position(h_.from(3 * f + 1)) +
            h_.position(h_.from(3 * f + 2))) /
           3.0f;
  }

  Eigen::Vector3f normal(std::uint32_t f) const {
    const Eigen::Vector3f& a = h_.position(h_.from(3 * f));
    return (h_.position(h_.from(3 * f + 1)) - a).cross(h_.position(h_.from(3 * f + 2)) - a);
  }

  // The face's region if it takes part and the face lies along its plane (region growing
  // compares faces with the seed's normal, so a region can take in a row of the bevel).
  std::int32_t large_region(std::uint32_t f) const {
    const std::int32_t r = seg_.region_of_face[f];
    if (r < 0 || !large_[static_cast<std::size_t>(r)]) return kNoRegion;
    const Eigen::Vector3f n = normal(f);
    const float along = n.dot(planes_[static_cast<std::size_t>(r)].n);
    return along > cfg_.min_face_cos * n.norm() ? r : kNoRegion;
  }

  bool creased(std::int32_t a, std::int32_t b) const {
    return std::abs(planes_[static_cast<std::size_t>(a)].n.dot(
               planes_[static_cast<std::size_t>(b)].n)) < cfg_.max_normal_cos;
  }

  // Regions on a vertex's faces (0 rings), spread `rings` times to the neighbours.
  std::vector<NearRegions> find_candidates() const {
    const std::size_t n = h_.vertex_count();
    std::vector<NearRegions> near(n);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t vi) {
      for (std::uint32_t e : h_.ring(static_cast<std::uint32_t>(vi))) {
        const std::uint32_t f = HalfEdgeMesh::face(e);
        const std::int32_t r = large_region(f);
        if (r == kNoRegion) continue;
        near[vi].add(NearRegion{r, 0, centroid(f)});
      }
    });
    for (int step = 1; step <= cfg_.rings; ++step) {
      const std::vector<NearRegions> before = near;
      tbb::parallel_for(std::size_t{0}, n, [&](std::size_t vi) {
        for (std::uint32_t e : h_.ring(static_cast<std::uint32_t>(vi))) {
          const NearRegions& other = before[h_.to(e)];
          for (int i = 0; i < other.count; ++i) {
            NearRegion c = other.items[static_cast<std::size_t>(i)];
            c.rings = step;
            near[vi].add(c);
          }
        }
      });
    }
    return near;
  }

  // The nearest point of the piecewise planar surface that the vertex's candidate regions form
  // around their creases; kStay when there is no crease or nothing within reach.
  Label choose_target(const NearRegions& near, Eigen::Vector3f& position) const {
    const int k = near.count;
    bool any_crease = false;
    // side[i][j]: the sign of plane j on region i's side of their crease (0: no crease).
    float side[kMaxCandidates][kMaxCandidates] = {};
    for (int i = 0; i < k; ++i)
      for (int j = 0; j < k; ++j) {
        const NearRegion& a = near.items[static_cast<std::size_t>(i)];
        const NearRegion& b = near.items[static_cast<std::size_t>(j)];
        if (i == j || !creased(a.region, b.region)) continue;
        const float s = planes_[static_cast<std::size_t>(b.region)].at(a.reference);
        side[i][j] = s > 0.0f ? 1.0f : -1.0f;
        any_crease = true;
      }
    if (!any_crease) return Label{};
    const Eigen::Vector3f p = position;
    auto plane = [&](int i) -> const Plane& {
      return planes_[static_cast<std::size_t>(near.items[static_cast<std::size_t>(i)].region)];
    };
    // q lies on region i's side of every crease i forms (with a little slack for q on a line).
    const float slack = 1e-4f * max_move_;
    auto on_side = [&](const Eigen::Vector3f& q, int i, int skip) {
      for (int j = 0; j < k; ++j)
        if (j != skip && side[i][j] != 0.0f && side[i][j] * plane(j).at(q) < -slack) return false;
      return true;
    };
    Label best;
    float best_distance = max_move_;
    auto consider = [&](const Eigen::Vector3f& q, Label label) {
      const float d = (q - p).norm();
      if (d <= best_distance) {
        best_distance = d;
        best = label;
        position = q;
      }
    };
    for (int i = 0; i < k; ++i) {
      bool creases_any = false;
      for (int j = 0; j < k; ++j) creases_any = creases_any || side[i][j] != 0.0f;
      const Eigen::Vector3f q = plane(i).project(p);
      if (creases_any && on_side(q, i, -1))
        consider(q, Label{Label::kPlane, {near.items[static_cast<std::size_t>(i)].region}});
    }
    for (int i = 0; i < k; ++i)
      for (int j = i + 1; j < k; ++j) {
        Line line;
        if (side[i][j] == 0.0f || !intersect(plane(i), plane(j), line)) continue;
        const Eigen::Vector3f q = line.closest(p);
        if (!on_side(q, i, j) || !on_side(q, j, i)) continue;
        consider(q, Label{Label::kLine,
                          {near.items[static_cast<std::size_t>(i)].region,
                           near.items[static_cast<std::size_t>(j)].region, kNoRegion}});
      }
    Eigen::Vector3f corner;
    if (k == 3 && side[0][1] != 0.0f && side[0][2] != 0.0f && side[1][2] != 0.0f &&
        intersect(plane(0), plane(1), plane(2), corner))
      consider(corner, Label{Label::kCorner,
                             {near.items[0].region, near.items[1].region, near.items[2].region}});
    return best;
  }

  // Applies the targets; a face that would turn by more than 90 degrees (or lose its area)
  // keeps its vertices where they were, repeated until no face turns.
  void move_without_flips(const std::vector<Eigen::Vector3f>& target) {
    const std::size_t n = h_.vertex_count();
    std::vector<std::uint8_t> moving(n, 0);
    for (std::uint32_t v = 0; v < n; ++v)
      if (labels_[v].kind != Label::kStay) {
        h_.set_position(v, target[v]);
        moving[v] = 1;
      }
    // Each round puts back the farthest-moved vertex of every turned face; it ends because every
    // round puts back at least one vertex, and the input has no turned face.
    for (;;) {
      std::vector<std::uint32_t> undo;
      for (std::uint32_t f = 0; f < original_normals_.size(); ++f) {
        if (!h_.face_alive(f) || !turned(f, original_normals_[f])) continue;
        std::uint32_t farthest = HalfEdgeMesh::kNone;
        float distance = 0.0f;
        for (std::uint32_t c = 0; c < 3; ++c) {
          const std::uint32_t v = h_.from(3 * f + c);
          const float d = (h_.position(v) - mesh_.vertices[v]).squaredNorm();
          if (moving[v] && (farthest == HalfEdgeMesh::kNone || d > distance)) {
            farthest = v;
            distance = d;
          }
        }
        if (farthest != HalfEdgeMesh::kNone) undo.push_back(farthest);
      }
      if (undo.empty()) return;
      for (std::uint32_t v : undo) {
        h_.set_position(v, mesh_.vertices[v]);
        moving[v] = 0;
        labels_[v] = Label{};
      }
    }
  }

  // Cuts every edge from a vertex on plane a to one on plane b (a crease) at their line.
  void cut_along_lines(SharpEdgeReport& report) {
    std::set<std::pair<std::int32_t, std::int32_t>> creases;
    for (std::uint32_t f = 0; f < h_.face_count(); ++f) {
      if (!h_.face_alive(f)) continue;
      for (std::uint32_t c = 0; c < 3; ++c) {
        const std::uint32_t e = 3 * f + c;
        const std::uint32_t u = h_.from(e), w = h_.to(e);
        const Label lu = labels_[u], lw = labels_[w];
        if (lu.kind != Label::kPlane || lw.kind != Label::kPlane) continue;
        const std::int32_t a = lu.regions[0], b = lw.regions[0];
        Line line;
        if (a == b || !creased(a, b) ||
            !intersect(planes_[static_cast<std::size_t>(a)], planes_[static_cast<std::size_t>(b)],
                       line))
          continue;
        creases.emplace(std::min(a, b), std::max(a, b));
        const Label on_line{Label::kLine, {std::min(a, b), std::max(a, b), kNoRegion}};
        const Eigen::Vector3f pu = h_.position(u), pw = h_.position(w);
        const float t = crossing(pu, pw, line);
        if (t < cfg_.snap_fraction || t > 1.0f - cfg_.snap_fraction) {
          // Moving the near end onto the line keeps it on its plane (the line lies in both).
          const std::uint32_t end = t < 0.5f ? u : w;
          const Eigen::Vector3f before = h_.position(end);
          h_.set_position(end, line.closest(before));
          if (!turns_around(end)) {
            labels_[end] = on_line;
            c = static_cast<std::uint32_t>(-1);  // this face changed: look at it again
            continue;
          }
          h_.set_position(end, before);
          if (t < 0.02f || t > 0.98f) continue;  // a cut this close would leave a sliver
        }
        const Eigen::Vector3f on_edge = pu + t * (pw - pu);
        const std::uint32_t twin = h_.twin(e);
        const std::uint32_t m = h_.split(e, line.closest(on_edge));
        parent_.push_back(parent_[f]);
        if (twin != HalfEdgeMesh::kNone) parent_.push_back(parent_[HalfEdgeMesh::face(twin)]);
        colors_.push_back({u, w});
        labels_.push_back(on_line);
        if (turns_around(m)) {  // the line is off this edge by too much: cut on the edge
          h_.set_position(m, on_edge);
          labels_.back() = Label{};
        }
        ++report.split_edges;
        c = static_cast<std::uint32_t>(-1);  // this face changed: look at it again
      }
    }
    report.creases = creases.size();
  }

  // Where the segment u-w passes closest to the line, as a share of the way from u to w.
  static float crossing(const Eigen::Vector3f& u, const Eigen::Vector3f& w, const Line& line) {
    const Eigen::Vector3f e = w - u;
    const Eigen::Vector3f across = e - line.direction * line.direction.dot(e);
    const float a2 = across.squaredNorm();
    if (a2 <= 0.0f) return 0.5f;
    const Eigen::Vector3f r = u - line.point;
    const Eigen::Vector3f r_across = r - line.direction * line.direction.dot(r);
    return std::clamp(-r_across.dot(across) / a2, 0.0f, 1.0f);
  }

  void count_results(SharpEdgeReport& report) const {
    for (std::uint32_t v = 0; v < h_.vertex_count(); ++v) {
      const Label& l = labels_[v];
      if (l.kind == Label::kPlane) ++report.to_plane;
      if (l.kind == Label::kCorner) ++report.to_corner;
      if (l.kind != Label::kLine) continue;
      if (v < mesh_.vertices.size()) ++report.to_line;
      Line line;
      intersect(planes_[static_cast<std::size_t>(l.regions[0])],
                planes_[static_cast<std::size_t>(l.regions[1])], line);
      report.max_line_distance = std::max(report.max_line_distance,
                                          (line.closest(h_.position(v)) - h_.position(v)).norm());
    }
    for (std::uint32_t f = 0; f < h_.face_count(); ++f)
      if (h_.face_alive(f) && turned(f, original_normals_[parent_[f]])) ++report.flipped_faces;
  }

  TriangleMesh output() const {
    TriangleMesh out;
    out.vertices.resize(h_.vertex_count());
    for (std::uint32_t v = 0; v < h_.vertex_count(); ++v) out.vertices[v] = h_.position(v);
    if (mesh_.colors.size() == mesh_.vertices.size()) {
      out.colors = mesh_.colors;
      for (const auto& [u, w] : colors_) {
        const Rgb8 a = out.colors[u], b = out.colors[w];  // copies: push_back may reallocate
        out.colors.push_back(midpoint_color(a, b));
      }
    }
    for (std::uint32_t f = 0; f < h_.face_count(); ++f)
      if (h_.face_alive(f))
        out.triangles.push_back(Triangle{h_.from(3 * f), h_.from(3 * f + 1), h_.from(3 * f + 2)});
    return compact_vertices(out, out.triangles);
  }

  const TriangleMesh& mesh_;
  const PlanarSegmentation& seg_;
  const SharpEdgeConfig& cfg_;
  HalfEdgeMesh h_;
  std::vector<Plane> planes_;
  std::vector<std::uint8_t> large_;  // per region: takes part
  float max_move_ = 0.0f;
  std::vector<Label> labels_;                                    // per vertex, new ones included
  std::vector<std::pair<std::uint32_t, std::uint32_t>> colors_;  // new vertex: its edge's ends
  std::vector<std::uint32_t> parent_;              // per face slot: the input face it was cut from
  std::vector<Eigen::Vector3f> original_normals_;  // per input face (not unit length)
};

}  // namespace

TriangleMesh sharpen_creases(const TriangleMesh& mesh, const PlanarSegmentation& segmentation,
                             const SharpEdgeConfig& config, SharpEdgeReport* report) {
  SharpEdgeReport r;
  CreaseSharpener sharpener(mesh, segmentation, config);
  TriangleMesh out = sharpener.run(r);
  if (report != nullptr) *report = r;
  return out;
}

}  // namespace meshflow
