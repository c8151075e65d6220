#include "nodes/normals/normals.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "nodes/normals/smallest_eigen.h"
#include "nodes/search/neighbour_table.h"
#include "runtime/default_init.h"
#include "runtime/error.h"
#include "runtime/parallel.h"
#include "runtime/simd.h"

namespace meshflow {
namespace {

struct LocalFrame {
  Eigen::Vector3d mean;
  Eigen::Matrix3d axes;    // columns: principal axes, smallest variance first
  Eigen::Vector3d values;  // the covariance's eigenvalues, ascending
};

// Mean and scatter (the sum of the outer products about the mean) of the n points base[row[i]]
// (base[i] when `row` is null), in double; the scatter's lower triangle mirrors the upper. Each
// sum is taken point by point in the order given, lane by lane in vectors: (x, y, z) for the
// mean, (xx, xy, xz, yy) and (yz, zz) for the scatter (no FMA: the same rounding as scalar code).
MESHFLOW_AVX2_CLONES void scatter_of(const Eigen::Vector3f* base, const std::uint32_t* row,
                                     std::size_t n, Eigen::Vector3d& mean,
                                     Eigen::Matrix3d& scatter) {
  using simd::Doubles4;
  using Floats4 = float __attribute__((vector_size(16)));
  constexpr std::size_t kKept = 16;  // points kept converted between the two passes
  Doubles4 kept[kKept];
  Doubles4 sum{}, p;
  const auto load = [&](std::size_t i, Doubles4& out) {  // (x, y, z, 0)
    const Eigen::Vector3f& v = base[row != nullptr ? row[i] : i];
    const Floats4 f = {v.x(), v.y(), v.z(), 0.0f};
    out = __builtin_convertvector(f, Doubles4);
  };
  for (std::size_t i = 0; i < n; ++i) {
    load(i, p);
    if (i < kKept) kept[i] = p;
    sum += p;
  }
  const Doubles4 m = sum / static_cast<double>(n);
  Doubles4 a{}, b{};  // (s00, s01, s02, s11), (s12, s22, -, -)
  for (std::size_t i = 0; i < n; ++i) {
    if (i < kKept)
      p = kept[i];
    else
      load(i, p);
    const Doubles4 d = p - m;
    a += __builtin_shufflevector(d, d, 0, 0, 0, 1) * __builtin_shufflevector(d, d, 0, 1, 2, 1);
    b += __builtin_shufflevector(d, d, 1, 2, 3, 3) * __builtin_shufflevector(d, d, 2, 2, 3, 3);
  }
  mean = Eigen::Vector3d(m[0], m[1], m[2]);
  scatter << a[0], a[1], a[2], a[1], a[3], b[0], a[2], b[0], b[1];
}

LocalFrame principal_frame(const std::vector<Eigen::Vector3f>& pts, std::size_t n) {
  LocalFrame f{Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()};
  Eigen::Matrix3d cov;
  scatter_of(pts.data(), nullptr, n, f.mean, cov);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(cov);
  f.axes = solver.eigenvectors();
  f.values = solver.eigenvalues();
  return f;
}

// Thesis criterion: the neighbourhood's bounding box must not be degenerate. The box is taken
// in the neighbours' principal frame, so a sloped scan line is recognised as a line.
bool box_well_shaped(const std::vector<Eigen::Vector3f>& pts, std::size_t n, const LocalFrame& f,
                     float ratio) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e300), hi = -lo;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = pts[i].cast<double>() - f.mean;
    const Eigen::Vector2d c(d.dot(f.axes.col(1)), d.dot(f.axes.col(2)));
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  const Eigen::Vector2d extent = hi - lo;  // (middle axis, major axis)
  return extent.x() >= ratio * extent.y();
}

// 1 where the cloud's own normal is usable (finite, not zero).
std::vector<std::uint8_t> usable_input_normals(const PointCloud& cloud) {
  std::vector<std::uint8_t> usable(cloud.size(), 0);
  if (!cloud.has_normals()) return usable;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cloud.size(), 8192),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const Eigen::Vector3f& n = cloud.normals[i];
                        usable[i] = n.allFinite() && n.squaredNorm() > 1e-12f ? 1 : 0;
                      }
                    });
  return usable;
}

// The least-squares plane of a point's neighbourhood (no member initialisers: a vector of them
// is left for plane_fits()'s threads to write; no_fit() where none was fitted).
struct PlaneFit {
  Eigen::Vector3f normal;    // unit, either sign; zero: < 3 neighbours
  Eigen::Vector3f centroid;  //
  float variation;           // smallest eigenvalue / their sum: 0 on a plane, 1/3 at most
  float thickness;           // RMS distance of the neighbours to the plane
  float spread;              // RMS distance of the neighbours to their centroid
};
PlaneFit no_fit() { return {Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero(), 1.0f, 0.0f, 0.0f}; }
using PlaneFits = UninitVector<PlaneFit>;

// Plane fits of the points with wanted[i] (all when `wanted` is empty), from the table's first
// kn neighbours (more under the adaptive criterion).
PlaneFits plane_fits(const PointCloud& cloud, const SpatialIndex& index,
                     const NeighbourTable& table, const std::vector<std::uint8_t>& wanted,
                     const NormalsConfig& config) {
  const std::size_t kn = static_cast<std::size_t>(std::max(config.kn, 3));
  const std::size_t max_k =
      std::max<std::size_t>(static_cast<std::size_t>(std::max(config.adaptive_max_k, 3)), kn);
  PlaneFits fits(cloud.size());  // every one written below, by the threads
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cloud.size(), 512),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::vector<std::uint32_t> idx(max_k);
                      std::vector<float> d2(max_k);
                      std::vector<Eigen::Vector3f> pts(max_k);
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        fits[i] = no_fit();
                        if (!wanted.empty() && !wanted[i]) continue;
                        std::size_t k = std::min<std::size_t>(kn, table.counts[i]);
                        if (k < 3) continue;
                        const std::uint32_t* row = table.row(i);
                        Eigen::Vector3d mean, values;
                        Eigen::Vector3f normal;
                        if (!config.adaptive_k) {  // the smallest eigenvector only, in closed form
                          Eigen::Matrix3d scatter;
                          scatter_of(cloud.positions.data(), row, k, mean, scatter);
                          const SmallestEigen e = smallest_eigen(scatter);
                          values = e.values;
                          normal = e.vector.cast<float>();
                        } else {
                          for (std::size_t j = 0; j < k; ++j) pts[j] = cloud.positions[row[j]];
                          LocalFrame frame = principal_frame(pts, k);
                          while (!box_well_shaped(pts, k, frame, config.adaptive_ratio) &&
                                 k < max_k && k < index.size()) {
                            k = index.knn(cloud.positions[i], std::min(2 * k, max_k), idx.data(),
                                          d2.data());
                            for (std::size_t j = 0; j < k; ++j) pts[j] = cloud.positions[idx[j]];
                            frame = principal_frame(pts, k);
                          }
                          mean = frame.mean;
                          values = frame.values;
                          normal = frame.axes.col(0).normalized().cast<float>();
                        }
                        PlaneFit& f = fits[i];
                        f.normal = normal;
                        f.centroid = mean.cast<float>();
                        const double total = values.sum();
                        f.variation = total > 0.0 ? static_cast<float>(values[0] / total) : 1.0f;
                        f.thickness = static_cast<float>(std::sqrt(std::max(0.0, values[0]) / k));
                        f.spread = static_cast<float>(std::sqrt(std::max(0.0, total) / k));
                      }
                    });
  return fits;
}

// The median variation of the fits of the points with wanted[i] (all when empty); 0 for none.
float median_variation(const PlaneFits& fits, const std::vector<std::uint8_t>& wanted) {
  std::vector<float> v;
  v.reserve(fits.size());
  for (std::size_t i = 0; i < fits.size(); ++i)
    if ((wanted.empty() || wanted[i]) && !fits[i].normal.isZero()) v.push_back(fits[i].variation);
  if (v.empty()) return 0.0f;
  const auto middle = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), middle, v.end());
  return *middle;
}

std::vector<Eigen::Vector3f> normals_of(const PlaneFits& fits) {
  std::vector<Eigen::Vector3f> normals(fits.size());  // Vector3f: left uninitialised
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, fits.size(), 8192),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        normals[i] = fits[i].normal;
                    });
  return normals;
}

// Neighbourhood shifting for sharp features: each point takes the plane of the flattest
// neighbourhood (least variation) among its own and those of its neighbours and their
// neighbours (two rings of the table) that passes through it, i.e. within twice that plane's
// thickness (plus 0.1 % of its spread) of the point. Near a sharp edge every neighbourhood
// around a point straddles the edge, but some a little farther along the point's own face do
// not, and their plane is that face's (measured on a box: normals more than 5 degrees off 5 800
// -> 83 of 100 000). Parallel over points; O(n k^2).
std::vector<Eigen::Vector3f> flattest_plane_normals(const PlaneFits& fits, const PointCloud& cloud,
                                                    const NeighbourTable& table,
                                                    const std::vector<std::uint8_t>& wanted) {
  std::vector<Eigen::Vector3f> normals = normals_of(fits);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cloud.size(), 512),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        if (!wanted.empty() && !wanted[i]) continue;
                        float best = fits[i].variation;
                        auto consider = [&](std::uint32_t j) {
                          const PlaneFit& f = fits[j];
                          if (f.variation >= best || f.normal.isZero()) return;
                          const float d = std::abs(f.normal.dot(cloud.positions[i] - f.centroid));
                          if (d > 2.0f * f.thickness + 1e-3f * f.spread) return;
                          best = f.variation;
                          normals[i] = f.normal;
                        };
                        for (std::uint32_t a = 0; a < table.counts[i]; ++a) {
                          const std::uint32_t j = table.row(i)[a];
                          for (std::uint32_t b = 0; b < table.counts[j]; ++b)
                            consider(table.row(j)[b]);
                        }
                      }
                    });
  return normals;
}

// `normals`, each turned to agree with the oriented normal of its point in `oriented`.
std::vector<Eigen::Vector3f> signed_like(std::vector<Eigen::Vector3f> normals,
                                         const std::vector<Eigen::Vector3f>& oriented) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, normals.size(), 8192),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        if (normals[i].dot(oriented[i]) < 0.0f) normals[i] = -normals[i];
                    });
  return normals;
}

// Turns each normal towards (sign +1) or away from (-1) `viewpoint`; zero normals become the
// direction to it.
void orient_to_viewpoint(const PointCloud& cloud, const Eigen::Vector3f& viewpoint, float sign,
                         std::vector<Eigen::Vector3f>& normals) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, normals.size(), 8192),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const Eigen::Vector3f to_view = viewpoint - cloud.positions[i];
                        Eigen::Vector3f& n = normals[i];
                        if (n.isZero()) n = sign * to_view.normalized();
                        if (sign * n.dot(to_view) < 0.0f) n = -n;
                      }
                    });
}

// interpolate() for the points [begin, end): smoothed[i] for each.
MESHFLOW_AVX2_CLONES void interpolate_range(const std::vector<Eigen::Vector3f>& normals,
                                            const NeighbourTable& table, std::size_t ki,
                                            const std::vector<std::uint8_t>& smooth,
                                            float min_agreement, std::size_t begin, std::size_t end,
                                            Eigen::Vector3f* smoothed) {
  for (std::size_t i = begin; i != end; ++i) {
    if (!smooth.empty() && !smooth[i]) {
      smoothed[i] = normals[i];
      continue;
    }
    Eigen::Vector3f sum = Eigen::Vector3f::Zero();
    const std::size_t k = std::min<std::size_t>(ki, table.counts[i]);
    for (std::size_t j = 0; j < k; ++j) {
      const Eigen::Vector3f& n = normals[table.row(i)[j]];
      if (n.dot(normals[i]) >= min_agreement) sum += n;
    }
    const float len = sum.norm();
    smoothed[i] = len > 0.0f ? Eigen::Vector3f(sum / len) : normals[i];
  }
}

// Normal interpolation (thesis ki): each point with `smooth[i]` (all when empty) takes the
// normalised sum of its ki nearest neighbours' oriented normals, leaving out those whose dot
// product with its own is below `min_agreement` (-1: none left out).
std::vector<Eigen::Vector3f> interpolate(const std::vector<Eigen::Vector3f>& normals,
                                         const NeighbourTable& table, std::size_t ki,
                                         const std::vector<std::uint8_t>& smooth,
                                         float min_agreement) {
  std::vector<Eigen::Vector3f> smoothed(normals.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, normals.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      interpolate_range(normals, table, ki, smooth, min_agreement, r.begin(),
                                        r.end(), smoothed.data());
                    });
  return smoothed;
}

NormalSource resolve_source(const PointCloud& cloud, const std::vector<std::uint8_t>& usable,
                            NormalSource wanted) {
  const bool any_usable = std::find(usable.begin(), usable.end(), 1) != usable.end();
  if (wanted == NormalSource::kInput && !any_usable)
    throw Error("normals", "input",
                cloud.has_normals() ? "every input normal is zero or not finite"
                                    : "the cloud carries no normals (estimate them instead)");
  if (wanted == NormalSource::kAuto)
    return any_usable ? NormalSource::kInput : NormalSource::kEstimate;
  return wanted;
}

}  // namespace

const char* side_name(ComponentSide side, const Eigen::Vector3f& axis) {
  switch (side) {
    case ComponentSide::kOutward:
    case ComponentSide::kViewOrOutward:
    case ComponentSide::kAxisOrOutward:
      return "outward";
    case ComponentSide::kTowardPoint:
      return "towards-origin";
    case ComponentSide::kAlongAxis:
      if (axis == Eigen::Vector3f::UnitZ()) return "up";
      if (axis == -Eigen::Vector3f::UnitZ()) return "down";
      return "axis";
  }
  return "?";
}

NormalOrientation resolve_orientation(const PointCloud& cloud) {
  if (cloud.has_normals()) return NormalOrientation::kInput;
  if (cloud.has_sensor_origin || cloud.is_organized()) return NormalOrientation::kTowardSensor;
  return NormalOrientation::kPropagate;
}

const char* orientation_name(NormalOrientation orientation) {
  switch (orientation) {
    case NormalOrientation::kAuto:
      return "auto";
    case NormalOrientation::kTowardSensor:
      return "sensor";
    case NormalOrientation::kTowardViewpoint:
      return "viewpoint";
    case NormalOrientation::kAwayFromViewpoint:
      return "away-from-viewpoint";
    case NormalOrientation::kPropagate:
      return "propagate";
    case NormalOrientation::kInput:
      return "input";
    case NormalOrientation::kUp:
      return "up";
    case NormalOrientation::kDown:
      return "down";
  }
  return "?";
}

Eigen::Vector3f fit_plane_normal(const std::vector<Eigen::Vector3f>& points) {
  if (points.size() < 3) return Eigen::Vector3f::Zero();
  return principal_frame(points, points.size()).axes.col(0).normalized().cast<float>();
}

namespace {

// Median plane-fit variation over at most `samples` points spread evenly over the cloud (kn
// nearest neighbours each): how clean the samples are when no fit is needed for the normals.
float sampled_median_variation(const PointCloud& cloud, const SpatialIndex& index, int kn,
                               std::size_t samples) {
  const std::size_t n = cloud.size();
  const std::size_t k = static_cast<std::size_t>(std::max(kn, 3));
  if (n < k) return 1.0f;
  const std::size_t count = std::min(n, samples);
  std::vector<float> variation(count, 1.0f);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, count, 64), [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<std::uint32_t> idx(k);
        std::vector<float> d2(k);
        std::vector<Eigen::Vector3f> pts(k);
        for (std::size_t s = r.begin(); s != r.end(); ++s) {
          const std::size_t i = s * n / count;
          const std::size_t found = index.knn(cloud.positions[i], k, idx.data(), d2.data());
          if (found < 3) continue;
          for (std::size_t j = 0; j < found; ++j) pts[j] = cloud.positions[idx[j]];
          const LocalFrame frame = principal_frame(pts, found);
          const double total = frame.values.sum();
          variation[s] = total > 0.0 ? static_cast<float>(frame.values[0] / total) : 1.0f;
        }
      });
  const auto middle = variation.begin() + static_cast<std::ptrdiff_t>(count / 2);
  std::nth_element(variation.begin(), middle, variation.end());
  return *middle;
}

// The side rule and its point or axis for a propagated `orientation`; `scene` is what the
// automatic rule took the cloud for (untouched for kUp / kDown).
PropagationConfig propagation_for(const PointCloud& cloud, NormalOrientation orientation,
                                  const NormalsConfig& config, SceneKind& scene) {
  PropagationConfig p = config.propagation;
  p.point = Eigen::Vector3f::Zero();
  switch (orientation) {
    case NormalOrientation::kUp:
      p.side = ComponentSide::kAlongAxis;
      p.axis = Eigen::Vector3f::UnitZ();
      break;
    case NormalOrientation::kDown:
      p.side = ComponentSide::kAlongAxis;
      p.axis = -Eigen::Vector3f::UnitZ();
      break;
    default:
      scene = classify_scene(cloud, config.whole_scene);
      p.side = side_of_scene(scene);
      p.axis = Eigen::Vector3f::UnitZ();
      break;
  }
  return p;
}

ComputedNormals normals_before_flip(const PointCloud& cloud, const SpatialIndex& index,
                                    const NormalsConfig& config) {
  const std::size_t n = cloud.size();
  const std::vector<std::uint8_t> usable = usable_input_normals(cloud);
  ComputedNormals out;
  NormalsReport& report = out.report;
  report.source = resolve_source(cloud, usable, config.source);

  // Which points get a plane fit: all, or only those without a usable input normal.
  std::vector<std::uint8_t> estimate;  // empty = all
  if (report.source == NormalSource::kInput) {
    estimate.resize(n);
    for (std::size_t i = 0; i < n; ++i) estimate[i] = usable[i] ? 0 : 1;
    report.estimated = static_cast<std::size_t>(std::count(estimate.begin(), estimate.end(), 1));
    out.normals.resize(n);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
      out.normals[i] = usable[i] ? cloud.normals[i].normalized() : Eigen::Vector3f::Zero();
    });
    if (report.estimated == 0) {
      // Exact samples of a CAD-like part with their exact normals: extended marching cubes
      // keeps its edges (the normals are used as they are).
      if (config.sharp == NormalsConfig::Sharp::kWhenClean) {
        report.kn = std::max(config.kn, 3);
        report.median_variation = sampled_median_variation(cloud, index, config.kn, 4096);
        report.sharp = report.median_variation < config.clean_variation;
      }
      report.sharp = report.sharp || config.sharp == NormalsConfig::Sharp::kOn;
      return out;
    }
  } else {
    report.estimated = n;
  }

  NormalOrientation orientation = config.orientation;
  if (orientation == NormalOrientation::kAuto) orientation = resolve_orientation(cloud);
  if (orientation == NormalOrientation::kInput && report.source == NormalSource::kEstimate &&
      std::find(usable.begin(), usable.end(), 1) == usable.end())
    orientation = cloud.has_sensor_origin || cloud.is_organized() ? NormalOrientation::kTowardSensor
                                                                  : NormalOrientation::kPropagate;
  // Points estimated among input normals always take their neighbours' orientation.
  if (report.source == NormalSource::kInput) orientation = NormalOrientation::kInput;
  report.orientation = orientation;

  NormalsConfig fit_config = config;
  fit_config.kn = std::max(config.kn, 3);
  const std::size_t ki = static_cast<std::size_t>(std::max(config.ki, 1));
  NeighbourTable table = build_neighbour_table(
      cloud.positions, index, std::max(static_cast<std::size_t>(fit_config.kn), ki));
  PlaneFits fits = plane_fits(cloud, index, table, estimate, fit_config);
  report.median_variation = median_variation(fits, estimate);
  if (config.noisy_variation > 0.0f && report.median_variation > config.noisy_variation) {
    fit_config.kn *= 2;  // noisy points: fit planes over twice the neighbours
    table = build_neighbour_table(cloud.positions, index,
                                  std::max(static_cast<std::size_t>(fit_config.kn), ki));
    fits = plane_fits(cloud, index, table, estimate, fit_config);
  }
  report.kn = fit_config.kn;
  // Orientation works on the plane fits as they are: across a sharp edge sharp normals are
  // perpendicular and give the spanning tree no sign to pass on, while the fits there blend the
  // two faces and carry it. Sharp normals then take the signs of their points' oriented fits.
  std::vector<Eigen::Vector3f> fitted = normals_of(fits);

  // The viewpoint in the cloud's local frame (it is given in the file's own coordinates).
  const Eigen::Vector3f viewpoint = (config.viewpoint.cast<double>() - cloud.origin).cast<float>();
  switch (orientation) {
    case NormalOrientation::kAuto:  // resolved above
    case NormalOrientation::kTowardSensor:
      orient_to_viewpoint(cloud, cloud.has_sensor_origin ? cloud.sensor_origin : viewpoint, 1.0f,
                          fitted);
      break;
    case NormalOrientation::kTowardViewpoint:
      orient_to_viewpoint(cloud, viewpoint, 1.0f, fitted);
      break;
    case NormalOrientation::kAwayFromViewpoint:
      orient_to_viewpoint(cloud, viewpoint, -1.0f, fitted);
      break;
    case NormalOrientation::kPropagate:
    case NormalOrientation::kUp:
    case NormalOrientation::kDown:
    case NormalOrientation::kInput: {
      // Fixed points: those with a usable input normal. Estimated ones take its sign; when the
      // source is the input, the input normal itself.
      std::vector<std::uint8_t> fixed;
      if (orientation == NormalOrientation::kInput) {
        fixed = usable;
        for (std::size_t i = 0; i < n; ++i) {
          if (!usable[i]) continue;
          if (report.source == NormalSource::kInput)
            fitted[i] = out.normals[i];
          else if (fitted[i].dot(cloud.normals[i]) < 0.0f)
            fitted[i] = -fitted[i];
        }
      }
      for (Eigen::Vector3f& v : fitted)
        if (v.isZero()) v = Eigen::Vector3f::UnitX();  // fewer than 3 neighbours
      const PropagationConfig propagation =
          propagation_for(cloud, orientation, config, report.scene);
      OrientedNormals oriented =
          orient_by_propagation(cloud.positions, fitted, table, fixed, propagation);
      report.components = oriented.components;
      report.flipped_by_vote = oriented.flipped_by_vote;
      report.side = oriented.side;
      report.view_agreement = oriented.view_agreement;
      report.side_axis = propagation.axis;
      fitted = std::move(oriented.normals);
      break;
    }
  }
  report.sharp =
      config.sharp == NormalsConfig::Sharp::kOn ||
      (config.sharp == NormalsConfig::Sharp::kWhenClean &&
       orientation == NormalOrientation::kPropagate && report.source == NormalSource::kEstimate &&
       report.median_variation < config.clean_variation);
  if (report.sharp)
    fitted = signed_like(flattest_plane_normals(fits, cloud, table, estimate), fitted);
  // With sharp features, neighbours across an edge (more than 25 degrees off) are not averaged.
  const float min_agreement = report.sharp ? 0.9f : -1.0f;
  out.normals =
      ki <= 1 ? std::move(fitted) : interpolate(fitted, table, ki, estimate, min_agreement);
  return out;
}

}  // namespace

ComputedNormals compute_normals(const PointCloud& cloud, const SpatialIndex& index,
                                const NormalsConfig& config) {
  ComputedNormals out = normals_before_flip(cloud, index, config);
  if (config.flip) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.normals.size(), 8192),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i)
                          out.normals[i] = -out.normals[i];
                      });
    out.report.flipped = true;
  }
  return out;
}

std::vector<Eigen::Vector3f> estimate_normals(const PointCloud& cloud, const SpatialIndex& index,
                                              const NormalsConfig& config) {
  NormalsConfig c = config;
  c.source = NormalSource::kEstimate;
  return compute_normals(cloud, index, c).normals;
}

}  // namespace meshflow
