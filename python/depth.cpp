// Depth images from Python: camera intrinsics, per-frame triangulation and TSDF fusion.

#include <pybind11/stl.h>
#include <algorithm>

#include <string>

#include "graph/stages.h"
#include "nodes/fusion/tsdf_mesher.h"
#include "nodes/fusion/tsdf_volume.h"
#include "nodes/triangulate/depth_triangulation.h"
#include "python/bindings.h"
#include "runtime/error.h"

namespace meshflow::python {

DepthFrame make_depth_frame(const py::handle& depth, const PinholeIntrinsics& intrinsics,
                            const py::object& pose, float depth_scale, const py::object& color) {
  const py::array given = py::array::ensure(depth);
  if (!given || given.ndim() != 2) throw py::value_error("depth: expected a (height, width) array");
  DepthFrame frame;
  const int rows = static_cast<int>(given.shape(0)), cols = static_cast<int>(given.shape(1));
  if (given.dtype().kind() == 'u' || given.dtype().kind() == 'i') {
    const auto d =
        py::array_t<std::uint16_t, py::array::c_style | py::array::forcecast>::ensure(given);
    frame.depth = Image(rows, cols, PixelFormat::U16, d.data(), cols * sizeof(std::uint16_t));
  } else if (given.dtype().kind() == 'f') {
    const auto d = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(given);
    frame.depth = Image(rows, cols, PixelFormat::F32, d.data(), cols * sizeof(float));
  } else {
    throw py::value_error("depth: expected uint16 (1/depth_scale metres) or float (metres), got " +
                          std::string(py::str(given.dtype())));
  }
  frame.depth_scale = depth_scale;
  frame.intrinsics = intrinsics;
  if (!pose.is_none()) {
    const auto m = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(pose);
    if (!m || m.ndim() != 2 || m.shape(0) != 4 || m.shape(1) != 4)
      throw py::value_error("pose: expected a 4 x 4 camera-to-world matrix");
    Eigen::Matrix4f t;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) t(r, c) = m.at(r, c);
    if (!t.allFinite()) throw py::value_error("pose: not finite (NaN or infinity)");
    frame.T_world_camera.matrix() = t;
  }
  if (!color.is_none()) {
    const auto c =
        py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(color);
    if (!c || c.ndim() != 3 || c.shape(0) != rows || c.shape(1) != cols || c.shape(2) != 3)
      throw py::value_error("color: expected a (height, width, 3) uint8 array of the depth's size");
    frame.color = Image(rows, cols, PixelFormat::RGB8, c.data(), cols * 3);
  }
  check_depth_frame(frame);
  return frame;
}

void set_triangulation(DepthTriangulationConfig& config, const std::string& method,
                       float decimate) {
  if (method == "naive") {
    config.method = DepthTriangulationMethod::kNaive;
  } else if (method == "rqt") {
    config.method = DepthTriangulationMethod::kRestrictedQuadtree;
  } else {
    throw py::value_error("method: expected 'naive' or 'rqt', got '" + method + "'");
  }
  if (!(decimate >= 0.0f && decimate < 1.0f))
    throw py::value_error("decimate: expected a share in [0, 1) (0 = off)");
  config.decimate_to = decimate;
}

namespace {

Mesh to_mesh(TriangleMesh triangles) {
  Mesh mesh;
  *mesh.data = std::move(triangles);
  return mesh;
}

// TsdfVolume with the mesher that keeps the meshes of unchanged blocks between extractions.
struct Volume {
  TsdfVolume volume;
  TsdfMesher mesher;
  explicit Volume(const TsdfConfig& config) : volume(config) {}
};

}  // namespace

void bind_depth(py::module_& m) {
  py::class_<PinholeIntrinsics>(m, "Intrinsics",
                                "Pinhole camera: u = fx x / z + cx, v = fy y / z + cy (pixels).")
      .def(py::init([](int width, int height, float fx, float fy, float cx, float cy) {
             return PinholeIntrinsics{width, height, fx, fy, cx, cy};
           }),
           py::arg("width"), py::arg("height"), py::arg("fx"), py::arg("fy"), py::arg("cx"),
           py::arg("cy"))
      .def_readwrite("width", &PinholeIntrinsics::width)
      .def_readwrite("height", &PinholeIntrinsics::height)
      .def_readwrite("fx", &PinholeIntrinsics::fx)
      .def_readwrite("fy", &PinholeIntrinsics::fy)
      .def_readwrite("cx", &PinholeIntrinsics::cx)
      .def_readwrite("cy", &PinholeIntrinsics::cy)
      .def("__repr__", [](const PinholeIntrinsics& k) {
        return "<meshflow.Intrinsics " + std::to_string(k.width) + "x" + std::to_string(k.height) +
               " fx " + std::to_string(k.fx) + ">";
      });

  m.def(
      "triangulate_depth",
      [](const py::handle& depth, const PinholeIntrinsics& intrinsics, const py::object& pose,
         const std::string& method, float decimate, float depth_scale, const py::object& color) {
        DepthTriangulationConfig config;
        set_triangulation(config, method, decimate);
        // The pipeline's own triangulate stage: vertex colours from the image, vertex normals.
        Frame frame;
        frame.name = "depth";
        frame.set_depth_image(make_depth_frame(depth, intrinsics, pose, depth_scale, color));
        ReconstructionConfig reconstruction;
        reconstruction.triangulation = config;
        py::gil_scoped_release no_gil;
        stages::triangulate(frame, reconstruction);
        return to_mesh(std::move(frame.mesh));
      },
      py::arg("depth"), py::arg("intrinsics"), py::arg("pose") = py::none(),
      py::arg("method") = "naive", py::arg("decimate") = 0.0f, py::arg("depth_scale") = 1000.0f,
      py::arg("color") = py::none(),
      R"(Triangulates one depth image in the world frame (pose: 4 x 4 camera-to-world; None =
the camera frame): 'naive' (two triangles per pixel quad, occlusion edges cut) or 'rqt' (the
restricted quadtree: large triangles where the surface is flat); decimate in (0, 1) keeps that
share of the triangles (QEM). Vertex colours when color is given. An image that gives no
triangle (no valid depth) raises meshflow.Error.)");

  py::class_<Volume>(m, "TsdfVolume",
                     "A sparse TSDF map (8^3-voxel blocks) that depth frames are fused into.")
      .def(
          py::init([](float voxel, float truncation, float behind, float max_weight,
                      bool fuse_color, const std::string& integrator, bool carve) {
            if (integrator != "projective" && integrator != "along-ray")
              throw Error("TsdfVolume", "integrator",
                          "must be 'projective' or 'along-ray', not '" + integrator + "'");
            TsdfConfig c;
            c.integrator =
                integrator == "along-ray" ? TsdfIntegrator::kAlongRay : TsdfIntegrator::kProjective;
            c.voxel_size = voxel;
            c.truncation_voxels = truncation;
            c.behind_voxels = std::min(behind, truncation);
            c.max_weight = max_weight;
            c.fuse_color = fuse_color;
            c.carve_free_space = carve;
            return std::make_unique<Volume>(c);
          }),
          py::arg("voxel") = TsdfConfig{}.voxel_size,
          py::arg("truncation") = TsdfConfig{}.truncation_voxels,
          py::arg("behind") = TsdfConfig{}.behind_voxels,
          py::arg("max_weight") = TsdfConfig{}.max_weight,
          py::arg("fuse_color") = TsdfConfig{}.fuse_color, py::arg("integrator") = "projective",
          py::arg("carve") = TsdfConfig{}.carve_free_space,
          "voxel in metres, truncation in voxels, behind: the least band behind each measured "
          "surface in voxels (the CLI's run --fuse defaults; behind = truncation: Open3D's "
          "symmetric band); integrator: 'projective' (each voxel of a touched block projected "
          "into the image) or 'along-ray' (each pixel's ray walks its band, voxblox-style); carve: "
          "frames carve existing surface where they measured free space a truncation behind it "
          "(moved objects and stray surface leave the map).")
      .def(
          "integrate",
          [](Volume& v, const py::handle& depth, const PinholeIntrinsics& intrinsics,
             const py::object& pose, float depth_scale, const py::object& color) {
            const DepthFrame frame = make_depth_frame(depth, intrinsics, pose, depth_scale, color);
            IntegrationStats s;
            {
              py::gil_scoped_release no_gil;
              s = v.volume.integrate(frame);
            }
            py::dict d;
            d["pixels_used"] = s.pixels_used;
            d["noise_per_depth2"] = s.noise_per_depth2;
            d["blocks_touched"] = s.blocks_touched;
            d["blocks_allocated"] = s.blocks_allocated;
            d["voxels_updated"] = s.voxels_updated;
            d["blocks_carved"] = s.blocks_carved;
            return d;
          },
          py::arg("depth"), py::arg("intrinsics"), py::arg("pose") = py::none(),
          py::arg("depth_scale") = 1000.0f, py::arg("color") = py::none(),
          "Fuses one depth frame seen from pose (4 x 4 camera-to-world); returns its counts: "
          "pixels_used, noise_per_depth2 (the frame's estimated depth noise, 1/m), "
          "blocks_touched, blocks_allocated, voxels_updated, blocks_carved (existing blocks "
          "updated as the free space the frame saw through).")
      .def(
          "extract",
          [](Volume& v, bool incremental) {
            py::gil_scoped_release no_gil;
            if (incremental) return to_mesh(v.mesher.extract(v.volume));
            TsdfMesher fresh;
            return to_mesh(fresh.extract(v.volume));
          },
          py::arg("incremental") = true,
          "The map's surface (marching cubes). incremental: blocks unchanged since the last call "
          "reuse their meshes (same result); False meshes every block.")
      .def_property_readonly("block_count", [](const Volume& v) { return v.volume.block_count(); })
      .def_property_readonly("memory_bytes",
                             [](const Volume& v) { return v.volume.memory_bytes(); });
}

}  // namespace meshflow::python
