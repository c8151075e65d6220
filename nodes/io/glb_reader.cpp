#include "nodes/io/glb_reader.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <type_traits>

#include "nodes/io/byte_buffer.h"
#include "nodes/io/glb_format.h"
#include "runtime/error.h"

namespace meshflow::io {
namespace {

using glb::kBinChunk;
using glb::kFloat;
using glb::kJsonChunk;
using glb::kUnsignedByte;
using glb::kUnsignedInt;
using glb::kUnsignedShort;

std::size_t component_size(int type) {
  return type == kUnsignedByte ? 1 : type == kUnsignedShort ? 2 : 4;
}

std::size_t type_width(const std::string& type) {
  return type == "SCALAR" ? 1 : type == "VEC3" ? 3 : type == "VEC4" ? 4 : 0;
}

// One accessor resolved against the binary chunk: element i, component k at
// data + i * stride + k * component bytes, every byte of it inside the chunk.
struct AccessorView {
  const unsigned char* data = nullptr;
  std::size_t count = 0, stride = 0, width = 0;
  int component = 0;
  bool normalized = false;

  double value(std::size_t i, std::size_t k) const {
    const unsigned char* p = data + i * stride + k * component_size(component);
    switch (component) {
      case kUnsignedByte:
        return normalized ? *p / 255.0 : *p;
      case kUnsignedShort: {
        std::uint16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? v / 65535.0 : v;
      }
      case kUnsignedInt: {
        std::uint32_t v;
        std::memcpy(&v, p, 4);
        return v;
      }
      default: {
        float v;
        std::memcpy(&v, p, 4);
        return v;
      }
    }
  }
};

class GlbDocument {
 public:
  GlbDocument(const std::vector<unsigned char>& bytes, const std::string& source)
      : source_(source) {
    ByteReader in(source, bytes);
    if (in.u32("magic") != glb::kMagic) in.fail("magic", "not a binary glTF file (no 'glTF')");
    if (const std::uint32_t version = in.u32("version"); version != 2)
      throw Error(source, "version", "glTF " + std::to_string(version) + " (reads version 2)");
    if (in.u32("length") > bytes.size())
      throw Error(source, "length", "the header's length is past the end of the file");
    const std::uint32_t json_length = in.u32("JSON chunk length");
    if (in.u32("JSON chunk type") != kJsonChunk) in.fail("first chunk", "is not the JSON chunk");
    const unsigned char* json = in.bytes(json_length, "JSON chunk");
    try {
      doc_ = nlohmann::json::parse(json, json + json_length);
    } catch (const nlohmann::json::exception& e) {
      throw Error(source, "JSON chunk", std::string("not valid JSON: ") + e.what());
    }
    if (in.remaining() >= 8) {
      const std::uint32_t bin_length = in.u32("BIN chunk length");
      if (in.u32("BIN chunk type") == kBinChunk) {
        bin_ = in.bytes(bin_length, "BIN chunk");
        bin_size_ = bin_length;
      }
    }
  }

  const nlohmann::json& json() const { return doc_; }

  // A member of `object` as T, or an error naming `field`.
  template <typename T>
  T get(const nlohmann::json& object, const char* key, const std::string& field) const {
    if (!object.is_object() || !object.contains(key))
      throw Error(source_, field, std::string("has no '") + key + "'");
    return as<T>(object.at(key), field + "." + key);
  }

  // A member of `object` as T, `fallback` when absent, or an error naming `field`.
  template <typename T>
  T optional(const nlohmann::json& object, const char* key, T fallback,
             const std::string& field) const {
    if (!object.is_object() || !object.contains(key)) return fallback;
    return as<T>(object.at(key), field + "." + key);
  }

  // `value` as T; integers must be JSON integers in T's range (nlohmann would cast a float such
  // as 1e30 or -1.5 to an integer type, which is undefined behaviour).
  template <typename T>
  T as(const nlohmann::json& value, const std::string& field) const {
    if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
      bool fits = std::is_unsigned_v<T> ? value.is_number_unsigned() : value.is_number_integer();
      if constexpr (sizeof(T) < sizeof(std::int64_t)) {  // (64-bit types hold any such number)
        if (fits && std::is_unsigned_v<T>)
          fits = value.get<std::uint64_t>() <= std::uint64_t{std::numeric_limits<T>::max()};
        else if (fits)
          fits = value.get<std::int64_t>() >= std::int64_t{std::numeric_limits<T>::min()} &&
                 value.get<std::int64_t>() <= std::int64_t{std::numeric_limits<T>::max()};
      }
      if (!fits) throw Error(source_, field, "expected an integer in range");
    }
    try {
      return value.get<T>();
    } catch (const nlohmann::json::exception&) {
      throw Error(source_, field, "has the wrong type");
    }
  }

  // Element `index` of the top-level array `name`.
  const nlohmann::json& element(const char* name, std::size_t index) const {
    const std::string field = std::string(name) + "[" + std::to_string(index) + "]";
    if (!doc_.contains(name) || !doc_[name].is_array() || index >= doc_[name].size())
      throw Error(source_, field, "does not exist");
    return doc_[name][index];
  }

  AccessorView accessor(std::size_t index) const {
    const std::string field = "accessors[" + std::to_string(index) + "]";
    const nlohmann::json& a = element("accessors", index);
    if (a.contains("sparse")) throw Error(source_, field, "sparse accessors are not read");
    AccessorView v;
    v.count = get<std::size_t>(a, "count", field);
    v.component = get<int>(a, "componentType", field);
    v.width = type_width(get<std::string>(a, "type", field));
    v.normalized = optional(a, "normalized", false, field);
    if (v.width == 0 || (v.component != kUnsignedByte && v.component != kUnsignedShort &&
                         v.component != kUnsignedInt && v.component != kFloat))
      throw Error(source_, field,
                  "type or componentType not read (SCALAR/VEC3/VEC4 of "
                  "unsigned byte, short, int or float)");
    const std::size_t view_index = get<std::size_t>(a, "bufferView", field);
    const nlohmann::json& view = element("bufferViews", view_index);
    const std::string view_field = "bufferViews[" + std::to_string(view_index) + "]";
    if (get<std::size_t>(view, "buffer", view_field) != 0 || bin_ == nullptr)
      throw Error(source_, view_field, "refers to a buffer outside the file's BIN chunk");
    const std::size_t element_bytes = v.width * component_size(v.component);
    v.stride = optional(view, "byteStride", std::size_t{0}, view_field);
    if (v.stride == 0) v.stride = element_bytes;
    const std::size_t view_offset = optional(view, "byteOffset", std::size_t{0}, view_field);
    const std::size_t view_length = get<std::size_t>(view, "byteLength", view_field);
    const std::size_t offset = optional(a, "byteOffset", std::size_t{0}, field);
    // The last element ends at offset + (count - 1) * stride + element bytes, inside the view,
    // and the view inside the chunk (checked without overflow).
    if (view_offset > bin_size_ || view_length > bin_size_ - view_offset ||
        (v.count > 0 && (offset > view_length || v.stride < element_bytes ||
                         (v.count - 1) > (view_length - offset) / v.stride ||
                         (v.count - 1) * v.stride + element_bytes > view_length - offset)))
      throw Error(source_, field, "reaches past its buffer view or the BIN chunk");
    // Primitives may share an accessor, each decoding it again: bounded, so that a small file
    // cannot make the reader allocate without limit (count * element_bytes <= the chunk here).
    decoded_bytes_ += v.count * element_bytes;
    if (decoded_bytes_ > kMaxDecodedPerByte * bin_size_ + kDecodedSlack)
      throw Error(source_, field,
                  "the accessors decoded so far hold more than 16 times the BIN chunk's bytes "
                  "(accessors shared by that many primitives are not read)");
    v.data = bin_ + view_offset + offset;
    return v;
  }

  const std::string& source() const { return source_; }

 private:
  std::string source_;
  nlohmann::json doc_;
  const unsigned char* bin_ = nullptr;
  std::size_t bin_size_ = 0;
  static constexpr std::size_t kMaxDecodedPerByte = 16, kDecodedSlack = std::size_t{1} << 16;
  mutable std::size_t decoded_bytes_ = 0;  ///< element bytes of every accessor() so far
};

void check(const AccessorView& v, std::size_t width, bool float_only, const std::string& source,
           const std::string& field) {
  if (v.width != width || (float_only && v.component != kFloat))
    throw Error(
        source, field,
        "expected " + std::string(float_only ? "float " : "") + "VEC" + std::to_string(width));
}

}  // namespace

namespace {

TriangleMesh decode(const std::vector<unsigned char>& bytes, const std::string& source) {
  const GlbDocument glb(bytes, source);
  TriangleMesh mesh;
  bool normals = true, colors = true;
  std::vector<Eigen::Vector3f> normal_values;
  std::vector<Rgb8> color_values;
  const nlohmann::json meshes = glb.json().value("meshes", nlohmann::json::array());
  if (!meshes.is_array()) throw Error(source, "meshes", "is not an array");
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const std::string mesh_field = "meshes[" + std::to_string(m) + "]";
    const auto primitives = glb.get<nlohmann::json>(meshes[m], "primitives", mesh_field);
    if (!primitives.is_array()) throw Error(source, mesh_field + ".primitives", "is not an array");
    for (std::size_t p = 0; p < primitives.size(); ++p) {
      const std::string field = mesh_field + ".primitives[" + std::to_string(p) + "]";
      const nlohmann::json& primitive = primitives[p];
      if (glb.optional(primitive, "mode", 4, field) != 4)
        throw Error(source, field + ".mode", "not triangles (mode 4)");
      const auto attributes = glb.get<nlohmann::json>(primitive, "attributes", field);
      const AccessorView position =
          glb.accessor(glb.get<std::size_t>(attributes, "POSITION", field + ".attributes"));
      check(position, 3, true, source, field + ".POSITION");
      const std::size_t base = mesh.vertices.size();
      for (std::size_t i = 0; i < position.count; ++i) {
        const Eigen::Vector3f v(static_cast<float>(position.value(i, 0)),
                                static_cast<float>(position.value(i, 1)),
                                static_cast<float>(position.value(i, 2)));
        if (!v.allFinite())
          throw Error(source, field + ".POSITION[" + std::to_string(i) + "]", "is not finite");
        mesh.vertices.push_back(v);
      }
      normals = normals && attributes.contains("NORMAL");
      if (normals) {
        const AccessorView n = glb.accessor(glb.get<std::size_t>(attributes, "NORMAL", field));
        check(n, 3, true, source, field + ".NORMAL");
        if (n.count != position.count)
          throw Error(source, field + ".NORMAL", "count differs from POSITION's");
        for (std::size_t i = 0; i < n.count; ++i)
          normal_values.emplace_back(static_cast<float>(n.value(i, 0)),
                                     static_cast<float>(n.value(i, 1)),
                                     static_cast<float>(n.value(i, 2)));
      }
      colors = colors && attributes.contains("COLOR_0");
      if (colors) {
        const AccessorView c = glb.accessor(glb.get<std::size_t>(attributes, "COLOR_0", field));
        if (c.width != 3 && c.width != 4)
          throw Error(source, field + ".COLOR_0", "expected VEC3 or VEC4");
        if (c.count != position.count)
          throw Error(source, field + ".COLOR_0", "count differs from POSITION's");
        const auto channel = [](double x) {
          return static_cast<std::uint8_t>(std::lround(std::clamp(x, 0.0, 1.0) * 255.0));
        };
        for (std::size_t i = 0; i < c.count; ++i)
          color_values.push_back(
              {channel(c.value(i, 0)), channel(c.value(i, 1)), channel(c.value(i, 2))});
      }
      std::vector<std::uint32_t> corners;
      if (primitive.contains("indices")) {
        const AccessorView idx = glb.accessor(glb.get<std::size_t>(primitive, "indices", field));
        if (idx.width != 1 || idx.component == kFloat)
          throw Error(source, field + ".indices", "expected unsigned SCALAR indices");
        corners.resize(idx.count);
        for (std::size_t i = 0; i < idx.count; ++i)
          corners[i] = static_cast<std::uint32_t>(idx.value(i, 0));
      } else {
        corners.resize(position.count);
        for (std::size_t i = 0; i < corners.size(); ++i) corners[i] = static_cast<std::uint32_t>(i);
      }
      if (corners.size() % 3 != 0)
        throw Error(source, field + ".indices", "count is not a multiple of 3");
      for (std::size_t i = 0; i < corners.size(); i += 3) {
        for (std::size_t k = 0; k < 3; ++k)
          if (corners[i + k] >= position.count)
            throw Error(source, field + ".indices[" + std::to_string(i + k) + "]",
                        "vertex " + std::to_string(corners[i + k]) + " out of range (" +
                            std::to_string(position.count) + " vertices)");
        mesh.triangles.push_back({static_cast<std::uint32_t>(base + corners[i]),
                                  static_cast<std::uint32_t>(base + corners[i + 1]),
                                  static_cast<std::uint32_t>(base + corners[i + 2])});
      }
    }
  }
  if (normals && normal_values.size() == mesh.vertices.size() && !mesh.vertices.empty())
    mesh.normals = std::move(normal_values);
  if (colors && color_values.size() == mesh.vertices.size() && !mesh.vertices.empty())
    mesh.colors = std::move(color_values);
  return mesh;
}

}  // namespace

TriangleMesh decode_glb(const std::vector<unsigned char>& bytes, const std::string& source) {
  try {
    return decode(bytes, source);
  } catch (const nlohmann::json::exception& e) {  // a member of an unexpected JSON type
    throw Error(source, "JSON chunk", e.what());
  }
}

TriangleMesh read_glb_mesh(const std::string& path) {
  return decode_glb(read_file_bytes(path), path);
}

}  // namespace meshflow::io
