#include "nodes/io/rgbd_sequences.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include "runtime/image.h"

#include "nodes/io/image_io.h"
#include "nodes/io/parse_util.h"
#include "nodes/io/text_chunks.h"
#include "runtime/error.h"

namespace meshflow::io {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> sorted_files(const fs::path& dir,
                                      const std::vector<std::string>& extensions) {
  std::vector<std::string> files;
  if (!fs::is_directory(dir)) return files;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string ext = lower_extension(e.path().string());
    if (e.is_regular_file() &&
        std::find(extensions.begin(), extensions.end(), ext) != extensions.end()) {
      files.push_back(e.path().string());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string first_json(const fs::path& dir) {
  const auto files = sorted_files(dir, {".json"});
  return files.empty() ? std::string() : files.front();
}

Image read_color_image(const std::string& path) {
  if (!fs::exists(path)) throw Error(path, "", "colour image missing");
  return read_color_image_file(path);
}

// Checks the depth image against the intrinsics and attaches colour when its size matches.
DepthFrame make_frame(const std::string& depth_path, const std::string& color_path, float scale,
                      const PinholeIntrinsics& k, const Eigen::Isometry3f& T_world_camera,
                      double timestamp) {
  DepthFrame f;
  f.depth = read_depth_image(depth_path);
  if (f.depth.cols() != k.width || f.depth.rows() != k.height) {
    throw Error(depth_path, "",
                "image is " + std::to_string(f.depth.cols()) + "x" +
                    std::to_string(f.depth.rows()) + " but the intrinsics are for " +
                    std::to_string(k.width) + "x" + std::to_string(k.height));
  }
  f.depth_scale = scale;
  f.intrinsics = k;
  f.T_world_camera = T_world_camera;
  f.timestamp_s = timestamp;
  if (!color_path.empty()) {
    Image color = read_color_image(color_path);
    if (color.same_size(f.depth)) f.color = color;
  }
  return f;
}

// Depth images listed in order, paired with colour images, under one camera model. Poses come
// from a trajectory file (Redwood) or, without one, every frame is in the camera frame.
struct DepthImageList {
  std::string description;  // e.g. "Redwood RGB-D frames in DIR"
  std::vector<std::string> depth, color;
  PinholeIntrinsics intrinsics;
  double frame_period_s = 1.0;  // timestamps are index x period
  float depth_scale = 1000.0f;  // depth units per metre
  std::string trajectory;       // empty: identity poses
  std::vector<Eigen::Isometry3f> poses;
};

class DepthImageListSequence final : public Sequence {
 public:
  explicit DepthImageListSequence(DepthImageList list) : list_(std::move(list)) {}
  std::size_t size() const override { return list_.depth.size(); }
  SequenceFrame frame(std::size_t i) const override {
    SequenceFrame f;
    f.index = i;
    f.timestamp_s = static_cast<double>(i) * list_.frame_period_s;
    f.name = list_.depth[i];
    const std::string depth = list_.depth[i];
    const std::string color = i < list_.color.size() ? list_.color[i] : std::string();
    const bool posed = !list_.trajectory.empty();
    const bool has_pose = !posed || i < list_.poses.size();
    const Eigen::Isometry3f T_world_camera =
        posed && has_pose ? list_.poses[i] : Eigen::Isometry3f::Identity();
    const std::string trajectory = list_.trajectory;
    const PinholeIntrinsics k = list_.intrinsics;
    const float scale = list_.depth_scale;
    const double t = f.timestamp_s;
    f.load_depth = [=] {
      if (!has_pose) {
        throw Error(trajectory, "",
                    "pose missing for frame " + std::to_string(i) + " (" + depth + ")");
      }
      return make_frame(depth, color, scale, k, T_world_camera, t);
    };
    return f;
  }
  std::string description() const override {
    return list_.description + " (" + std::to_string(list_.depth.size()) + " frames" +
           (list_.trajectory.empty() ? ", no poses)" : ")");
  }

 private:
  DepthImageList list_;
};

struct TimedFile {
  double t;
  std::string file;
};

std::vector<TimedFile> read_timed_list(const std::string& path, const fs::path& base) {
  std::ifstream in = open_input(path);
  std::vector<TimedFile> out;
  std::string line;
  std::vector<std::string_view> tok;
  for (std::size_t n = 1; read_line(in, line); ++n) {
    split_whitespace(line, tok);
    if (tok.empty() || tok[0].front() == '#') continue;
    if (tok.size() != 2)
      throw Error(path, "line " + std::to_string(n), "expected 'timestamp filename'");
    out.push_back(
        {parse_finite(tok[0], path, n, "timestamp"), (base / std::string(tok[1])).string()});
  }
  return out;
}

}  // namespace

std::vector<TimedPose> read_tum_groundtruth(const std::string& path) {
  std::ifstream in = open_input(path);
  std::vector<TimedPose> out;
  std::string line;
  std::vector<std::string_view> tok;
  static const char* kFields[] = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  for (std::size_t n = 1; read_line(in, line); ++n) {
    split_whitespace(line, tok);
    if (tok.empty() || tok[0].front() == '#') continue;
    if (tok.size() != 8)
      throw Error(path, "line " + std::to_string(n), "expected 'timestamp tx ty tz qx qy qz qw'");
    double v[8];
    for (int k = 0; k < 8; ++k)
      v[k] = parse_finite(tok[static_cast<std::size_t>(k)], path, n, kFields[k]);
    const Eigen::Quaternionf q(static_cast<float>(v[7]), static_cast<float>(v[4]),
                               static_cast<float>(v[5]), static_cast<float>(v[6]));
    if (!(std::abs(q.norm() - 1.0f) < 1e-2f))
      throw Error(path, "line " + std::to_string(n), "quaternion is not unit length");
    const Eigen::Vector3d t(v[1], v[2], v[3]);
    check_position(t, path, "line " + std::to_string(n), "translation");
    Eigen::Isometry3f T_world_camera = Eigen::Isometry3f::Identity();
    T_world_camera.linear() = q.normalized().toRotationMatrix();
    T_world_camera.translation() = t.cast<float>();
    out.push_back({v[0], T_world_camera});
  }
  std::sort(out.begin(), out.end(),
            [](const TimedPose& a, const TimedPose& b) { return a.t < b.t; });
  return out;
}

namespace {

class TumSequence final : public Sequence {
 public:
  TumSequence(std::string dir, std::vector<TimedFile> depth, std::vector<TimedFile> rgb,
              std::vector<TimedPose> poses, PinholeIntrinsics k)
      : dir_(std::move(dir)),
        depth_(std::move(depth)),
        rgb_(std::move(rgb)),
        poses_(std::move(poses)),
        k_(k) {}
  std::size_t size() const override { return depth_.size(); }
  SequenceFrame frame(std::size_t i) const override {
    constexpr double kMaxGap = 0.02;  // seconds, as TUM's associate.py
    SequenceFrame f;
    f.index = i;
    f.timestamp_s = depth_[i].t;
    f.name = depth_[i].file;
    const TimedPose* timed = nearest(poses_, depth_[i].t, kMaxGap);
    const TimedFile* rgb = nearest(rgb_, depth_[i].t, kMaxGap);
    const std::string depth = depth_[i].file, color = rgb ? rgb->file : std::string();
    const double t = depth_[i].t;
    const std::string list = (fs::path(dir_) / "depth.txt").string();
    const bool has_pose = timed != nullptr;
    const Eigen::Isometry3f T_world_camera =
        has_pose ? timed->T_world_camera : Eigen::Isometry3f::Identity();
    const PinholeIntrinsics k = k_;
    f.load_depth = [=] {
      if (!has_pose) {
        char when[32];
        std::snprintf(when, sizeof when, "%.6f", t);
        throw Error(list, std::string("timestamp ") + when, "no ground-truth pose within 20 ms");
      }
      return make_frame(depth, color, 5000.0f, k, T_world_camera, t);
    };
    return f;
  }
  std::string description() const override {
    return "TUM RGB-D frames in " + dir_ + " (" + std::to_string(depth_.size()) + " frames)";
  }

 private:
  template <typename T>
  static const T* nearest(const std::vector<T>& items, double t, double max_gap) {
    const T* best = nullptr;
    for (const T& item : items) {
      if (std::abs(item.t - t) <= max_gap &&
          (best == nullptr || std::abs(item.t - t) < std::abs(best->t - t)))
        best = &item;
    }
    return best;
  }

  std::string dir_;
  std::vector<TimedFile> depth_, rgb_;
  std::vector<TimedPose> poses_;
  PinholeIntrinsics k_;
};

std::vector<std::string> files_containing(const std::vector<std::string>& files,
                                          const std::vector<std::string>& words) {
  std::vector<std::string> out;
  for (const std::string& f : files) {
    const std::string name = fs::path(f).filename().string();
    for (const std::string& w : words) {
      if (name.find(w) != std::string::npos) {
        out.push_back(f);
        break;
      }
    }
  }
  return out;
}

// The number between <tag> and </tag> inside `section`; NaN when the tag is missing.
double xml_number(const std::string& section, const std::string& tag, const std::string& path) {
  const std::size_t open = section.find("<" + tag + ">");
  if (open == std::string::npos) return std::nan("");
  const std::size_t from = open + tag.size() + 2;
  const std::size_t close = section.find("</" + tag + ">", from);
  if (close == std::string::npos) throw Error(path, tag, "the element is not closed");
  std::string token = section.substr(from, close - from);
  token.erase(0, token.find_first_not_of(" \t\r\n"));
  token.erase(token.find_last_not_of(" \t\r\n") + 1);
  return parse_number(token, path, tag, tag);
}

// The depth camera of a PCL image grabber's XML (<depth> focal_length_x/y, principal_point_x/y,
// z_multiplication_factor in metres per unit); missing values keep `k`'s and the scale's.
void read_grabber_xml(const std::string& path, PinholeIntrinsics& k, float& depth_scale) {
  const std::string text = read_whole_file(path);
  const std::size_t start = text.find("<depth>");
  const std::size_t end = text.find("</depth>");
  if (start == std::string::npos || end == std::string::npos || end < start)
    throw Error(path, "depth", "expected a <depth> element with the depth camera's intrinsics");
  const std::string section = text.substr(start, end - start);
  const auto take = [&](const char* tag, float& into, double low, double high) {
    const double v = xml_number(section, tag, path);
    if (std::isnan(v)) return;
    if (!(v > low && v <= high))
      throw Error(path, tag,
                  "expected a value in (" + std::to_string(low) + ", " + std::to_string(high) +
                      "], got " + std::to_string(v));
    into = static_cast<float>(v);
  };
  take("focal_length_x", k.fx, 0.0, 1e6);
  take("focal_length_y", k.fy, 0.0, 1e6);
  take("principal_point_x", k.cx, -1e6, 1e6);
  take("principal_point_y", k.cy, -1e6, 1e6);
  float metres_per_unit = 1.0f / depth_scale;
  take("z_multiplication_factor", metres_per_unit, 0.0, 1e3);
  depth_scale = 1.0f / metres_per_unit;
}

}  // namespace

std::unique_ptr<Sequence> open_depth_image_directory(const std::string& directory) {
  const auto images = sorted_files(directory, {".png", ".tif", ".tiff", ".jpg", ".jpeg", ".pclzf"});
  auto depth = files_containing(images, {"depth"});
  if (depth.empty())
    throw Error(directory, "", "no depth images (*depth*.png / .tif / .tiff / .pclzf)");
  auto color = files_containing(images, {"rgb", "color"});
  if (color.size() != depth.size()) color.clear();
  const std::string json = first_json(directory);
  PinholeIntrinsics k;
  k.cx = 320.0f;  // PCL's Kinect grabber convention
  k.cy = 240.0f;
  float depth_scale = 1000.0f;
  if (!json.empty()) {
    k = read_intrinsics_json(json);
  } else if (const auto xml = sorted_files(directory, {".xml"}); !xml.empty()) {
    read_grabber_xml(xml.front(), k, depth_scale);  // PCL's grabber: one per frame, all alike
  }
  DepthImageList list;
  list.depth_scale = depth_scale;
  list.description = "depth images in " + directory;
  list.depth = std::move(depth);
  list.color = std::move(color);
  list.intrinsics = k;
  return std::make_unique<DepthImageListSequence>(std::move(list));
}

Image read_depth_image(const std::string& path) {
  if (!fs::exists(path)) throw Error(path, "", "depth image missing");
  return read_depth_image_file(path);
}

std::vector<Eigen::Isometry3f> read_trajectory_log(const std::string& path) {
  std::ifstream in = open_input(path);
  std::vector<Eigen::Isometry3f> poses;
  std::string line;
  std::vector<std::string_view> tok;
  std::size_t n = 0;
  auto next_line = [&]() {
    do {
      if (!read_line(in, line)) return false;
      ++n;
      split_whitespace(line, tok);
    } while (tok.empty());
    return true;
  };
  while (next_line()) {
    if (tok.size() != 3)
      throw Error(path, "line " + std::to_string(n), "expected the block header 'i j k'");
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r) {
      if (!next_line())
        throw Error(path, "line " + std::to_string(n + 1), "file ends inside a 4x4 matrix");
      if (tok.size() != 4)
        throw Error(path, "line " + std::to_string(n), "expected 4 matrix entries");
      for (int c = 0; c < 4; ++c)
        m(r, c) = parse_number(tok[static_cast<std::size_t>(c)], path, n, "matrix");
    }
    if (!m.allFinite() || (m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-6 ||
        (m.block<3, 3>(0, 0).transpose() * m.block<3, 3>(0, 0) - Eigen::Matrix3d::Identity())
                .norm() > 1e-3) {
      throw Error(path, "line " + std::to_string(n), "matrix is not a rigid transform");
    }
    check_position(m.block<3, 1>(0, 3), path, "line " + std::to_string(n), "translation");
    Eigen::Isometry3d pose(m);
    poses.push_back(pose.cast<float>());
  }
  return poses;
}

PinholeIntrinsics read_intrinsics_json(const std::string& path) {
  std::ifstream in = open_input(path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw Error(path, "", std::string("invalid JSON: ") + e.what());
  }
  if (!j.contains("intrinsic_matrix") || !j["intrinsic_matrix"].is_array() ||
      j["intrinsic_matrix"].size() != 9 || !j.contains("width") || !j.contains("height")) {
    throw Error(
        path, "",
        "expected {\"width\", \"height\", \"intrinsic_matrix\": [9 numbers, column-major]}");
  }
  // Every value is read as a double and range-checked before it is converted: a huge width or
  // focal length must be an error, not an undefined conversion or an infinite float.
  const auto number = [&](const nlohmann::json& value, const char* field, double low, double high) {
    if (!value.is_number()) throw Error(path, field, "expected a number, got " + value.dump());
    const double x = value.get<double>();
    if (!(x >= low && x <= high)) {
      char range[64];
      std::snprintf(range, sizeof range, "[%g, %g]", low, high);
      throw Error(path, field, value.dump() + " is outside " + range);
    }
    return x;
  };
  const auto size = [&](const char* field) {
    const double x = number(j[field], field, 1.0, 65535.0);
    if (x != std::floor(x)) throw Error(path, field, "expected a whole number of pixels");
    return static_cast<int>(x);
  };
  constexpr double kMaxFocal = 1e6, kMaxCentre = 1e6;  // pixels
  const auto& m = j["intrinsic_matrix"];
  PinholeIntrinsics k;
  k.width = size("width");
  k.height = size("height");
  k.fx = static_cast<float>(number(m[0], "intrinsic_matrix[0] (fx)", 1e-3, kMaxFocal));
  k.fy = static_cast<float>(number(m[4], "intrinsic_matrix[4] (fy)", 1e-3, kMaxFocal));
  k.cx = static_cast<float>(number(m[6], "intrinsic_matrix[6] (cx)", -kMaxCentre, kMaxCentre));
  k.cy = static_cast<float>(number(m[7], "intrinsic_matrix[7] (cy)", -kMaxCentre, kMaxCentre));
  return k;
}

std::unique_ptr<Sequence> open_redwood_directory(const std::string& directory) {
  const fs::path dir(directory);
  auto depth = sorted_files(dir / "depth", {".png"});
  if (depth.empty()) throw Error(directory, "depth/", "no depth PNG files");
  auto color = sorted_files(dir / "color", {".jpg", ".jpeg", ".png"});
  if (color.size() != depth.size()) color.clear();  // pair only when the counts agree
  std::string trajectory = (dir / "trajectory.log").string();
  if (!fs::exists(trajectory)) trajectory = (dir / "odometry.log").string();
  if (!fs::exists(trajectory))
    throw Error(directory, "", "no trajectory.log or odometry.log with the camera poses");
  const std::string json = first_json(dir);
  DepthImageList list;
  list.description = "Redwood RGB-D frames in " + directory;
  list.depth = std::move(depth);
  list.color = std::move(color);
  list.intrinsics = json.empty() ? PinholeIntrinsics{} : read_intrinsics_json(json);
  list.frame_period_s = 1.0 / 30.0;
  list.poses = read_trajectory_log(trajectory);
  list.trajectory = trajectory;
  return std::make_unique<DepthImageListSequence>(std::move(list));
}

std::unique_ptr<Sequence> open_tum_directory(const std::string& directory) {
  const fs::path dir(directory);
  auto depth = read_timed_list((dir / "depth.txt").string(), dir);
  if (depth.empty()) throw Error((dir / "depth.txt").string(), "", "lists no depth images");
  std::vector<TimedFile> rgb;
  if (fs::exists(dir / "rgb.txt")) rgb = read_timed_list((dir / "rgb.txt").string(), dir);
  auto poses = read_tum_groundtruth((dir / "groundtruth.txt").string());
  const std::string json = first_json(dir);
  const PinholeIntrinsics k = json.empty() ? PinholeIntrinsics{} : read_intrinsics_json(json);
  return std::make_unique<TumSequence>(directory, std::move(depth), std::move(rgb),
                                       std::move(poses), k);
}

}  // namespace meshflow::io
