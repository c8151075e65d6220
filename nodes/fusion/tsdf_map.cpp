#include "nodes/fusion/tsdf_map.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <new>
#include <string>
#include <type_traits>

#include "runtime/error.h"
#include "runtime/radix_sort.h"

namespace meshflow {

// Larger voxels are a unit error; they would also put far vertices beyond float's range.
constexpr float kMaxVoxelSize = 1000.0f;  // metres

TsdfMap::TsdfMap(const TsdfConfig& config) : config_(config) {
  if (!(config.voxel_size > 0.0f && config.voxel_size <= kMaxVoxelSize)) {
    throw Error("tsdf", "voxel_size", "must be a positive number of metres, at most 1000");
  }
  if (!(config.truncation_voxels > 0.0f) || !std::isfinite(config.truncation_voxels)) {
    throw Error("tsdf", "truncation_voxels", "must be a positive number of voxels");
  }
  if (!(config.max_weight > 0.0f) || !std::isfinite(config.max_weight))
    throw Error("tsdf", "max_weight", "must be a positive finite number");
}

const TsdfBlock* TsdfMap::find(const Eigen::Vector3i& block_coords) const {
  if (!tsdf_block_in_range(block_coords)) return nullptr;
  const auto it = index_.find(pack_key(block_coords));
  return it == index_.end() ? nullptr : blocks_[it->second];
}

std::vector<std::uint32_t> TsdfMap::blocks_in_key_order() const {
  std::vector<std::uint64_t> keyed(blocks_.size());
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    // Block keys use 57 bits; the index is recovered through the map after sorting.
    keyed[i] = pack_key(blocks_[i]->coords);
  }
  radix_sort(keyed);
  std::vector<std::uint32_t> order(keyed.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) order[i] = index_.at(keyed[i]);
  return order;
}

std::uint32_t TsdfMap::allocate(const std::vector<Eigen::Vector3i>& coords) {
  const auto first = static_cast<std::uint32_t>(blocks_.size());
  // One slab for the batch, left uninitialised here (new[] of bytes is aligned for any
  // fundamental type); the blocks are constructed (voxels zeroed, 6 KiB each) in parallel.
  // TsdfBlock needs no destructor.
  static_assert(std::is_trivially_destructible_v<TsdfBlock>);
  slabs_.emplace_back(new unsigned char[coords.size() * sizeof(TsdfBlock)]);
  unsigned char* const slab = slabs_.back().get();
  blocks_.resize(blocks_.size() + coords.size());
  tbb::parallel_for(std::size_t{0}, coords.size(), [&](std::size_t i) {
    auto* block = new (slab + i * sizeof(TsdfBlock)) TsdfBlock();
    block->coords = coords[i];
    blocks_[first + i] = block;
  });
  for (std::size_t i = 0; i < coords.size(); ++i)
    index_.emplace(pack_key(coords[i]), first + static_cast<std::uint32_t>(i));
  return first;
}

void TsdfMap::insert_block(const Eigen::Vector3i& coords,
                           const std::array<TsdfVoxel, kTsdfBlockVoxels>& voxels) {
  if (!tsdf_block_in_range(coords)) {
    throw Error("tsdf", "block coordinates",
                "outside +-" + std::to_string(kMaxTsdfBlockIndex) + " blocks (the volume's range)");
  }
  if (index_.count(pack_key(coords)) != 0) {
    throw Error("tsdf",
                "block (" + std::to_string(coords.x()) + ", " + std::to_string(coords.y()) + ", " +
                    std::to_string(coords.z()) + ")",
                "appears twice");
  }
  TsdfBlock& block = *blocks_[allocate({coords})];
  block.voxels = voxels;
  block.modified = ++generation_;
}

void TsdfMap::find_or_allocate(const std::vector<VoxelKey>& keys, std::size_t max_new_blocks,
                               std::size_t max_memory_bytes, std::size_t& allocated,
                               std::vector<std::uint32_t>& blocks) {
  // Existing blocks are looked up in parallel (the index is only read); kNewBlock marks the rest.
  constexpr std::uint32_t kNewBlock = ~std::uint32_t{0};
  blocks.resize(keys.size());
  tbb::parallel_for(std::size_t{0}, keys.size(), [&](std::size_t i) {
    const auto it = index_.find(keys[i]);
    blocks[i] = it != index_.end() ? it->second : kNewBlock;
  });
  const auto new_blocks =
      static_cast<std::size_t>(std::count(blocks.begin(), blocks.end(), kNewBlock));
  if (max_new_blocks > 0 && new_blocks > max_new_blocks) {
    throw Error("tsdf map", "new blocks",
                "this frame would add " + std::to_string(new_blocks) + " blocks, more than the " +
                    std::to_string(max_new_blocks) +
                    " allowed per frame (a pose that jumps, or depth in the wrong unit?); the map "
                    "keeps its " +
                    std::to_string(blocks_.size()) + " blocks");
  }
  if (max_memory_bytes > 0) {
    const std::size_t after = memory_bytes() + new_blocks * kBytesPerBlock;
    if (after > max_memory_bytes) {
      const auto mib = [](std::size_t bytes) { return std::to_string(bytes >> 20) + " MiB"; };
      throw Error("tsdf map", "memory",
                  "this frame's " + std::to_string(new_blocks) +
                      " new blocks would grow the map to " + mib(after) + ", past the limit of " +
                      mib(max_memory_bytes) + " (--max-memory); the map keeps its " +
                      std::to_string(blocks_.size()) + " blocks");
    }
  }
  // The new blocks in key order: deterministic block numbering.
  std::vector<Eigen::Vector3i> fresh;
  fresh.reserve(new_blocks);
  for (std::size_t i = 0; i < keys.size(); ++i)
    if (blocks[i] == kNewBlock) fresh.push_back(unpack_key(keys[i]));
  if (fresh.empty()) return;
  std::uint32_t next = allocate(fresh);
  for (std::uint32_t& b : blocks)
    if (b == kNewBlock) b = next++;
  allocated += fresh.size();
}

}  // namespace meshflow
