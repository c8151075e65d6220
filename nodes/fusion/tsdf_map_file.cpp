#include "nodes/fusion/tsdf_map_file.h"

#include <cmath>
#include <cstring>
#include <vector>

#include "nodes/io/byte_buffer.h"
#include "runtime/error.h"

namespace meshflow {
namespace {

constexpr char kMagic[8] = {'M', 'F', 'T', 'S', 'D', 'F', '\r', '\n'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 4 + 4 + 4 + 4 + 8;
constexpr std::size_t kVoxelBytes = 4 + 4 + 4;
constexpr std::size_t kBlockBytes = 12 + kTsdfBlockVoxels * kVoxelBytes;

}  // namespace

void write_tsdf_map(const std::string& path, const TsdfMap& volume) {
  const TsdfConfig& c = volume.config();
  io::ByteWriter w;
  w.out.reserve(kHeaderBytes + volume.block_count() * kBlockBytes + 8);
  w.bytes(kMagic, sizeof kMagic);
  w.u32(kVersion);
  w.u32(kTsdfBlockSide);
  w.f32(c.voxel_size);
  w.f32(c.truncation_voxels);
  w.f32(c.max_weight);
  w.u32((c.weighting == TsdfWeighting::kInverseDepth ? 1u : 0u) | (c.fuse_color ? 2u : 0u));
  w.u64(volume.block_count());
  for (std::uint32_t i : volume.blocks_in_key_order()) {
    const TsdfBlock& b = volume.block(i);
    for (int a = 0; a < 3; ++a) w.i32(b.coords[a]);
    for (const TsdfVoxel& v : b.voxels) {
      w.f32(v.distance);
      w.f32(v.weight);
      const unsigned char rgb0[4] = {v.color.r, v.color.g, v.color.b, 0};
      w.bytes(rgb0, 4);
    }
  }
  w.u64(io::fnv1a64(w.out.data(), w.out.size()));
  io::write_file_bytes(path, w.out);
}

void reseal_tsdf_map(std::uint8_t* bytes, std::size_t size) { io::reseal_fnv1a64(bytes, size); }

TsdfMap read_tsdf_map(const std::string& path) {
  const std::vector<unsigned char> data = io::read_file_bytes(path);
  io::ByteReader r(path, data);
  if (data.size() < sizeof kMagic || std::memcmp(data.data(), kMagic, sizeof kMagic) != 0) {
    throw Error(path, "magic", "not a meshflow TSDF map (expected \"MFTSDF\" at byte 0)");
  }
  for (std::size_t i = 0; i < sizeof kMagic; ++i) r.u8("magic");
  const std::uint32_t version = r.u32("version");
  if (version != kVersion) {
    r.fail("version", "is " + std::to_string(version) + "; this build reads version " +
                          std::to_string(kVersion));
  }
  if (r.u32("block side") != kTsdfBlockSide) r.fail("block side", "must be 8");
  TsdfConfig config;
  config.voxel_size = r.f32("voxel size");
  config.truncation_voxels = r.f32("truncation");
  config.max_weight = r.f32("max weight");
  const std::uint32_t flags = r.u32("flags");
  if (flags > 3u) r.fail("flags", "unknown bits set");
  config.weighting = (flags & 1u) ? TsdfWeighting::kInverseDepth : TsdfWeighting::kConstant;
  config.fuse_color = (flags & 2u) != 0;
  const std::uint64_t blocks = r.u64("block count");
  const std::uint64_t expected = kHeaderBytes + 8;
  if (blocks > (data.size() - std::min<std::size_t>(data.size(), expected)) / kBlockBytes ||
      expected + blocks * kBlockBytes != data.size()) {
    r.fail("block count", std::to_string(blocks) + " blocks need " +
                              std::to_string(expected + blocks * kBlockBytes) +
                              " bytes, the file has " + std::to_string(data.size()) +
                              " (truncated or corrupt)");
  }
  const std::uint64_t stored_hash = [&] {
    std::uint64_t h = 0;
    for (int i = 0; i < 8; ++i)
      h |= static_cast<std::uint64_t>(data[data.size() - 8 + static_cast<std::size_t>(i)])
           << (8 * i);
    return h;
  }();
  if (stored_hash != io::fnv1a64(data.data(), data.size() - 8)) {
    throw Error(path, "checksum", "does not match the contents (corrupt file)");
  }
  TsdfMap volume = [&] {
    try {
      return TsdfMap(config);
    } catch (const Error& e) {
      throw Error(path, "header field " + e.location(), e.problem());
    }
  }();
  std::array<TsdfVoxel, kTsdfBlockVoxels> voxels;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    Eigen::Vector3i coords;
    for (int a = 0; a < 3; ++a) coords[a] = r.i32("block coordinates");
    for (TsdfVoxel& v : voxels) {
      v.distance = r.f32("voxel distance");
      v.weight = r.f32("voxel weight");
      v.color = Rgb8{r.u8("voxel colour"), r.u8("voxel colour"), r.u8("voxel colour")};
      r.u8("voxel padding");
      if (!std::isfinite(v.distance)) r.fail("voxel distance", "is not finite");
      if (!std::isfinite(v.weight) || v.weight < 0.0f)
        r.fail("voxel weight", "must be finite and >= 0");
    }
    try {
      volume.insert_block(coords, voxels);
    } catch (const Error& e) {
      r.fail(e.location(), e.problem());
    }
  }
  return volume;
}

}  // namespace meshflow
