#include "nodes/io/glb_writer.h"

#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "nodes/io/atomic_file.h"
#include "nodes/io/glb_format.h"
#include "runtime/error.h"

namespace meshflow::io {
namespace {

using glb::kBinChunk;
using glb::kFloat;
using glb::kJsonChunk;
using glb::kUnsignedByte;
using glb::kUnsignedInt;

constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

template <typename T>
void append(std::vector<std::uint8_t>& out, const T& value) {
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(&value);
  out.insert(out.end(), bytes, bytes + sizeof(T));
}

// Appends one buffer view (and its accessor) over bytes appended to `bin` by `fill`.
class GltfBuffers {
 public:
  template <typename Fill>
  int add(std::size_t count, int component_type, const char* type, int target, bool normalized,
          Fill fill) {
    const std::size_t offset = bin_.size();
    fill(bin_);
    const int view = static_cast<int>(views_.size());
    views_.push_back({{"buffer", 0},
                      {"byteOffset", offset},
                      {"byteLength", bin_.size() - offset},
                      {"target", target}});
    nlohmann::json accessor = {
        {"bufferView", view}, {"componentType", component_type}, {"count", count}, {"type", type}};
    if (normalized) accessor["normalized"] = true;
    accessors_.push_back(std::move(accessor));
    return static_cast<int>(accessors_.size()) - 1;
  }
  nlohmann::json& accessor(int i) { return accessors_[static_cast<std::size_t>(i)]; }
  std::vector<std::uint8_t>& bin() { return bin_; }
  nlohmann::json views() const { return views_; }
  nlohmann::json accessors() const { return accessors_; }

 private:
  std::vector<std::uint8_t> bin_;
  nlohmann::json views_ = nlohmann::json::array();
  nlohmann::json accessors_ = nlohmann::json::array();
};

void append_chunk(std::vector<std::uint8_t>& out, std::uint32_t type,
                  const std::vector<std::uint8_t>& data, std::uint8_t pad) {
  const std::size_t padded = (data.size() + 3) / 4 * 4;
  append(out, static_cast<std::uint32_t>(padded));
  append(out, type);
  out.insert(out.end(), data.begin(), data.end());
  out.insert(out.end(), padded - data.size(), pad);
}

}  // namespace

std::vector<std::uint8_t> encode_glb(const TriangleMesh& mesh, const Eigen::Vector3d& origin) {
  if (mesh.triangles.empty()) throw Error("glTF", "", "a mesh without triangles cannot be written");
  const std::size_t n = mesh.vertices.size();
  GltfBuffers buffers;
  nlohmann::json attributes;
  attributes["POSITION"] = buffers.add(n, kFloat, "VEC3", kArrayBuffer, false, [&](auto& bin) {
    for (const Eigen::Vector3f& v : mesh.vertices)
      for (int k = 0; k < 3; ++k) append(bin, v[k]);
  });
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(0.0f), hi = lo;
  if (n > 0) lo = hi = mesh.vertices[0];
  for (const Eigen::Vector3f& v : mesh.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  buffers.accessor(attributes["POSITION"])["min"] = {lo.x(), lo.y(), lo.z()};
  buffers.accessor(attributes["POSITION"])["max"] = {hi.x(), hi.y(), hi.z()};
  if (mesh.normals.size() == n && n > 0) {
    attributes["NORMAL"] = buffers.add(n, kFloat, "VEC3", kArrayBuffer, false, [&](auto& bin) {
      for (const Eigen::Vector3f& normal : mesh.normals) {
        const float length = normal.norm();
        const Eigen::Vector3f unit = length > 1e-12f && std::isfinite(length)
                                         ? Eigen::Vector3f(normal / length)
                                         : Eigen::Vector3f::UnitZ();
        for (int k = 0; k < 3; ++k) append(bin, unit[k]);
      }
    });
  }
  if (mesh.colors.size() == n && n > 0) {
    attributes["COLOR_0"] =
        buffers.add(n, kUnsignedByte, "VEC4", kArrayBuffer, true, [&](auto& bin) {
          for (const Rgb8& c : mesh.colors)
            for (std::uint8_t channel : {c.r, c.g, c.b, std::uint8_t{255}}) bin.push_back(channel);
        });
  }
  const int indices = buffers.add(3 * mesh.triangles.size(), kUnsignedInt, "SCALAR",
                                  kElementArrayBuffer, false, [&](auto& bin) {
                                    for (const Triangle& t : mesh.triangles)
                                      for (std::uint32_t v : t) append(bin, v);
                                  });
  nlohmann::json doc = {
      {"asset", {{"version", "2.0"}, {"generator", "meshflow"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes",
       {origin.isZero()
            ? nlohmann::json{{"mesh", 0}}
            : nlohmann::json{{"mesh", 0}, {"translation", {origin.x(), origin.y(), origin.z()}}}}},
      {"meshes",
       {{{"primitives", {{{"attributes", attributes}, {"indices", indices}, {"mode", 4}}}}}}},
      {"buffers", {{{"byteLength", buffers.bin().size()}}}},
      {"bufferViews", buffers.views()},
      {"accessors", buffers.accessors()}};
  const std::string json = doc.dump();
  std::vector<std::uint8_t> out;
  append(out, glb::kMagic);
  append(out, std::uint32_t{2});
  append(out, std::uint32_t{0});  // total length, set below
  append_chunk(out, kJsonChunk, std::vector<std::uint8_t>(json.begin(), json.end()), ' ');
  append_chunk(out, kBinChunk, buffers.bin(), 0);
  const auto total = static_cast<std::uint32_t>(out.size());
  std::memcpy(out.data() + 8, &total, sizeof total);
  return out;
}

void write_glb(const std::string& path, const TriangleMesh& mesh, const Eigen::Vector3d& origin) {
  std::vector<std::uint8_t> bytes;
  try {
    bytes = encode_glb(mesh, origin);
  } catch (const Error& e) {
    throw Error(path, "", e.problem());
  }
  AtomicOutputFile file(path);
  file.stream().write(reinterpret_cast<const char*>(bytes.data()),
                      static_cast<std::streamsize>(bytes.size()));
  file.commit();
}

}  // namespace meshflow::io
