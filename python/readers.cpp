// Readers for the inputs of the depth paths from Python, the same as the CLI's sequences use
// (nodes/io): depth and colour images, Redwood and TUM trajectories, Open3D camera intrinsics.

#include <pybind11/stl.h>

#include <cstring>
#include <string>

#include "nodes/io/image_io.h"
#include "nodes/io/parse_util.h"
#include "nodes/io/rgbd_sequences.h"
#include "python/bindings.h"

namespace meshflow::python {
namespace {

// The pixels of `image` as a new NumPy array of `shape` (copied).
template <typename T>
py::array_t<T> pixels_array(const Image& image, std::vector<py::ssize_t> shape) {
  py::array_t<T> out(shape);
  std::memcpy(out.mutable_data(), image.data(),
              image.row_bytes() * static_cast<std::size_t>(image.rows()));
  return out;
}

}  // namespace

void bind_readers(py::module_& m) {
  m.def(
      "read_depth",
      [](const std::string& path) {
        Image image;
        {
          py::gil_scoped_release no_gil;
          image = io::read_depth_image_file(path);
        }
        return pixels_array<std::uint16_t>(image, {image.rows(), image.cols()});
      },
      py::arg("path"),
      R"(Reads a 16-bit single-channel depth image (PNG, TIFF or PCL's PCLZF) as a (height, width)
uint16 array, as stored (Redwood and Kinect: millimetres, depth_scale 1000; TUM: 1/5000 m).
Raises meshflow.Error naming the file for a missing, corrupt, 8-bit or colour image.)");
  m.def(
      "read_color",
      [](const std::string& path) {
        Image image;
        {
          py::gil_scoped_release no_gil;
          image = io::read_color_image_file(path);
        }
        return pixels_array<std::uint8_t>(image, {image.rows(), image.cols(), 3});
      },
      py::arg("path"),
      R"(Reads a colour image (PNG, JPEG, TIFF, PCLZF) as a (height, width, 3) uint8 RGB array
(grey replicated, alpha dropped). Raises meshflow.Error naming the file.)");
  m.def(
      "read_trajectory",
      [](const std::string& path) {
        std::vector<io::TimedPose> poses;
        {
          py::gil_scoped_release no_gil;
          if (io::lower_extension(path) == ".log") {
            const std::vector<Eigen::Isometry3f> log = io::read_trajectory_log(path);
            for (std::size_t i = 0; i < log.size(); ++i)
              poses.push_back({static_cast<double>(i), log[i]});
          } else {
            poses = io::read_tum_groundtruth(path);
          }
        }
        const auto n = static_cast<py::ssize_t>(poses.size());
        py::array_t<double> times(n);
        py::array_t<float> matrices({n, py::ssize_t{4}, py::ssize_t{4}});
        auto t = times.mutable_unchecked<1>();
        auto view = matrices.mutable_unchecked<3>();
        for (py::ssize_t i = 0; i < n; ++i) {
          const io::TimedPose& p = poses[static_cast<std::size_t>(i)];
          t(i) = p.t;
          for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) view(i, r, c) = p.T_world_camera.matrix()(r, c);
        }
        return py::make_tuple(times, matrices);
      },
      py::arg("path"),
      R"(Reads a camera trajectory as (timestamps, poses): an (n,) float64 array and an (n, 4, 4)
float32 array of camera-to-world poses (the `pose` that push_depth() and TsdfVolume.integrate()
take). A Redwood / Open3D .log file (timestamps are the frame numbers 0, 1, ...), or a TUM
RGB-D groundtruth.txt ("timestamp tx ty tz qx qy qz qw", sorted by time). Raises meshflow.Error
naming the file and line for malformed input or a pose that is not rigid.)");
  m.def(
      "read_intrinsics", [](const std::string& path) { return io::read_intrinsics_json(path); },
      py::arg("path"),
      R"(Reads Open3D's camera JSON (width, height, intrinsic_matrix) as an Intrinsics. Raises
meshflow.Error naming the file and the field.)");
}

}  // namespace meshflow::python
