#pragma once
// Inputs shared by the benchmarks: a synthetic 100k-point scan and, when present, kurt3d
// scan000. Every benchmark takes the thread count as its first argument (1 or 2).

#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "graph/frame.h"
#include "nodes/optimize/optimize_mesh.h"
#include "runtime/point_cloud.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::bench {

enum Input : int { kSynthetic = 0, kKurt3d = 1, kRedwood = 2, kSyntheticDepth = 3 };

/// The input cloud (cached); nullptr when kurt3d is requested but $MESHFLOW_DATA lacks it.
const PointCloud* input_cloud(Input input);

/// $MESHFLOW_DATA (default ../shared/data beside the source tree).
std::string data_dir();

/// Path of kurt3d/scan000.3d under data_dir().
std::string kurt3d_path();

/// A frame advanced through the stages up to and excluding `stage` ("normals", "voxelize",
/// "distance", "extract", "optimize"), at 5 cm voxels; cached per input.
const Frame* prepared_frame(Input input, const std::string& stage);

/// Skips with a message when the input is missing; returns the cloud otherwise.
const PointCloud* require(benchmark::State& state, Input input);

/// Five 640 x 480 depth frames: the Redwood frames (empty when $MESHFLOW_DATA lacks them), or
/// the first five of a 40-frame synthetic turn in the demo room. Cached.
const std::vector<DepthFrame>& depth_frames(bool redwood);

/// depth_frames(redwood), or null after skipping `state` with a message when they are missing.
const std::vector<DepthFrame>* require_depth_frames(benchmark::State& state, bool redwood);

/// The mesh the extract stage makes of input state.range(1) at 5 cm, or null after skipping
/// `state` when the input is missing. Cached.
const TriangleMesh* extracted_mesh(benchmark::State& state);

/// extracted_mesh() after the clean step (manifold, so every optimize step runs). Cached.
const TriangleMesh* cleaned_mesh(benchmark::State& state);

/// Counters of a mesh-to-mesh step: triangles/s over the input, input and output triangles.
void count_triangles(benchmark::State& state, const TriangleMesh& in, std::size_t out);

/// Counters of a simplification's accuracy: the mean and 95th percentile (millimetres) of the
/// distances from the vertices of `input` to the surface of `output` (evaluate_surface()'s
/// reference_to_mesh). Run once after the timing loop; O((V + T) log T).
void count_distance_to_input(benchmark::State& state, const TriangleMesh& input,
                             const TriangleMesh& output);

/// Times optimize_mesh(mesh, config) on state.range(0) threads, then count_triangles(). With
/// `feature_vertices` (the extraction's, one per vertex): the seeded optimize_mesh().
void time_optimize(benchmark::State& state, const TriangleMesh& mesh, const OptimizeConfig& config,
                   const std::vector<std::uint8_t>* feature_vertices = nullptr);

/// Registers the standard argument grid: threads {1, 2} x inputs {synthetic, kurt3d}.
void thread_and_input_args(benchmark::internal::Benchmark* b);

}  // namespace meshflow::bench
