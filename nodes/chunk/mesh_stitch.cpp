#include "nodes/chunk/mesh_stitch.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "runtime/disjoint_sets.h"
#include "runtime/voxel_key.h"

namespace meshflow::chunk {

std::uint64_t lattice_edge_key(const Eigen::Vector3f& p, float voxel_size) {
  constexpr std::uint64_t kNone = std::numeric_limits<std::uint64_t>::max();
  const Eigen::Vector3d g = p.cast<double>() / static_cast<double>(voxel_size);
  int edge_axis = -1;
  Eigen::Vector3i lower;
  for (int a = 0; a < 3; ++a) {
    const double nearest = std::round(g[a]);
    const double off = std::abs(g[a] - nearest);
    if (!(std::abs(nearest) < kMaxCellIndex)) return kNone;
    if (off < 1e-4) {
      lower[a] = static_cast<int>(nearest);
    } else if (off > 5e-4 && edge_axis < 0) {
      edge_axis = a;
      lower[a] = static_cast<int>(std::floor(g[a]));
    } else {
      return kNone;
    }
  }
  if (edge_axis < 0) return kNone;
  return pack_key(lower) * 3 + static_cast<std::uint64_t>(edge_axis);
}

namespace {

constexpr std::uint64_t kNoKey = std::numeric_limits<std::uint64_t>::max();

// Bit a set when the vertex of lattice edge `key` lies on a chunk boundary plane across axis a
// (a coordinate of the lower corner, other than the edge's own axis, divisible by chunk_cells).
unsigned seam_axes(std::uint64_t key, int chunk_cells) {
  if (key == kNoKey) return 0;
  const auto axis = static_cast<int>(key % 3);
  const Eigen::Vector3i lower = unpack_key(key / 3);
  unsigned axes = 0;
  for (int a = 0; a < 3; ++a)
    if (a != axis && lower[a] % chunk_cells == 0) axes |= 1u << a;
  return axes;
}

// Whether lattice edge vertices `a` and `b` lie on one chunk boundary plane.
bool on_one_seam_plane(std::uint64_t a, std::uint64_t b, unsigned axes_a, unsigned axes_b) {
  const Eigen::Vector3i la = unpack_key(a / 3), lb = unpack_key(b / 3);
  for (int axis = 0; axis < 3; ++axis)
    if ((axes_a & axes_b & (1u << axis)) && la[axis] == lb[axis]) return true;
  return false;
}

}  // namespace

bool on_chunk_seam(std::uint64_t key, int chunk_cells) {
  return chunk_cells > 0 && seam_axes(key, chunk_cells) != 0;
}

std::vector<std::uint8_t> seam_vertices(const std::vector<Eigen::Vector3f>& vertices,
                                        float voxel_size, int chunk_cells,
                                        const std::vector<std::uint8_t>& apart) {
  std::vector<std::uint8_t> seam(vertices.size(), 0);
  const bool with_apart = apart.size() == vertices.size();
  tbb::parallel_for(std::size_t{0}, vertices.size(), [&](std::size_t v) {
    if (with_apart && apart[v] != 0) return;
    seam[v] = on_chunk_seam(lattice_edge_key(vertices[v], voxel_size), chunk_cells) ? 1 : 0;
  });
  return seam;
}

void MeshStitcher::relate_pieces(std::size_t first_vertex, std::size_t first_triangle) {
  const std::size_t vertices = joined_.vertices.size() - first_vertex;
  const auto local = [&](std::uint32_t v) { return static_cast<std::uint32_t>(v - first_vertex); };
  // The mesh's connected pieces (triangles sharing a vertex), numbered globally in the order of
  // their lowest vertex.
  DisjointSets sets(vertices);
  for (std::size_t t = first_triangle; t < joined_.triangles.size(); ++t) {
    const Triangle& tri = joined_.triangles[t];
    sets.unite(local(tri[0]), local(tri[1]));
    sets.unite(local(tri[0]), local(tri[2]));
  }
  const std::vector<std::uint32_t> root = sets.labels();
  std::vector<std::uint32_t> piece_of_root(vertices, UINT32_MAX);
  for (std::size_t v = 0; v < vertices; ++v) {
    std::uint32_t& piece = piece_of_root[root[v]];
    if (piece == UINT32_MAX) {
      piece = static_cast<std::uint32_t>(piece_triangles_.size());
      piece_triangles_.push_back(0);
    }
    vertex_piece_.push_back(piece);
  }
  for (std::size_t t = first_triangle; t < joined_.triangles.size(); ++t) {
    const std::uint32_t piece = vertex_piece_[joined_.triangles[t][0]];
    triangle_piece_.push_back(piece);
    ++piece_triangles_[piece];
  }
  if (chunk_cells_ <= 0) return;
  std::vector<unsigned> axes(vertices);
  for (std::size_t v = 0; v < vertices; ++v)
    axes[v] = seam_axes(keys_[first_vertex + v], chunk_cells_);
  for (std::size_t t = first_triangle; t < joined_.triangles.size(); ++t) {
    const Triangle& tri = joined_.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = tri[k], b = tri[(k + 1) % 3];
      if (!axes[local(a)] || !axes[local(b)]) continue;
      const std::uint64_t ka = keys_[a], kb = keys_[b];
      if (!on_one_seam_plane(ka, kb, axes[local(a)], axes[local(b)])) continue;
      const SeamSide side{vertex_piece_[a], static_cast<std::uint8_t>(ka < kb ? 1 : 0)};
      const auto [it, fresh] =
          seam_edges_.emplace(std::make_pair(std::min(ka, kb), std::max(ka, kb)), side);
      if (fresh || it->second.piece == side.piece) continue;
      const std::uint32_t lo = std::min(side.piece, it->second.piece);
      const std::uint32_t hi = std::max(side.piece, it->second.piece);
      Relation& r = relations_[static_cast<std::uint64_t>(lo) << 32 | hi];
      (it->second.direction != side.direction ? r.agree : r.disagree) += 1;
    }
  }
}

std::vector<std::uint8_t> MeshStitcher::pieces_to_turn() const {
  const std::size_t pieces = piece_triangles_.size();
  // Union-find keeping each piece's parity relative to its parent (1: turned against it).
  std::vector<std::uint32_t> parent(pieces);
  std::vector<std::uint8_t> parity(pieces, 0);
  for (std::size_t p = 0; p < pieces; ++p) parent[p] = static_cast<std::uint32_t>(p);
  const auto find = [&](std::uint32_t p) {
    std::uint8_t acc = 0;
    std::uint32_t r = p;
    while (parent[r] != r) {
      acc ^= parity[r];
      r = parent[r];
    }
    // Compress: every piece on the path points at the root with its total parity.
    std::uint8_t along = acc;
    while (parent[p] != p) {
      const std::uint32_t next = parent[p];
      const std::uint8_t own = parity[p];
      parent[p] = r;
      parity[p] = along;
      along ^= own;
      p = next;
    }
    return std::make_pair(r, acc);
  };
  // The strongest relations first (most shared seam edges), ties by piece pair: deterministic.
  std::vector<std::pair<std::uint64_t, Relation>> order(relations_.begin(), relations_.end());
  std::sort(order.begin(), order.end(), [](const auto& x, const auto& y) {
    const std::uint32_t wx = x.second.agree + x.second.disagree;
    const std::uint32_t wy = y.second.agree + y.second.disagree;
    return wx != wy ? wx > wy : x.first < y.first;
  });
  for (const auto& [pair, r] : order) {
    if (r.agree == r.disagree) continue;
    const auto [ra, pa] = find(static_cast<std::uint32_t>(pair >> 32));
    const auto [rb, pb] = find(static_cast<std::uint32_t>(pair & 0xffffffffu));
    if (ra == rb) continue;  // already decided by stronger relations
    const auto turned = static_cast<std::uint8_t>(r.disagree > r.agree ? 1 : 0);
    parent[std::max(ra, rb)] = std::min(ra, rb);
    parity[std::max(ra, rb)] = static_cast<std::uint8_t>(pa ^ pb ^ turned);
  }
  // Per group, turn whichever side holds fewer triangles.
  std::vector<std::uint64_t> weight[2] = {std::vector<std::uint64_t>(pieces, 0),
                                          std::vector<std::uint64_t>(pieces, 0)};
  std::vector<std::uint32_t> root(pieces);
  std::vector<std::uint8_t> relative(pieces);
  for (std::size_t p = 0; p < pieces; ++p) {
    const auto [r, par] = find(static_cast<std::uint32_t>(p));
    root[p] = r;
    relative[p] = par;
    weight[par][r] += piece_triangles_[p];
  }
  std::vector<std::uint8_t> turn(pieces);
  for (std::size_t p = 0; p < pieces; ++p) {
    const std::uint8_t flip_root = weight[1][root[p]] > weight[0][root[p]] ? 1 : 0;
    turn[p] = relative[p] ^ flip_root;
  }
  return turn;
}

void MeshStitcher::add(const TriangleMesh& mesh, const std::vector<std::uint8_t>& vertex_flags) {
  const auto base = static_cast<std::uint32_t>(joined_.vertices.size());
  normals_ = normals_ && mesh.normals.size() == mesh.vertices.size();
  colors_ = colors_ && mesh.colors.size() == mesh.vertices.size();
  joined_.vertices.insert(joined_.vertices.end(), mesh.vertices.begin(), mesh.vertices.end());
  if (normals_)
    joined_.normals.insert(joined_.normals.end(), mesh.normals.begin(), mesh.normals.end());
  if (colors_) joined_.colors.insert(joined_.colors.end(), mesh.colors.begin(), mesh.colors.end());
  flags_given_ = flags_given_ && vertex_flags.size() == mesh.vertices.size();
  if (flags_given_) flags_.insert(flags_.end(), vertex_flags.begin(), vertex_flags.end());
  const bool flagged = vertex_flags.size() == mesh.vertices.size();
  // With the chunk edge known, only seam vertices can have a copy in another chunk (a chunk's
  // own mesh has one vertex per lattice edge): the others are never merged, so only the seam's
  // keys are sorted.
  const std::size_t first = keys_.size();
  keys_.resize(first + mesh.vertices.size());
  tbb::parallel_for(std::size_t{0}, mesh.vertices.size(), [&](std::size_t v) {
    std::uint64_t key = flagged && (vertex_flags[v] & apart_flags_)
                            ? kNoKey
                            : lattice_edge_key(mesh.vertices[v], voxel_size_);
    if (chunk_cells_ > 0 && !on_chunk_seam(key, chunk_cells_)) key = kNoKey;
    keys_[first + v] = key;
  });
  const std::size_t first_triangle = joined_.triangles.size();
  for (const Triangle& t : mesh.triangles)
    joined_.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  relate_pieces(base, first_triangle);
}

TriangleMesh MeshStitcher::stitch(std::size_t* merged, std::vector<std::uint8_t>* vertex_flags,
                                  std::size_t* turned) {
  const std::size_t n = joined_.vertices.size();
  // Orientation first: turn the pieces the seam relations say are wound against the majority.
  const std::vector<std::uint8_t> turn = pieces_to_turn();
  std::size_t turned_triangles = 0;
  for (std::size_t t = 0; t < joined_.triangles.size(); ++t) {
    if (!turn[triangle_piece_[t]]) continue;
    std::swap(joined_.triangles[t][1], joined_.triangles[t][2]);
    ++turned_triangles;
  }
  if (normals_ && joined_.normals.size() == n)
    for (std::size_t v = 0; v < n; ++v)
      if (turn[vertex_piece_[v]]) joined_.normals[v] *= -1.0f;
  if (turned) *turned = turned_triangles;
  // Order the vertices with a key by (key, index): the first copy of each key is the
  // representative; a vertex without a key is its own.
  std::vector<std::uint32_t> order;
  for (std::size_t i = 0; i < n; ++i)
    if (keys_[i] != kNoKey) order.push_back(static_cast<std::uint32_t>(i));
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return keys_[a] != keys_[b] ? keys_[a] < keys_[b] : a < b;
  });
  std::vector<std::uint32_t> representative(n);
  for (std::size_t v = 0; v < n; ++v) representative[v] = static_cast<std::uint32_t>(v);
  std::size_t welded = 0;
  for (std::size_t i = 1; i < order.size(); ++i) {
    const std::uint32_t v = order[i];
    if (keys_[order[i - 1]] != keys_[v]) continue;
    representative[v] = representative[order[i - 1]];
    ++welded;
  }
  if (merged) *merged = welded;
  // The per-chunk bookkeeping is no longer needed: free it before the mesh is compacted.
  keys_ = {};
  triangle_piece_ = {};
  vertex_piece_ = {};
  piece_triangles_ = {};
  seam_edges_ = {};
  relations_ = {};
  // Keep representatives that a triangle uses, in their original order, compacted in place
  // (a kept vertex only moves down): the whole mesh is held once, not twice.
  std::vector<std::uint32_t> new_index(n, std::numeric_limits<std::uint32_t>::max());
  for (Triangle& t : joined_.triangles)
    for (std::uint32_t& v : t) {
      v = representative[v];
      new_index[v] = 0;
    }
  representative = {};
  const bool with_normals = normals_ && joined_.normals.size() == n;
  const bool with_colors = colors_ && joined_.colors.size() == n;
  const bool with_flags = flags_given_ && flags_.size() == n;
  std::uint32_t next = 0;
  for (std::size_t v = 0; v < n; ++v) {
    if (new_index[v] != 0) continue;
    new_index[v] = next;
    joined_.vertices[next] = joined_.vertices[v];
    if (with_normals) joined_.normals[next] = joined_.normals[v];
    if (with_colors) joined_.colors[next] = joined_.colors[v];
    if (with_flags) flags_[next] = flags_[v];
    ++next;
  }
  joined_.vertices.resize(next);
  joined_.vertices.shrink_to_fit();
  if (with_normals) {
    joined_.normals.resize(next);
    joined_.normals.shrink_to_fit();
  } else {
    joined_.normals = {};
  }
  if (with_colors) {
    joined_.colors.resize(next);
    joined_.colors.shrink_to_fit();
  } else {
    joined_.colors = {};
  }
  flags_.resize(with_flags ? next : 0);
  if (vertex_flags) *vertex_flags = std::move(flags_);
  flags_ = {};
  for (Triangle& t : joined_.triangles)
    for (std::uint32_t& v : t) v = new_index[v];
  TriangleMesh out = std::move(joined_);
  joined_ = TriangleMesh{};
  return out;
}

}  // namespace meshflow::chunk
