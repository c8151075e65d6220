#include "bench/peers/fused_map_measures.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "nodes/eval/surface_eval.h"
#include "nodes/eval/truth_eval.h"
#include "nodes/search/mesh_distance_index.h"

namespace meshflow::fusion_peer {
namespace {

// Each reference point's distance to the mesh's surface.
std::vector<float> distances_to(const TriangleMesh& mesh, const std::vector<Eigen::Vector3f>& at) {
  std::vector<float> out(at.size(), std::numeric_limits<float>::infinity());
  if (mesh.triangles.empty()) return out;
  const MeshDistanceIndex index(mesh);
  tbb::parallel_for(std::size_t{0}, at.size(),
                    [&](std::size_t i) { out[i] = index.closest(at[i]).distance; });
  return out;
}

// What meshflow's map holds in the cell around p; for a cell with some corners unobserved, also
// where those corners are (in no block: never allocated; in a block: never updated) and the
// sign of the observed ones.
enum Cell { kNothing, kPartlyObserved, kAllInFront, kAllBehind, kSignChange, kCellKinds };
const char* const kCellNames[kCellKinds] = {"no corner observed", "some corners unobserved",
                                            "all observed, in front (+)",
                                            "all observed, behind (-)", "a sign change (meshed)"};
struct CellState {
  Cell kind = kNothing;
  int in_no_block = 0, unobserved = 0, in_front = 0, observed = 0;
};

CellState cell_at(const TsdfMap& map, const Eigen::Vector3f& p, float min_weight) {
  const float voxel = map.config().voxel_size;
  const Eigen::Vector3i base = (p / voxel).array().floor().cast<int>();
  CellState s;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3i v = base + Eigen::Vector3i(c & 1, (c >> 1) & 1, (c >> 2) & 1);
    const Eigen::Vector3i block = (v.cast<float>() / kTsdfBlockSide).array().floor().cast<int>();
    const TsdfBlock* b = map.find(block);
    if (b == nullptr) {
      ++s.in_no_block;
      continue;
    }
    const Eigen::Vector3i local = v - block * kTsdfBlockSide;
    const TsdfVoxel& voxel_at = b->voxels[static_cast<std::size_t>(
        local.x() + kTsdfBlockSide * (local.y() + kTsdfBlockSide * local.z()))];
    if (!(voxel_at.weight > min_weight)) {
      ++s.unobserved;
      continue;
    }
    ++s.observed;
    s.in_front += voxel_at.distance >= 0.0f ? 1 : 0;
  }
  if (s.observed == 0)
    s.kind = kNothing;
  else if (s.in_front > 0 && s.in_front < s.observed)
    s.kind = kSignChange;
  else if (s.observed < 8)
    s.kind = kPartlyObserved;
  else
    s.kind = s.in_front == 8 ? kAllInFront : kAllBehind;
  return s;
}

}  // namespace

std::vector<char> seen_by_frames(const io::Sequence& sequence,
                                 const std::vector<Eigen::Vector3f>& points, float tolerance) {
  std::vector<DepthFrame> frames;
  std::vector<Image> depths;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    frames.push_back(sequence.frame(i).load_depth());
    depths.push_back(depth_in_metres(frames.back()));
  }
  std::vector<char> seen(points.size(), 0);
  tbb::parallel_for(std::size_t{0}, points.size(), [&](std::size_t i) {
    for (std::size_t f = 0; f < frames.size() && seen[i] == 0; ++f) {
      const PinholeIntrinsics& k = frames[f].intrinsics;
      const Eigen::Vector3f q = frames[f].T_world_camera.inverse() * points[i];
      if (!(q.z() > 0.0f)) continue;
      const float u = std::round(k.fx * q.x() / q.z() + k.cx);
      const float v = std::round(k.fy * q.y() / q.z() + k.cy);
      if (!(u >= 0.0f && v >= 0.0f && u < static_cast<float>(k.width) &&
            v < static_cast<float>(k.height)))
        continue;
      const float d = depths[f].at<float>(static_cast<int>(v), static_cast<int>(u));
      seen[i] = d > 0.0f && std::abs(d - q.z()) <= tolerance ? 1 : 0;
    }
  });
  return seen;
}

// The world point of pixel (u, v) at depth z: T_world_camera ((u - cx) z / fx, (v - cy) z / fy, z)
// (depth_frame.h's camera).
std::vector<Eigen::Vector3f> frame_points(const io::Sequence& sequence) {
  std::vector<Eigen::Vector3f> out;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const DepthFrame f = sequence.frame(i).load_depth();
    const Image depth = depth_in_metres(f);
    const PinholeIntrinsics& k = f.intrinsics;
    for (int v = 0; v < depth.rows(); v += 2)
      for (int u = 0; u < depth.cols(); u += 2) {
        const float z = depth.at<float>(v, u);
        if (z > 0.1f && z < 10.0f)
          out.push_back(f.T_world_camera *
                        Eigen::Vector3f((static_cast<float>(u) - k.cx) * z / k.fx,
                                        (static_cast<float>(v) - k.cy) * z / k.fy, z));
      }
  }
  return out;
}

Measures measure(const TriangleMesh& mesh, const Scene& scene, float tau) {
  Measures m;
  m.to_mesh = distances_to(mesh, scene.reference);
  if (scene.object) {
    const synthetic::ClosedObject& object = *scene.object;
    m.accuracy = evaluate_against_truth(
                     mesh, [&](const Eigen::Vector3f& p) { return object.distance(p); }, 200000)
                     .area.mean /
                 scene.unit;
  } else {
    TriangleMesh points;
    points.vertices = scene.reference;
    m.accuracy = evaluate_surface(mesh, points).mesh_to_reference.mean / scene.unit;
  }
  double sum = 0.0;
  std::size_t within[2] = {}, within_twice[2] = {}, seen = 0;  // [0]: all, [1]: seen
  for (std::size_t i = 0; i < m.to_mesh.size(); ++i) {
    const float d = m.to_mesh[i];
    const std::size_t s = scene.seen[i] != 0 ? 1 : 0;
    sum += d;
    seen += s;
    within[0] += d <= tau ? 1 : 0;
    within_twice[0] += d <= 2.0f * tau ? 1 : 0;
    within[1] += d <= tau ? s : 0;
    within_twice[1] += d <= 2.0f * tau ? s : 0;
  }
  const double n = static_cast<double>(m.to_mesh.size());
  const double n_seen = static_cast<double>(std::max<std::size_t>(seen, 1));
  m.completeness = sum / n / scene.unit;
  m.within = static_cast<double>(within[0]) / n;
  m.within_twice = static_cast<double>(within_twice[0]) / n;
  m.seen = static_cast<double>(seen) / n;
  m.seen_within = static_cast<double>(within[1]) / n_seen;
  m.seen_within_twice = static_cast<double>(within_twice[1]) / n_seen;
  m.triangles = mesh.triangles.size();
  m.border_edges = edge_statistics(mesh).boundary_edges;
  return m;
}

void report(const char* tool, const Measures& m, float tau) {
  std::printf(
      "%-9s accuracy %.3e  completeness mean %.3e  within %.1f mm %.4f  within %.1f mm %.4f  "
      "triangles %zu  border edges %zu\n"
      "%-9s of the %.2f %% measured by a frame: within %.1f mm %.4f  within %.1f mm %.4f\n",
      tool, m.accuracy, m.completeness, 1e3 * tau, m.within, 2e3 * tau, m.within_twice, m.triangles,
      m.border_edges, "", 100.0 * m.seen, 1e3 * tau, m.seen_within, 2e3 * tau, m.seen_within_twice);
}

// The reference points within tau of one mesh and not of the other, by meshflow's cell there
// (and by the object's patch with --patches).
void breakdown(const Scene& scene, const TsdfMap& map, const Measures& ours, const Measures& theirs,
               float tau, float min_weight, bool patches_too) {
  const std::size_t n = scene.reference.size();
  const std::size_t patches = scene.object ? scene.object->patches.size() : 0;
  struct Side {
    std::size_t only = 0, unseen = 0, kinds[kCellKinds] = {};
    std::size_t corners_in_no_block = 0, corners_unobserved = 0, observed_in_front = 0,
                observed_behind = 0;
    std::vector<std::size_t> by_patch;
  } sides[2];
  for (Side& s : sides) s.by_patch.assign(patches, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const bool ours_has = ours.to_mesh[i] <= tau, theirs_has = theirs.to_mesh[i] <= tau;
    if (ours_has == theirs_has) continue;
    Side& side = sides[theirs_has ? 0 : 1];  // 0: Open3D keeps, meshflow drops
    ++side.only;
    side.unseen += scene.seen[i] == 0 ? 1 : 0;
    const CellState cell = cell_at(map, scene.reference[i], min_weight);
    ++side.kinds[cell.kind];
    if (cell.kind == kPartlyObserved) {
      side.corners_in_no_block += static_cast<std::size_t>(cell.in_no_block);
      side.corners_unobserved += static_cast<std::size_t>(cell.unobserved);
      ++(cell.in_front > 0 ? side.observed_in_front : side.observed_behind);
    }
    if (patches_too && patches > 0) {
      const auto& all = scene.object->patches;
      std::size_t nearest = 0;
      for (std::size_t k = 1; k < patches; ++k)
        if (all[k].distance(scene.reference[i]) < all[nearest].distance(scene.reference[i]))
          nearest = k;
      ++side.by_patch[nearest];
    }
  }
  const char* const names[2] = {"Open3D keeps, meshflow drops", "meshflow keeps, Open3D drops"};
  for (int k = 0; k < 2; ++k) {
    const Side& side = sides[k];
    std::printf(
        "%s: %zu of %zu reference points (%.2f %%; %zu measured by no frame); meshflow's cell "
        "there:\n",
        names[k], side.only, n, 100.0 * static_cast<double>(side.only) / static_cast<double>(n),
        side.unseen);
    for (int c = 0; c < kCellKinds; ++c) std::printf("  %-28s %zu\n", kCellNames[c], side.kinds[c]);
    std::printf(
        "    (some unobserved: observed corners in front %zu, behind %zu; unobserved corners in "
        "no block %zu, in a block %zu)\n",
        side.observed_in_front, side.observed_behind, side.corners_in_no_block,
        side.corners_unobserved);
    if (patches_too && patches > 0) {
      std::printf("  by patch:");
      for (std::size_t p = 0; p < patches; ++p)
        if (side.by_patch[p] > 0) std::printf(" %zu:%zu", p, side.by_patch[p]);
      std::printf("\n");
    }
  }
}

}  // namespace meshflow::fusion_peer
