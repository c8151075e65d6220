#include "nodes/io/textured_obj.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "nodes/io/atomic_file.h"
#include "nodes/io/image_io.h"
#include "runtime/error.h"

namespace meshflow::io {
void write_textured_obj(const std::string& path, const TexturedMesh& textured) {
  const TriangleMesh& mesh = textured.mesh;
  const std::filesystem::path obj(path);
  const std::string stem = obj.stem().string();
  const std::filesystem::path directory = obj.parent_path();
  auto beside = [&](const std::string& name) { return (directory / name).string(); };
  const std::string library = stem + ".mtl";
  std::vector<std::string> images;
  for (std::size_t k = 0; k < textured.textures.size(); ++k) {
    images.push_back(stem + "_region" + std::to_string(k) + ".png");
    write_png(beside(images.back()), textured.textures[k].image);
  }

  AtomicOutputFile materials(beside(library));
  materials.stream() << "# written by meshflow\nnewmtl vertex_colours\nKd 1 1 1\n";
  for (std::size_t k = 0; k < images.size(); ++k)
    materials.stream() << "newmtl region" << k << "\nKa 1 1 1\nKd 1 1 1\nmap_Kd " << images[k]
                       << "\n";
  materials.commit();

  AtomicOutputFile file(path);
  std::ostream& out = file.stream();
  out << "# written by meshflow\nmtllib " << library << "\n";
  const bool colors = mesh.colors.size() == mesh.vertices.size();
  char line[160];
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    const Eigen::Vector3f& p = mesh.vertices[v];
    if (colors) {
      const Rgb8& c = mesh.colors[v];
      std::snprintf(line, sizeof line, "v %.9g %.9g %.9g %.4f %.4f %.4f\n", p.x(), p.y(), p.z(),
                    c.r / 255.0, c.g / 255.0, c.b / 255.0);
    } else {
      std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", p.x(), p.y(), p.z());
    }
    out << line;
  }
  // Texture coordinates of the textured faces, in face order, three each.
  std::vector<std::uint32_t> first_uv(mesh.triangles.size(), 0);
  std::uint32_t uv_count = 0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (textured.texture_of_face[t] < 0) continue;
    first_uv[t] = uv_count + 1;
    for (std::size_t k = 0; k < 3; ++k) {
      const Eigen::Vector2f& uv = textured.uv[3 * t + k];
      std::snprintf(line, sizeof line, "vt %.7g %.7g\n", uv.x(), uv.y());
      out << line;
    }
    uv_count += 3;
  }
  // Faces grouped by material: vertex colours first, then each texture.
  std::vector<std::uint32_t> order(mesh.triangles.size());
  for (std::uint32_t t = 0; t < order.size(); ++t) order[t] = t;
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return textured.texture_of_face[a] < textured.texture_of_face[b];
  });
  std::int32_t current = -2;
  for (std::uint32_t t : order) {
    const std::int32_t material = textured.texture_of_face[t];
    if (material != current) {
      current = material;
      if (material < 0)
        out << "usemtl vertex_colours\n";
      else
        out << "usemtl region" << material << "\n";
    }
    const Triangle& f = mesh.triangles[t];
    if (material < 0)
      std::snprintf(line, sizeof line, "f %u %u %u\n", f[0] + 1, f[1] + 1, f[2] + 1);
    else
      std::snprintf(line, sizeof line, "f %u/%u %u/%u %u/%u\n", f[0] + 1, first_uv[t], f[1] + 1,
                    first_uv[t] + 1, f[2] + 1, first_uv[t] + 2);
    out << line;
  }
  file.commit();
}

}  // namespace meshflow::io
