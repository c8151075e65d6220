#include "nodes/fusion/tsdf_mesher.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "nodes/cube/cube_table.h"
#include "runtime/error.h"
#include "runtime/parallel.h"
#include "runtime/radix_sort.h"

namespace meshflow {
namespace {

constexpr int kSide = kTsdfBlockSide;
constexpr int kLattice = kSide + 1;  // a block's cells reach one voxel into its + neighbours

// The 9 x 9 x 9 voxels a block's cells read: its own and the face voxels of the neighbours at
// offsets {0, 1}^3 (nullptr where a neighbour block does not exist).
class BlockLattice {
 public:
  BlockLattice(const TsdfMap& volume, const TsdfBlock& block) : origin_(block.coords * kSide) {
    for (int o = 0; o < 8; ++o) {
      const Eigen::Vector3i offset(o & 1, (o >> 1) & 1, (o >> 2) & 1);
      neighbours_[static_cast<std::size_t>(o)] =
          o == 0 ? &block : volume.find(block.coords + offset);
    }
  }
  // Voxel at lattice position (x, y, z), each in 0..8; nullptr if its block is missing.
  const TsdfVoxel* at(int x, int y, int z) const {
    const int o = (x >> 3) | ((y >> 3) << 1) | ((z >> 3) << 2);
    const TsdfBlock* b = neighbours_[static_cast<std::size_t>(o)];
    if (b == nullptr) return nullptr;
    return &b->voxels[static_cast<std::size_t>((x & 7) + kSide * ((y & 7) + kSide * (z & 7)))];
  }
  const Eigen::Vector3i& origin() const { return origin_; }

 private:
  Eigen::Vector3i origin_;  // global voxel index of lattice position (0, 0, 0)
  std::array<const TsdfBlock*, 8> neighbours_{};
};

TsdfMesher::BlockMesh mesh_block(const TsdfMap& volume, const TsdfBlock& block, float min_weight) {
  const auto& cases = cube_cases();
  const float voxel = volume.config().voxel_size;
  const float truncation = volume.config().truncation();
  const BlockLattice lattice(volume, block);
  TsdfMesher::BlockMesh out;
  for (const TsdfVoxel& v : block.voxels) {
    if (v.weight > min_weight) ++out.counts.voxels_observed;
    if (v.weight > 0.0f && !(v.weight > min_weight)) ++out.counts.voxels_below_weight;
  }
  std::vector<std::int32_t> edge_vertex(kLattice * kLattice * kLattice * 3, -1);
  for (int z = 0; z < kSide; ++z)
    for (int y = 0; y < kSide; ++y)
      for (int x = 0; x < kSide; ++x) {
        std::array<const TsdfVoxel*, 8> corner{};
        int pattern = 0, observed = 0;
        const TsdfVoxel* inside = nullptr;  // an observed corner behind the surface
        for (int c = 0; c < 8; ++c) {
          const TsdfVoxel* v = lattice.at(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1));
          if (v == nullptr || !(v->weight > min_weight)) continue;
          corner[static_cast<std::size_t>(c)] = v;
          observed |= 1 << c;
          if (v->distance < 0.0f) {
            pattern |= 1 << c;
            inside = v;
          }
        }
        // A cell is meshed when its observed corners lie on both sides of the surface. Corners
        // no frame reached, when none of their edge neighbours in the cell is in front of the
        // surface, are behind it (a frame's band reaches farther in front of a surface than
        // behind it) and count as inside, at the truncation; any other unobserved corner (next
        // to free space: the edge of a view) leaves the cell out.
        if (pattern == 0 || pattern == observed) continue;
        const int in_front = observed & ~pattern;
        bool fillable = true;
        for (int c = 0; c < 8 && fillable; ++c) {
          const int neighbours = (1 << (c ^ 1)) | (1 << (c ^ 2)) | (1 << (c ^ 4));
          fillable = ((observed >> c) & 1) != 0 || (in_front & neighbours) == 0;
        }
        if (!fillable) {
          ++out.counts.cells_left_out;
          continue;
        }
        ++out.counts.cells_meshed;
        TsdfVoxel behind;
        if (observed != 255) {
          ++out.counts.cells_completed;
          behind.distance = -truncation;
          behind.color = inside->color;
          for (int c = 0; c < 8; ++c) {
            if (((observed >> c) & 1) == 0) {
              corner[static_cast<std::size_t>(c)] = &behind;
              pattern |= 1 << c;
            }
          }
        }
        std::array<std::uint32_t, 12> local{};
        for (int e = 0; e < 12; ++e) {
          const auto& ce = kCubeEdges[static_cast<std::size_t>(e)];
          if (((pattern >> ce[0]) & 1) == ((pattern >> ce[1]) & 1)) continue;
          const int axis = kCubeEdgeAxis[static_cast<std::size_t>(e)];
          const Eigen::Vector3i lower(x + (ce[0] & 1), y + ((ce[0] >> 1) & 1),
                                      z + ((ce[0] >> 2) & 1));
          const std::size_t slot = static_cast<std::size_t>(
              ((lower.x() + kLattice * (lower.y() + kLattice * lower.z())) * 3) + axis);
          if (edge_vertex[slot] < 0) {
            const TsdfVoxel& a = *corner[static_cast<std::size_t>(ce[0])];
            const TsdfVoxel& b = *corner[static_cast<std::size_t>(ce[1])];
            const float t = std::clamp(a.distance / (a.distance - b.distance), 1e-3f, 1.0f - 1e-3f);
            const Eigen::Vector3i global = lattice.origin() + lower;
            Eigen::Vector3f p = global.cast<float>() * voxel;
            p[axis] += t * voxel;
            auto mix = [t](std::uint8_t u, std::uint8_t v) {
              return static_cast<std::uint8_t>(static_cast<float>(u) * (1.0f - t) +
                                               static_cast<float>(v) * t + 0.5f);
            };
            edge_vertex[slot] = static_cast<std::int32_t>(out.vertices.size());
            out.vertices.push_back(p);
            out.colors.push_back(Rgb8{mix(a.color.r, b.color.r), mix(a.color.g, b.color.g),
                                      mix(a.color.b, b.color.b)});
            out.edge_keys.push_back((pack_key(global) << 2) | static_cast<std::uint64_t>(axis));
          }
          local[static_cast<std::size_t>(e)] = static_cast<std::uint32_t>(edge_vertex[slot]);
        }
        for (const auto& tri : cases[static_cast<std::size_t>(pattern)].triangles) {
          out.triangles.push_back(Triangle{local[tri[0]], local[tri[1]], local[tri[2]]});
        }
      }
  return out;
}

// The blocks' meshes joined in the given order, vertices with equal edge keys welded into one
// (numbered in key order). Parallel over blocks; O(vertex copies log).
TriangleMesh weld_block_meshes(const std::vector<const TsdfMesher::BlockMesh*>& blocks) {
  std::vector<std::size_t> vertex_offsets(blocks.size()), triangle_offsets(blocks.size());
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    vertex_offsets[i] = blocks[i]->vertices.size();
    triangle_offsets[i] = blocks[i]->triangles.size();
  }
  const std::size_t copies = exclusive_scan_in_place(vertex_offsets);
  const std::size_t triangles = exclusive_scan_in_place(triangle_offsets);
  std::vector<std::uint64_t> keys(copies);
  tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t i) {
    std::copy(blocks[i]->edge_keys.begin(), blocks[i]->edge_keys.end(),
              keys.begin() + static_cast<std::ptrdiff_t>(vertex_offsets[i]));
  });
  std::vector<std::uint64_t> unique_keys = keys;
  radix_sort_unique(unique_keys);
  std::vector<std::uint32_t> ids(copies);
  tbb::parallel_for(std::size_t{0}, copies, [&](std::size_t c) {
    ids[c] = static_cast<std::uint32_t>(
        std::lower_bound(unique_keys.begin(), unique_keys.end(), keys[c]) - unique_keys.begin());
  });
  TriangleMesh mesh;
  mesh.vertices.resize(unique_keys.size());
  mesh.colors.resize(unique_keys.size());
  mesh.triangles.resize(triangles);
  // Copies of a welded vertex are identical (same two voxels, same formula); the owner of each
  // vertex id is its first copy, so every id is written by one task.
  std::vector<std::uint8_t> first(copies, 0);
  std::vector<std::uint8_t> written(unique_keys.size(), 0);
  for (std::size_t c = 0; c < copies; ++c) {
    first[c] = written[ids[c]] == 0 ? 1 : 0;
    written[ids[c]] = 1;
  }
  tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t i) {
    const TsdfMesher::BlockMesh& b = *blocks[i];
    const std::size_t base = vertex_offsets[i];
    for (std::size_t v = 0; v < b.vertices.size(); ++v) {
      if (!first[base + v]) continue;
      mesh.vertices[ids[base + v]] = b.vertices[v];
      mesh.colors[ids[base + v]] = b.colors[v];
    }
    for (std::size_t t = 0; t < b.triangles.size(); ++t) {
      const Triangle& tri = b.triangles[t];
      mesh.triangles[triangle_offsets[i] + t] =
          Triangle{ids[base + tri[0]], ids[base + tri[1]], ids[base + tri[2]]};
    }
  });
  return mesh;
}

}  // namespace

TsdfCellCounts& TsdfCellCounts::operator+=(const TsdfCellCounts& o) {
  voxels_observed += o.voxels_observed;
  voxels_below_weight += o.voxels_below_weight;
  cells_meshed += o.cells_meshed;
  cells_completed += o.cells_completed;
  cells_left_out += o.cells_left_out;
  return *this;
}

TsdfMesher::TsdfMesher(float min_weight) : min_weight_(min_weight) {
  if (!(min_weight >= 0.0f) || !std::isfinite(min_weight))
    throw Error("tsdf mesher", "min_weight", "must be a non-negative number");
}

TriangleMesh TsdfMesher::extract(const TsdfMap& volume, TsdfExtractStats* stats) {
  if (volume_ != &volume) {  // another volume: nothing cached applies
    cache_.clear();
    meshed_generation_ = 0;
    volume_ = &volume;
  }
  const std::vector<std::uint32_t> order = volume.blocks_in_key_order();
  const std::vector<std::uint8_t> dirty = dirty_blocks(volume, order);
  TsdfExtractStats s;
  const std::vector<const BlockMesh*> meshes = remesh(volume, order, dirty, s);
  meshed_generation_ = volume.generation();
  for (const BlockMesh* m : meshes) s.cells += m->counts;
  TriangleMesh mesh = weld_block_meshes(meshes);
  compute_vertex_normals(mesh);
  if (stats != nullptr) *stats = s;
  return mesh;
}

std::vector<std::uint8_t> TsdfMesher::dirty_blocks(const TsdfMap& volume,
                                                   const std::vector<std::uint32_t>& order) const {
  // Changed since the last call, or reading a changed neighbour's voxels.
  std::vector<std::uint8_t> dirty(order.size(), 0);
  tbb::parallel_for(std::size_t{0}, order.size(), [&](std::size_t i) {
    const TsdfBlock& b = volume.block(order[i]);
    bool changed = cache_.count(pack_key(b.coords)) == 0;
    for (int o = 0; o < 8 && !changed; ++o) {
      const TsdfBlock* n = volume.find(b.coords + Eigen::Vector3i(o & 1, (o >> 1) & 1, o >> 2));
      changed = n != nullptr && n->modified > meshed_generation_;
    }
    dirty[i] = changed ? 1 : 0;
  });
  return dirty;
}

std::vector<VoxelKey> TsdfMesher::update(const TsdfMap& volume, TsdfExtractStats* stats) {
  if (volume_ != &volume) {
    cache_.clear();
    meshed_generation_ = 0;
    volume_ = &volume;
  }
  const std::vector<std::uint32_t> order = volume.blocks_in_key_order();
  const std::vector<std::uint8_t> dirty = dirty_blocks(volume, order);
  TsdfExtractStats s;
  std::vector<std::uint8_t> changed;
  const std::vector<const BlockMesh*> meshes = remesh(volume, order, dirty, s, &changed);
  meshed_generation_ = volume.generation();
  for (const BlockMesh* m : meshes) s.cells += m->counts;
  if (stats != nullptr) *stats = s;
  std::vector<VoxelKey> keys;
  for (std::size_t i = 0; i < order.size(); ++i)
    if (changed[i]) keys.push_back(pack_key(volume.block(order[i]).coords));
  return keys;
}

const TsdfMesher::BlockMesh* TsdfMesher::block_mesh(VoxelKey key) const {
  const auto found = cache_.find(key);
  return found == cache_.end() ? nullptr : &found->second;
}

std::vector<const TsdfMesher::BlockMesh*> TsdfMesher::remesh(
    const TsdfMap& volume, const std::vector<std::uint32_t>& order,
    const std::vector<std::uint8_t>& dirty, TsdfExtractStats& stats,
    std::vector<std::uint8_t>* changed) {
  // Cache entries are made first, serially, so the map never rehashes while tasks write into it.
  std::vector<BlockMesh*> slots(order.size(), nullptr);
  for (std::size_t i = 0; i < order.size(); ++i) {
    slots[i] = &cache_[pack_key(volume.block(order[i]).coords)];
    (dirty[i] ? stats.blocks_meshed : stats.blocks_cached) += 1;
  }
  if (changed != nullptr) changed->assign(order.size(), 0);
  tbb::parallel_for(std::size_t{0}, order.size(), [&](std::size_t i) {
    if (!dirty[i]) return;
    BlockMesh fresh = mesh_block(volume, volume.block(order[i]), min_weight_);
    if (changed != nullptr)
      (*changed)[i] = fresh.vertices != slots[i]->vertices || fresh.colors != slots[i]->colors ||
                              fresh.triangles != slots[i]->triangles
                          ? 1
                          : 0;
    *slots[i] = std::move(fresh);
  });
  return {slots.begin(), slots.end()};
}

}  // namespace meshflow
