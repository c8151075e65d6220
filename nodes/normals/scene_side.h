#pragma once
// Which way a scene without a sensor position faces: the side rule that consistent propagation
// of normals turns each component to (orient_by_propagation()). Decided from the cloud alone:
// its format (LAS and map coordinates fix +z as up), its geometry (one camera view in its
// camera's frame; one surface over the x-y plane, as a terrain tile), else a closed object.

#include <Eigen/Core>

#include "nodes/normals/orient_normals.h"
#include "runtime/point_cloud.h"

namespace meshflow {

/// What kind of scene classify_scene() took a cloud for, in the order it tests them.
enum class SceneKind {
  kMapFrame,     ///< PointCloud::z_up (LAS, clouds in map coordinates): up
  kCameraView,   ///< looks_like_camera_view(): towards the origin if the normals agree
  kHeightField,  ///< looks_like_height_field(): a terrain tile in local coordinates, up if
                 ///< the normals agree on it
  kObject        ///< anything else (closed objects): outward
};

/// The kind of `cloud` (finite positions; non-finite ones are ignored): kMapFrame when
/// cloud.z_up; else, when `whole_scene` (false for a piece of a larger cloud, such as an
/// out-of-core chunk, where a local test could disagree with its neighbours), kCameraView or
/// kHeightField by the geometric tests below (a camera's cloud of a bin seen from above is
/// both: the camera wins); else kObject. O(n), parallel, independent of the thread count.
SceneKind classify_scene(const PointCloud& cloud, bool whole_scene = true);

/// The side rule for a kind: kAlongAxis (+z) for kMapFrame, kAxisOrOutward (+z) for
/// kHeightField (a closed thin plate lying flat is a height field too: its normals do not
/// agree on up), kViewOrOutward towards the origin for kCameraView, kOutward for kObject. O(1).
ComponentSide side_of_scene(SceneKind kind);

/// side_of_scene(classify_scene(cloud, whole_scene)).
ComponentSide scene_side(const PointCloud& cloud, bool whole_scene = true);

/// Short name for reports and JSON: "map-frame", "camera-view", "height-field", "object".
const char* scene_kind_name(SceneKind kind);

/// Whether `cloud` may be one view from the origin of its coordinates, as depth-camera clouds
/// are when written in the camera's frame (Open3D, PCL; invalid pixels dropped, no VIEWPOINT):
/// not georeferenced, the origin outside the points' bounding box, at least 99 % of the finite
/// points in front of it (z > 0) within 75 degrees of +z (wider than any depth camera's field
/// of view) and within 25 m of it (a depth or stereo camera's range), and their mean direction
/// within 40 degrees of +z (the image lies around the optical axis). Geometry only:
/// kViewOrOutward then checks that the normals agree. O(n), parallel.
/// Ambiguous by nature: a terrain tile above an origin at its centre looks like a camera
/// looking up; LAS files are told apart by PointCloud::z_up.
bool looks_like_camera_view(const PointCloud& cloud);

/// Whether `cloud` is one surface over the x-y plane, z a function of x and y (a terrain or
/// floor tile in local coordinates): over a grid of square columns sized to hold about 16
/// points each if the points covered their x-y bounds in one layer, at least 80 % of the
/// finite points lie in columns whose height range is at most 3 column widths (slopes up to
/// about 65 degrees). A closed object fails (each column crosses it twice: its range is the
/// object's thickness), as do rooms (floor and ceiling) and clouds with fewer than 64 points.
/// O(n + columns), parallel over points, independent of the thread count.
bool looks_like_height_field(const PointCloud& cloud);

}  // namespace meshflow
