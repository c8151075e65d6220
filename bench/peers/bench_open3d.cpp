// Open3D (Debian's libopen3d-dev, C++ API) on the inputs and thread counts of meshflow's own
// benchmarks, so that every meshflow / Open3D ratio comes from one run of one binary:
//   BM_Open3dNormals       <-> BM_NormalsWithIndex (bench_normals.cpp): k = 10 kNN + PCA, the
//                              kd-tree built inside the timed region on both sides;
//   BM_Open3dTsdfIntegrate <-> BM_TsdfIntegrate (bench_fusion.cpp): the five Redwood frames
//                              with colour, truncation 4 voxels, a fresh map per iteration;
//   BM_Open3dTsdfExtract   <-> BM_TsdfExtract: marching cubes over the same fused map.
// Compiled only when CMake finds Open3D (MESHFLOW_BENCH_OPEN3D); scripts/bench_tables.py pairs
// the rows. Open3D parallelises with OpenMP: each benchmark sets its thread count with
// omp_set_num_threads(), as meshflow's set theirs with ThreadLimit.

#include <omp.h>

#include <open3d/camera/PinholeCameraIntrinsic.h>
#include <open3d/geometry/Image.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/RGBDImage.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/pipelines/integration/ScalableTSDFVolume.h>
#include <open3d/utility/Parallel.h>
#include <algorithm>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "bench_support.h"

namespace meshflow::bench {
namespace {

// Open3D's thread count for the benchmark's first argument. Open3D 0.16 sizes some of its
// OpenMP loops by utility::EstimateMaxThreads(), which ignores omp_set_num_threads() (it takes
// the physical core count) unless OMP_NUM_THREADS is set in the environment; libgomp has read
// that variable before main(), so setting it here only makes Open3D ask OpenMP. Returns false
// after skipping `state` when Open3D would still use another count.
bool open3d_threads(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  setenv("OMP_NUM_THREADS", std::to_string(threads).c_str(), /*overwrite=*/0);
  omp_set_num_threads(threads);
  if (open3d::utility::EstimateMaxThreads() == threads) return true;
  state.SkipWithError("Open3D does not take the thread count (OMP_NUM_THREADS set otherwise?)");
  return false;
}

open3d::geometry::PointCloud to_open3d(const PointCloud& cloud) {
  open3d::geometry::PointCloud out;
  out.points_.reserve(cloud.size());
  for (const Eigen::Vector3f& p : cloud.positions) out.points_.push_back(p.cast<double>());
  return out;
}

// Open3D's normals as its users call them: EstimateNormals over a KDTreeFlann that it builds
// itself, k = 10, on the cloud BM_Normals reads (the input after the filter stage). Clearing the
// normals keeps each iteration from orienting by the previous one's. Open3D orients nothing
// here and interpolates nothing; meshflow's side also turns the normals towards the sensor and
// averages them over ki = 10 neighbours (its default stage).
void BM_Open3dNormals(benchmark::State& state) {
  const auto input = static_cast<Input>(state.range(1));
  if (require(state, input) == nullptr || !open3d_threads(state)) return;
  open3d::geometry::PointCloud cloud = to_open3d(prepared_frame(input, "normals")->cloud);
  for (auto _ : state) {
    cloud.normals_.clear();
    cloud.EstimateNormals(open3d::geometry::KDTreeSearchParamKNN(10));
    benchmark::DoNotOptimize(cloud.normals_.data());
  }
  state.counters["points/s"] = benchmark::Counter(static_cast<double>(cloud.points_.size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Open3dNormals)->Apply(thread_and_input_args);

// The meshflow frames as Open3D RGBD images (depth in metres, colour as RGB8) with their
// intrinsics and extrinsics (camera from world), made once: meshflow's benchmarks, too, start
// from frames already in memory. depth_trunc is far enough for no pixel to be dropped, as
// meshflow drops none.
struct Open3dFrames {
  std::vector<std::shared_ptr<open3d::geometry::RGBDImage>> images;
  std::vector<Eigen::Matrix4d> extrinsics;
  open3d::camera::PinholeCameraIntrinsic intrinsic;
};

open3d::geometry::Image to_open3d(const Image& image, int channels, int bytes_per_channel) {
  open3d::geometry::Image out;
  out.Prepare(image.cols(), image.rows(), channels, bytes_per_channel);
  // Both store rows contiguously, without padding.
  std::copy_n(image.data(), image.pixels() * bytes_per_pixel(image.format()), out.data_.data());
  return out;
}

const Open3dFrames& open3d_frames(const std::vector<DepthFrame>& frames) {
  static const Open3dFrames converted = [&] {
    Open3dFrames out;
    const PinholeIntrinsics& k = frames.front().intrinsics;
    out.intrinsic.SetIntrinsics(k.width, k.height, k.fx, k.fy, k.cx, k.cy);
    for (const DepthFrame& f : frames) {
      out.images.push_back(open3d::geometry::RGBDImage::CreateFromColorAndDepth(
          to_open3d(f.color, 3, 1), to_open3d(f.depth, 1, 2), f.depth_scale,
          /*depth_trunc=*/1e3, /*convert_rgb_to_intensity=*/false));
      out.extrinsics.push_back(f.T_world_camera.inverse().matrix().cast<double>());
    }
    return out;
  }();
  return converted;
}

// The Redwood frames (with colour) or null after skipping `state`.
const Open3dFrames* require_open3d_frames(benchmark::State& state) {
  const std::vector<DepthFrame>* frames = require_depth_frames(state, /*redwood=*/true);
  if (frames == nullptr) return nullptr;
  if (frames->front().color.empty() || frames->front().depth.format() != PixelFormat::U16) {
    state.SkipWithError("the Redwood frames lack colour or U16 depth");
    return nullptr;
  }
  return &open3d_frames(*frames);
}

// Open3D's hashed TSDF at `voxel` metres with colour and meshflow's truncation (4 voxels).
std::unique_ptr<open3d::pipelines::integration::ScalableTSDFVolume> open3d_volume(float voxel) {
  return std::make_unique<open3d::pipelines::integration::ScalableTSDFVolume>(
      voxel, 4.0 * voxel, open3d::pipelines::integration::TSDFVolumeColorType::RGB8);
}

void integrate_all(open3d::pipelines::integration::ScalableTSDFVolume& volume,
                   const Open3dFrames& frames) {
  for (std::size_t i = 0; i < frames.images.size(); ++i)
    volume.Integrate(*frames.images[i], frames.intrinsic, frames.extrinsics[i]);
}

// Args: threads, voxel in 0.1 mm. Timed like BM_TsdfIntegrate: the map made outside the timed
// region, its destruction inside.
void BM_Open3dTsdfIntegrate(benchmark::State& state) {
  const Open3dFrames* frames = require_open3d_frames(state);
  if (frames == nullptr || !open3d_threads(state)) return;
  const float voxel = static_cast<float>(state.range(1)) * 1e-4f;
  for (auto _ : state) {
    state.PauseTiming();
    auto volume = open3d_volume(voxel);
    state.ResumeTiming();
    integrate_all(*volume, *frames);
  }
  const auto n = static_cast<double>(frames->images.size());
  state.counters["frames/s"] = benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_Open3dTsdfIntegrate)
    ->ArgNames({"threads", "voxel_0.1mm"})
    ->ArgsProduct({{1, 2}, {100, 50}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Open3dTsdfExtract(benchmark::State& state) {
  const Open3dFrames* frames = require_open3d_frames(state);
  if (frames == nullptr || !open3d_threads(state)) return;
  auto volume = open3d_volume(static_cast<float>(state.range(1)) * 1e-4f);
  integrate_all(*volume, *frames);
  std::size_t triangles = 0;
  for (auto _ : state) triangles = volume->ExtractTriangleMesh()->triangles_.size();
  state.counters["triangles"] = static_cast<double>(triangles);
}
BENCHMARK(BM_Open3dTsdfExtract)
    ->ArgNames({"threads", "voxel_0.1mm"})
    ->ArgsProduct({{1, 2}, {100, 50}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace meshflow::bench
