#include "nodes/io/tum_writer.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <system_error>

#include "nodes/io/atomic_file.h"
#include "nodes/io/image_io.h"
#include "runtime/error.h"

namespace meshflow::io {
namespace {

constexpr float kTumDepthScale = 5000.0f;  // units per metre, TUM's convention

Image tum_depth(const DepthFrame& frame) {
  const Image metres = depth_in_metres(frame);
  Image out(metres.rows(), metres.cols(), PixelFormat::U16);
  for (int v = 0; v < metres.rows(); ++v) {
    const float* in = metres.ptr<float>(v);
    auto* row = out.ptr<std::uint16_t>(v);
    for (int u = 0; u < metres.cols(); ++u) {
      const float units = in[u] > 0.0f && std::isfinite(in[u]) ? in[u] * kTumDepthScale : 0.0f;
      row[u] = static_cast<std::uint16_t>(std::lround(std::min(units, 65535.0f)));
    }
  }
  return out;
}

std::string format(const char* pattern, double a) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, pattern, a);
  return buffer;
}

void write_text(const std::string& path, const std::string& text) {
  AtomicOutputFile file(path);
  file.stream() << text;
  file.commit();
}

}  // namespace

void write_tum_directory(const Sequence& sequence, const std::string& directory) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(fs::path(directory) / "depth", ec);
  if (ec) throw Error(directory, "directory", "cannot be created: " + ec.message());
  std::string depth_list = "# depth maps written by meshflow\n# timestamp filename\n";
  std::string rgb_list = "# colour images written by meshflow\n# timestamp filename\n";
  std::string poses =
      "# ground truth trajectory written by meshflow\n# timestamp tx ty tz qx qy qz qw\n";
  PinholeIntrinsics intrinsics;
  bool any_color = false;
  double previous_time = -1.0;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const SequenceFrame f = sequence.frame(i);
    if (!f.load_depth) throw Error(f.name, "frame", "is a point cloud, not a depth image");
    const DepthFrame frame = f.load_depth();
    intrinsics = frame.intrinsics;
    double time = f.timestamp_s;
    if (!(time > previous_time)) time = static_cast<double>(i) / 30.0;
    previous_time = time;
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.png", i);
    const std::string stamp = format("%.6f", time);
    write_png((fs::path(directory) / "depth" / name).string(), tum_depth(frame));
    depth_list += stamp + " depth/" + name + "\n";
    if (frame.color.format() == PixelFormat::RGB8 && frame.color.same_size(frame.depth)) {
      if (!any_color) fs::create_directories(fs::path(directory) / "rgb", ec);
      if (ec) throw Error(directory, "rgb directory", "cannot be created: " + ec.message());
      any_color = true;
      write_png((fs::path(directory) / "rgb" / name).string(), frame.color);
      rgb_list += stamp + " rgb/" + name + "\n";
    }
    const Eigen::Vector3f t = frame.T_world_camera.translation();
    const Eigen::Quaternionf q(frame.T_world_camera.linear());
    char line[256];
    std::snprintf(line, sizeof line, "%s %.7f %.7f %.7f %.7f %.7f %.7f %.7f\n", stamp.c_str(),
                  t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
    poses += line;
  }
  write_text((fs::path(directory) / "depth.txt").string(), depth_list);
  if (any_color) write_text((fs::path(directory) / "rgb.txt").string(), rgb_list);
  write_text((fs::path(directory) / "groundtruth.txt").string(), poses);
  char camera[512];
  std::snprintf(camera, sizeof camera,
                "{\n  \"width\": %d,\n  \"height\": %d,\n  \"intrinsic_matrix\": [%.6f, 0, 0, 0, "
                "%.6f, 0, %.6f, %.6f, 1]\n}\n",
                intrinsics.width, intrinsics.height, static_cast<double>(intrinsics.fx),
                static_cast<double>(intrinsics.fy), static_cast<double>(intrinsics.cx),
                static_cast<double>(intrinsics.cy));
  write_text((fs::path(directory) / "camera.json").string(), camera);
}

}  // namespace meshflow::io
