#include "nodes/compress/compressed_mesh.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "nodes/compress/attribute_coder.h"
#include "nodes/compress/progressive_mesh.h"
#include "runtime/error.h"

namespace meshflow::compress {
namespace {

constexpr char kMagic[8] = {'M', 'F', 'M', 'E', 'S', 'H', '\r', '\n'};
constexpr std::uint32_t kVersion = 11;

}  // namespace

Quantizer choose_quantizer(const TriangleMesh& mesh, const CompressConfig& config) {
  require_corners_in_range(mesh.triangles, mesh.vertices.size(), "mesh");
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(0.0), hi = lo;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Eigen::Vector3d p = mesh.vertices[i].cast<double>();
    if (!p.allFinite())
      throw Error("mesh", "vertex " + std::to_string(i), "position is not finite");
    lo = i == 0 ? p : lo.cwiseMin(p);
    hi = i == 0 ? p : hi.cwiseMax(p);
  }
  const double extent = std::max((hi - lo).maxCoeff(), 1e-9);
  Quantizer q;
  q.origin = lo;
  if (config.position_bits > 0) {
    if (config.position_bits > 30)
      throw Error("compression", "position bits",
                  "must be 1 .. 30, not " + std::to_string(config.position_bits));
    q.bits = config.position_bits;
    q.step = extent / static_cast<double>((std::uint64_t{1} << q.bits) - 1);
    return q;
  }
  double step = config.step;
  if (!(step > 0.0)) {
    const double edge = median_edge_length(mesh);
    step = edge > 0.0 ? edge / 64.0 : extent / 65535.0;
  }
  // The fewest bits that cover the box at this step (at most 30: coarser steps beyond).
  q.bits = 1;
  while (q.bits < 30 && extent / step > static_cast<double>((std::uint64_t{1} << q.bits) - 1))
    ++q.bits;
  q.step = std::max(step, extent / static_cast<double>((std::uint64_t{1} << q.bits) - 1));
  return q;
}

namespace detail {

AttributeFlags attribute_flags(const TriangleMesh& mesh, const CompressConfig& config) {
  if (config.normal_bits != 0 &&
      (config.normal_bits < kMinNormalBits || config.normal_bits > kMaxNormalBits))
    throw Error("compression", "normal bits",
                "must be 0 (recomputed by the decoder) or " + std::to_string(kMinNormalBits) +
                    " .. " + std::to_string(kMaxNormalBits) + ", not " +
                    std::to_string(config.normal_bits));
  const bool normals =
      config.normals && !mesh.normals.empty() && mesh.normals.size() == mesh.vertices.size();
  AttributeFlags flags;
  flags.normals = normals && config.normal_bits > 0;
  flags.recomputed_normals = normals && config.normal_bits == 0;
  flags.colors =
      config.colors && !mesh.colors.empty() && mesh.colors.size() == mesh.vertices.size();
  flags.normal_bits = flags.normals ? config.normal_bits : kDefaultNormalBits;
  if (config.normal_error != 0.0) {
    if (!(config.normal_error >= 0.001 && config.normal_error <= 30.0))
      throw Error("compression", "normal error",
                  "must be 0.001 .. 30 degrees, not " + std::to_string(config.normal_error));
    // The progressive splits' octahedral grid: the fewest bits within the angle.
    flags.normal_bits = kMinNormalBits;
    while (flags.normal_bits < kMaxNormalBits &&
           normal_error_degrees(flags.normal_bits) > config.normal_error)
      ++flags.normal_bits;
  }
  flags.normal_step = normal_step_for(
      config.normal_error != 0.0 ? config.normal_error : normal_error_degrees(flags.normal_bits));
  return flags;
}

std::uint64_t fnv1a64_continue(std::uint64_t hash, const unsigned char* data, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    hash ^= data[i];
    hash *= 1099511628211ull;
  }
  return hash;
}

std::uint64_t prefix_checksum(const unsigned char* bytes, std::size_t end) {
  const unsigned char zero[8] = {};
  std::uint64_t h = fnv1a64_continue(14695981039346656037ull, bytes, kPrefixChecksumOffset);
  h = fnv1a64_continue(h, zero, 8);
  return fnv1a64_continue(h, bytes + kPrefixChecksumOffset + 8, end - kPrefixChecksumOffset - 8);
}

void recompute_normals(TriangleMesh& mesh, const std::vector<std::array<std::int32_t, 3>>& grid) {
  mesh.normals = recomputed_normals({grid, mesh.triangles});
}

void write_header(io::ByteWriter& out, CompressionKind kind, AttributeFlags flags,
                  std::uint64_t vertices, std::uint64_t triangles, const Quantizer& quantizer,
                  const Eigen::Vector3d& offset) {
  out.bytes(kMagic, sizeof kMagic);
  out.u32(kVersion);
  out.u32(static_cast<std::uint32_t>(kind));
  out.u32((flags.normals ? 1u : 0u) | (flags.colors ? 2u : 0u) |
          (flags.recomputed_normals ? 4u : 0u));
  out.u64(vertices);
  out.u64(triangles);
  for (int a = 0; a < 3; ++a) out.f64(quantizer.origin[a] + offset[a]);
  out.f64(quantizer.step);
  out.u32(quantizer.bits);
  out.u64(0);  // the prefix checksum (progressive_mesh.cpp sets it)
}

io::ByteReader body_reader(const std::vector<unsigned char>& bytes, const std::string& source) {
  return io::ByteReader(source, bytes.data(), bytes.size() >= 8 ? bytes.size() - 8 : bytes.size());
}

void seal(io::ByteWriter& out) { out.u64(io::fnv1a64(out.out.data(), out.out.size())); }

CompressedMeshInfo read_header(io::ByteReader& in, const std::vector<unsigned char>& bytes,
                               bool check_file_checksum) {
  if (bytes.size() < sizeof kMagic || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    in.fail("magic", "not a meshflow compressed mesh (expected \"MFMESH\" at byte 0)");
  in.bytes(sizeof kMagic, "magic");
  CompressedMeshInfo info;
  info.version = in.u32("version");
  if (info.version != kVersion)
    in.fail("version",
            "is " + std::to_string(info.version) + "; this build reads version " +
                std::to_string(kVersion) +
                (info.version < kVersion ? " only (compress the mesh again with this build)"
                                         : " (the file is from a newer meshflow)"));
  const std::uint32_t kind = in.u32("kind");
  if (kind != 1 && kind != 2) in.fail("kind", std::to_string(kind) + " is not 1 or 2");
  info.kind = static_cast<CompressionKind>(kind);
  const std::uint32_t flags = in.u32("flags");
  if (flags > 7) in.fail("flags", "unknown bits set");
  if ((flags & 5u) == 5u) in.fail("flags", "normals both stored and recomputed");
  info.normals = (flags & 1u) != 0;
  info.colors = (flags & 2u) != 0;
  info.recomputed_normals = (flags & 4u) != 0;
  info.vertices = in.u64("vertex count");
  info.triangles = in.u64("triangle count");
  for (int a = 0; a < 3; ++a) info.quantizer.origin[a] = in.f64("quantisation origin");
  info.quantizer.step = in.f64("quantisation step");
  info.quantizer.bits = in.u32("quantisation bits");
  if (!info.quantizer.origin.allFinite()) in.fail("quantisation origin", "is not finite");
  if (!(info.quantizer.step > 0.0) || !std::isfinite(info.quantizer.step))
    in.fail("quantisation step", "must be finite and > 0");
  if (info.quantizer.bits < 1 || info.quantizer.bits > 30)
    in.fail("quantisation bits", "must be 1 .. 30");
  info.prefix_checksum = in.u64("prefix checksum");
  if (!check_file_checksum) return info;
  if (bytes.size() < in.position() + 8) in.fail("checksum", "file ends early (truncated)");
  std::uint64_t stored = 0;
  for (std::size_t i = 0; i < 8; ++i)
    stored |= static_cast<std::uint64_t>(bytes[bytes.size() - 8 + i]) << (8 * i);
  if (stored != io::fnv1a64(bytes.data(), bytes.size() - 8))
    in.fail("checksum", "does not match the contents (corrupt or truncated file)");
  return info;
}

}  // namespace detail

std::vector<unsigned char> compress_mesh(const TriangleMesh& mesh, const CompressConfig& config,
                                         CompressReport* report) {
  const Quantizer quantizer = choose_quantizer(mesh, config);  // checks the corners first
  const AttributeFlags flags = detail::attribute_flags(mesh, config);
  io::ByteWriter out;
  detail::write_header(out, CompressionKind::kEdgebreaker, flags, mesh.vertices.size(),
                       mesh.triangles.size(), quantizer, config.origin_offset);
  BodyOrder order;
  const BodyStats stats = encode_body(mesh, quantizer, flags, out, &order);
  detail::seal(out);
  if (report != nullptr) {
    *report = CompressReport{};
    report->kind = CompressionKind::kEdgebreaker;
    report->total_bytes = out.out.size();
    report->body = stats;
    report->quantizer = quantizer;
    report->vertex_order = std::move(order.vertex);
    report->triangle_order = std::move(order.triangle);
  }
  return std::move(out.out);
}

CompressedMeshInfo compressed_mesh_info(const std::vector<unsigned char>& bytes,
                                        const std::string& source) {
  io::ByteReader in(source, bytes);
  return detail::read_header(in, bytes);
}

TriangleMesh decompress_mesh(const std::vector<unsigned char>& bytes, const std::string& source) {
  io::ByteReader in = detail::body_reader(bytes, source);
  const CompressedMeshInfo info = detail::read_header(in, bytes);
  TriangleMesh mesh;
  if (info.kind == CompressionKind::kProgressive) {
    mesh = decode_progressive(in, info, source, ProgressiveLevel{});
  } else {
    BodyCodes codes;
    mesh = decode_body(in, info.quantizer, {info.normals, info.colors}, source, &codes);
    if (info.recomputed_normals) detail::recompute_normals(mesh, codes.positions);
  }
  if (in.remaining() != 0)
    in.fail("end of data", std::to_string(in.remaining()) + " bytes left before the checksum");
  if (mesh.vertices.size() != info.vertices || mesh.triangles.size() != info.triangles)
    throw Error(source, "header counts",
                std::to_string(info.vertices) + " vertices and " + std::to_string(info.triangles) +
                    " triangles stated, " + std::to_string(mesh.vertices.size()) + " and " +
                    std::to_string(mesh.triangles.size()) + " decoded");
  return mesh;
}

void reseal_compressed_mesh(std::vector<unsigned char>& bytes) {
  io::reseal_fnv1a64(bytes.data(), bytes.size());
}

}  // namespace meshflow::compress
