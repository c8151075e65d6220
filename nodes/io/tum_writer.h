#pragma once
// Writes a depth-camera sequence in the TUM RGB-D layout (what open_tum_directory() reads, and
// what Open3D, ElasticFusion or BundleFusion users can load): meshflow's synthetic sequences on
// disk, so other tools can be measured on the same frames.

#include <string>

#include "nodes/io/sequence.h"

namespace meshflow::io {

/// Loads every frame of `sequence` (load_depth; frames with only a point cloud are an error) and
/// writes, under `directory` (created if missing): depth/NNNNNN.png (16-bit, 5000 units per
/// metre: depth up to 13.1 m, deeper pixels clipped), rgb/NNNNNN.png when the frames have RGB8
/// colour of the depth's size, depth.txt and rgb.txt ("timestamp file"), groundtruth.txt
/// ("timestamp tx ty tz qx qy qz qw", world from camera) and camera.json (Open3D's pinhole
/// JSON). Frame i's timestamp is its own, or i / 30 s when frames share one. Throws
/// meshflow::Error naming the frame or file that failed. Frames rendered in parallel inside,
/// written one at a time; O(frames x pixels).
void write_tum_directory(const Sequence& sequence, const std::string& directory);

}  // namespace meshflow::io
