#pragma once
// Boxes drilled with cylindrical holes, blind and through, along the box's axes: closed objects
// (closed_objects.h) with many concave pockets, whose floors and walls a camera circling them
// sees only in part and at grazing angles — the hard case of fusion's completeness. Kept out of
// closed_test_objects(): the perforated box is held out for comparing fused maps with Open3D
// (bench/peers/fusion_vs_open3d.cpp), the pocketed block is the tests' concave object.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "nodes/synthetic/closed_objects.h"

namespace meshflow::synthetic {

/// One cylindrical hole drilled into a face of the box along a box axis.
struct BoxHole {
  int axis = 2;       ///< 0, 1, 2: x, y, z
  float side = 1.0f;  ///< +1 or -1: enters through the face at +half_size or -half_size
  float a = 0.0f;     ///< the hole's axis position along box axis (axis + 1) % 3, metres
  float b = 0.0f;     ///< ... and along (axis + 2) % 3, from the box's centre
  float radius = 0.05f;
  float depth = 0.1f;  ///< metres; at least the box's size along `axis`: a through hole
};

/// An axis-aligned box of half sizes `half_size`, centred at `center`, minus its holes. The
/// holes' disks must lie inside their faces and apart, and the holes must not meet inside.
struct PerforatedBox {
  Eigen::Vector3f center = Eigen::Vector3f::Zero();
  Eigen::Vector3f half_size = Eigen::Vector3f(0.4f, 0.3f, 0.2f);
  std::vector<BoxHole> holes;
};

/// The closed surface of `box`: its faces minus the holes' disks, each hole's wall and each
/// blind hole's floor, with exact distances and area-uniform samples (ClosedObject). Asserts
/// that the disks lie inside their faces and apart (the holes' meeting inside is not checked).
/// O(holes^2).
ClosedObject perforated_box_object(const PerforatedBox& box, const std::string& name);

/// "perforated-box": 0.8 x 0.6 x 0.4 m, thirteen holes (six blind ones 0.10-0.18 m deep in the
/// top, two through along x, two blind in the bottom, three shallow in the sides), radii
/// 0.04-0.08 m. Held out: the Open3D comparison's object, never tuned on.
ClosedObject perforated_box_object();

/// "pocketed-block": 0.6 x 0.5 x 0.3 m, five holes (three blind pockets 0.12-0.2 m deep in the
/// top, a through hole along y, a blind one in the side), radii 0.045-0.07 m: the tests' object.
ClosedObject pocketed_block_object();

}  // namespace meshflow::synthetic
