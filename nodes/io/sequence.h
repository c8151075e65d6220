#pragma once
// Recorded sequences: an indexed list of frames that are loaded on demand, so the flow graph
// reads several frames concurrently and memory stays bounded by the frames in flight.

#include <cstddef>
#include <functional>
#include <memory>
#include <string>

#include "runtime/depth_frame.h"
#include "runtime/point_cloud.h"

namespace meshflow::io {

/// One frame of a sequence, not yet loaded.
struct SequenceFrame {
  std::size_t index = 0;     ///< 0-based position in the sequence
  double timestamp_s = 0.0;  ///< seconds (the index when the sequence has no clock)
  std::string name;          ///< file(s) behind the frame, for messages and output names
  /// Loads the frame as a cloud in the world frame (metres, sensor origin set when known).
  /// Valid while the Sequence that made it lives.
  /// Throws meshflow::Error naming the file and the problem. Safe to call from any thread.
  std::function<PointCloud()> load;
  /// For depth-camera sequences instead of `load`: the depth image with intrinsics and pose.
  std::function<DepthFrame()> load_depth;
};

/// A random-access sequence of frames. frame() is cheap (no I/O); thread-safe.
class Sequence {
 public:
  virtual ~Sequence() = default;
  /// Number of frames.
  virtual std::size_t size() const = 0;
  /// Frame i (0 <= i < size()), not loaded yet.
  virtual SequenceFrame frame(std::size_t i) const = 0;
  /// One line: kind, location and frame count, e.g. "3DTK scans in data/kurt3d (3 frames)".
  virtual std::string description() const = 0;
};

/// Opens `path` as a sequence: a Redwood / Open3D RGB-D directory (depth/, trajectory.log), a
/// TUM RGB-D directory (depth.txt, groundtruth.txt), a directory of cloud files (.pcd, .ply;
/// e.g. organized Kinect frames), a directory of depth images (*depth*.tiff/.png/.pclzf, no poses),
/// a directory of 3DTK scans (scanNNN.3d with scanNNN.pose), or a single point-cloud file. Throws
/// meshflow::Error when the path holds none of these.
std::unique_ptr<Sequence> open_sequence(const std::string& path);

/// The frames of a 3DTK directory: every scanNNN.3d in numeric order, each with its
/// scanNNN.pose, which is required (a frame without one fails to load, naming the file).
std::unique_ptr<Sequence> open_3dtk_directory(const std::string& directory);

}  // namespace meshflow::io
