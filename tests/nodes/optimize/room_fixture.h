#pragma once
// The demo room (8 x 6 x 3 m, a table-sized box, a cabinet, a ball) scanned from its centre and
// reconstructed at 5 cm with the default pipeline: the optimisation tests' realistic input.

#include "graph/pipeline.h"
#include "nodes/synthetic/scan_simulator.h"

namespace meshflow::test {

constexpr float kRoomVoxel = 0.05f;

/// Built once per test binary (about a second); shared by the optimisation tests.
inline const TriangleMesh& room_mesh() {
  static const TriangleMesh mesh = [] {
    synthetic::ScanConfig scan;
    scan.azimuth_steps = 1440;
    scan.elevation_steps = 480;
    const PointCloud cloud = synthetic::simulate_scan(synthetic::demo_room_scene(), scan);
    ReconstructionConfig config;
    config.voxelize.voxel_size = kRoomVoxel;
    return ReconstructionPipeline(config).reconstruct(cloud, "room")->mesh;
  }();
  return mesh;
}

}  // namespace meshflow::test
