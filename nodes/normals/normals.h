#pragma once
// Point normals for the Hoppe distance: taken from the input where it has them, otherwise
// estimated by k-nearest-neighbour PCA plane fits (Hoppe et al. 1992), oriented (towards the
// sensor, or consistently by propagation where there is none) and smoothed by interpolation
// over neighbours (Wiemann 2013, LVR).

#include <Eigen/Core>
#include <vector>

#include "nodes/normals/orient_normals.h"
#include "nodes/normals/scene_side.h"
#include "nodes/search/spatial_index.h"
#include "runtime/point_cloud.h"

namespace meshflow {

/// How estimated normals are turned (the sign of a plane fit is arbitrary).
enum class NormalOrientation {
  /// The signs of the cloud's own normals where it has them (kInput); else towards the sensor
  /// where the cloud carries one (a scan pose, a PCD VIEWPOINT, an organized depth-camera
  /// cloud: kTowardSensor); else consistent propagation (kPropagate), each component turned
  /// by classify_scene(): up for LAS, map coordinates and height fields (terrain tiles),
  /// towards the origin for one camera view in its camera frame, outward for everything else
  /// (closed objects).
  kAuto,
  kTowardSensor,       ///< towards cloud.sensor_origin (the origin when it has none)
  kTowardViewpoint,    ///< towards NormalsConfig::viewpoint
  kAwayFromViewpoint,  ///< away from `viewpoint` (e.g. the centre of a closed object)
  kPropagate,  ///< orient_by_propagation(), components turned by scene_side() (no sensor needed)
  /// Each estimated normal takes the sign of the cloud's normal at that point; points whose
  /// normal is missing (zero, NaN) are reached by propagation from the others.
  kInput,
  kUp,   ///< propagation, each component facing +z on the whole (terrain, floors)
  kDown  ///< propagation, each component facing -z on the whole (ceilings, scans from below)
};

/// Where normals come from.
enum class NormalSource {
  kAuto,     ///< the cloud's own normals when it has any (kInput), else kEstimate
  kInput,    ///< the cloud's normals, normalised; missing ones (zero, NaN) estimated
  kEstimate  ///< plane fits for every point, whatever the cloud carries
};

struct NormalsConfig {
  NormalSource source = NormalSource::kAuto;
  int kn = 10;  ///< neighbours of the plane fit (thesis default kn = 10)
  int ki = 10;  ///< neighbours averaged in normal interpolation; 0 or 1 = off (thesis ki = 10)
  /// Thesis bounding-box criterion: when the kn neighbours' bounding box (taken in their
  /// principal frame) is degenerate, its middle extent below `adaptive_ratio` x its largest as
  /// for points along one laser line, k is doubled until the box is well shaped or
  /// `adaptive_max_k` is reached.
  bool adaptive_k = false;
  float adaptive_ratio = 0.2f;
  int adaptive_max_k = 80;
  NormalOrientation orientation = NormalOrientation::kAuto;
  /// Metres, in the file's own coordinates: for a georeferenced cloud (PointCloud::origin not
  /// zero) the world coordinates, moved into the cloud's local frame here.
  Eigen::Vector3f viewpoint = Eigen::Vector3f::Zero();
  /// kPropagate / kInput / kUp / kDown (their `side` is set by compute_normals()).
  PropagationConfig propagation;
  /// Every output normal turned over at the end, the input's own included (`--orient flip`:
  /// the automatic result, the other way round).
  bool flip = false;
  /// Whether the cloud is the whole scene, so propagation without a sensor may take it for one
  /// camera view or a height field by its geometry (classify_scene()); off for pieces of a
  /// larger cloud (the out-of-core chunks), where neighbouring pieces could disagree.
  bool whole_scene = true;
  /// Normals for sharp features (extended marching cubes): each point takes the plane of the
  /// flattest neighbourhood within two rings of neighbours that passes through it
  /// (neighbourhood shifting), and interpolation skips neighbours more than 25 degrees off, so
  /// points beside a box edge get their face's normal instead of a blend of two faces. For
  /// exact or nearly exact samples of CAD-like parts; on noisy points it keeps the noise (at
  /// 0.05 voxel of noise extended marching cubes on them is 1.2-2x less accurate than marching
  /// cubes on the blended fits). kWhenClean: only for estimated normals oriented by
  /// propagation (no sensor) whose median plane-fit variation is below clean_variation. The
  /// reconstruction pipeline asks for kOn with `--extract emc` and kWhenClean with the default
  /// `--extract auto`.
  enum class Sharp { kOff, kOn, kWhenClean };
  Sharp sharp = Sharp::kOff;
  /// Samples as exact as a CAD export or a sampled mesh: median variation 0.0000-0.0001;
  /// Gaussian noise of 0.02 voxel already gives 0.001-0.002, kurt3d 0.015.
  float clean_variation = 0.0005f;
  /// Noisy points: when the median plane-fit variation (smallest eigenvalue over their sum)
  /// exceeds this, the planes are fitted again over 2 kn neighbours. Measured at kn = 10: exact
  /// samples 0.0000-0.0001, kurt3d 0.015, the bunny 0.014, samples with Gaussian noise of 0.1 /
  /// 0.2 voxel (at 1 % of the diagonal, 100 000 points) 0.026-0.045 / 0.075-0.10, where kn = 20
  /// brings the mesh's mean error from 0.11-0.12 to 0.08-0.09 voxel. 0 = off.
  float noisy_variation = 0.04f;
};

/// What compute_normals() did.
struct NormalsReport {
  NormalSource source = NormalSource::kEstimate;  ///< resolved: kInput or kEstimate
  /// Resolved orientation of the estimated normals (kAuto when none was estimated).
  NormalOrientation orientation = NormalOrientation::kAuto;
  std::size_t estimated = 0;        ///< points whose normal was estimated (0: all from the input)
  int kn = 0;                       ///< neighbours of the plane fits (2 kn for noisy points)
  float median_variation = 0.0f;    ///< of the first fits (see NormalsConfig::noisy_variation)
  bool sharp = false;               ///< sharp-feature normals (see NormalsConfig::sharp)
  std::size_t components = 0;       ///< propagation: components of the neighbour graph
  std::size_t flipped_by_vote = 0;  ///< propagation: normals turned by the final vote
  /// Propagation: the side its components were turned to (kViewOrOutward resolved).
  ComponentSide side = ComponentSide::kOutward;
  Eigen::Vector3f side_axis = Eigen::Vector3f::UnitZ();  ///< kAlongAxis's axis
  /// Automatic propagation (kAuto / kPropagate): what the cloud was taken for.
  SceneKind scene = SceneKind::kObject;
  double view_agreement = 0.0;  ///< when the camera-view test ran: its agreement (0-1)
  bool flipped = false;         ///< NormalsConfig::flip applied
};

struct ComputedNormals {
  std::vector<Eigen::Vector3f> normals;  ///< one unit normal per point
  NormalsReport report;
};

/// Unit normals for every point of `cloud` (finite positions required) as `config` says (see
/// NormalSource and NormalOrientation; kAuto resolves from the cloud: its normals, its sensor).
/// `index` must be built over cloud.positions. Input normals are used as they are (normalised);
/// a point whose input normal is zero or not finite gets an estimated one, turned to agree with
/// its neighbours'. Output independent of the thread count; parallel over points;
/// O(n (kn + ki) log n), plus O(n k log n) for propagation.
ComputedNormals compute_normals(const PointCloud& cloud, const SpatialIndex& index,
                                const NormalsConfig& config);

/// compute_normals() with plane fits for every point (NormalSource::kEstimate), normals only.
/// Points with fewer than 3 neighbours get the direction to the viewpoint (sensor orientations)
/// or an arbitrary axis before propagation.
std::vector<Eigen::Vector3f> estimate_normals(const PointCloud& cloud, const SpatialIndex& index,
                                              const NormalsConfig& config);

/// The orientation kAuto resolves to for `cloud` (never kAuto): kInput when it has normals,
/// kTowardSensor when it carries a sensor or is organized, else kPropagate. O(1).
NormalOrientation resolve_orientation(const PointCloud& cloud);

/// "auto", "sensor", "viewpoint", "away-from-viewpoint", "propagate", "input", "up" or "down".
const char* orientation_name(NormalOrientation orientation);

/// The side rule's name for reports and JSON: "outward", "towards-origin" (kTowardPoint, the
/// one point compute_normals() looks from), "up" / "down" (kAlongAxis along +z / -z), "axis".
const char* side_name(ComponentSide side, const Eigen::Vector3f& axis);

/// Normal of the least-squares plane through `points` (smallest-eigenvalue eigenvector of the
/// covariance), unit length, arbitrary sign; zero vector for fewer than 3 points.
Eigen::Vector3f fit_plane_normal(const std::vector<Eigen::Vector3f>& points);

}  // namespace meshflow
