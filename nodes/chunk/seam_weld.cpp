#include "nodes/chunk/seam_weld.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <map>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "nodes/chunk/mesh_stitch.h"
#include "runtime/disjoint_sets.h"
#include "runtime/voxel_key.h"

namespace meshflow::chunk {
namespace {

constexpr std::uint64_t kWeldNoKey = std::numeric_limits<std::uint64_t>::max();
constexpr std::uint32_t kWeldNone = std::numeric_limits<std::uint32_t>::max();

// Whether lattice edge vertices `a` and `b` (seam_plane_axes() `axes_a`, `axes_b`) lie on one
// chunk boundary plane.
bool weld_on_one_plane(std::uint64_t a, std::uint64_t b, unsigned axes_a, unsigned axes_b) {
  const Eigen::Vector3i la = unpack_key(a / 3), lb = unpack_key(b / 3);
  for (int axis = 0; axis < 3; ++axis)
    if ((axes_a & axes_b & (1u << axis)) && la[axis] == lb[axis]) return true;
  return false;
}

struct WeldRelation {
  std::uint32_t agree = 0, disagree = 0;  // shared seam edges run opposite / the same way
};

// Which pieces to turn over (one byte per piece) from the relations between pieces (by pair
// lower << 32 | higher): a union-find keeping each piece's parity, the strongest relations
// first; per group, whichever side holds fewer triangles turns.
std::vector<std::uint8_t> weld_pieces_to_turn(
    const std::vector<std::uint64_t>& piece_triangles,
    const std::unordered_map<std::uint64_t, WeldRelation>& relations) {
  const std::size_t pieces = piece_triangles.size();
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
  std::vector<std::pair<std::uint64_t, WeldRelation>> order(relations.begin(), relations.end());
  std::sort(order.begin(), order.end(), [](const auto& x, const auto& y) {
    const std::uint32_t wx = x.second.agree + x.second.disagree;
    const std::uint32_t wy = y.second.agree + y.second.disagree;
    return wx != wy ? wx > wy : x.first < y.first;
  });
  for (const auto& entry : order) {
    const WeldRelation& r = entry.second;
    if (r.agree == r.disagree) continue;
    const auto [ra, pa] = find(static_cast<std::uint32_t>(entry.first >> 32));
    const auto [rb, pb] = find(static_cast<std::uint32_t>(entry.first & 0xffffffffu));
    if (ra == rb) continue;  // already decided by stronger relations
    const auto turned = static_cast<std::uint8_t>(r.disagree > r.agree ? 1 : 0);
    parent[std::max(ra, rb)] = std::min(ra, rb);
    parity[std::max(ra, rb)] = static_cast<std::uint8_t>(pa ^ pb ^ turned);
  }
  std::vector<std::uint64_t> weight[2] = {std::vector<std::uint64_t>(pieces, 0),
                                          std::vector<std::uint64_t>(pieces, 0)};
  std::vector<std::uint32_t> root(pieces);
  std::vector<std::uint8_t> relative(pieces);
  for (std::size_t p = 0; p < pieces; ++p) {
    const auto [r, par] = find(static_cast<std::uint32_t>(p));
    root[p] = r;
    relative[p] = par;
    weight[par][r] += piece_triangles[p];
  }
  std::vector<std::uint8_t> turn(pieces);
  for (std::size_t p = 0; p < pieces; ++p) {
    const std::uint8_t flip_root = weight[1][root[p]] > weight[0][root[p]] ? 1 : 0;
    turn[p] = relative[p] ^ flip_root;
  }
  return turn;
}

// The relations between global pieces through seam edges shared by chunks (each later
// occurrence of an edge related to its first, in chunk then triangle order).
std::unordered_map<std::uint64_t, WeldRelation> weld_relations(
    const std::vector<const ChunkSeams*>& chunks, const std::vector<std::uint32_t>& piece_offset) {
  struct Side {
    std::uint32_t piece;
    std::uint8_t direction;
  };
  struct PairHash {
    std::size_t operator()(const std::pair<std::uint64_t, std::uint64_t>& k) const {
      return std::hash<std::uint64_t>()(k.first * 0x9e3779b97f4a7c15ULL ^ k.second);
    }
  };
  std::unordered_map<std::pair<std::uint64_t, std::uint64_t>, Side, PairHash> first;
  std::unordered_map<std::uint64_t, WeldRelation> relations;
  for (std::size_t c = 0; c < chunks.size(); ++c)
    for (const SeamEdge& e : chunks[c]->edges) {
      const Side side{piece_offset[c] + e.piece, e.direction};
      const auto [it, fresh] = first.emplace(std::make_pair(e.lower, e.higher), side);
      if (fresh || it->second.piece == side.piece) continue;
      const std::uint32_t lo = std::min(side.piece, it->second.piece);
      const std::uint32_t hi = std::max(side.piece, it->second.piece);
      WeldRelation& r = relations[static_cast<std::uint64_t>(lo) << 32 | hi];
      (it->second.direction != side.direction ? r.agree : r.disagree) += 1;
    }
  return relations;
}

}  // namespace

ChunkSeams summarize_seams(const TriangleMesh& mesh, const std::vector<std::uint8_t>& vertex_flags,
                           float voxel_size, int chunk_cells, std::uint8_t apart_flags) {
  ChunkSeams s;
  const std::size_t n = mesh.vertices.size();
  s.vertices = static_cast<std::uint32_t>(n);
  s.normals = mesh.normals.size() == n;
  s.colors = mesh.colors.size() == n;
  s.flags = vertex_flags.size() == n;
  std::vector<std::uint64_t> keys(n);
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t v) {
    std::uint64_t key = s.flags && (vertex_flags[v] & apart_flags)
                            ? kWeldNoKey
                            : lattice_edge_key(mesh.vertices[v], voxel_size);
    if (chunk_cells > 0 && !on_chunk_seam(key, chunk_cells)) key = kWeldNoKey;
    keys[v] = key;
  });
  // Pieces: triangles sharing a vertex, numbered in the order of their lowest vertex.
  DisjointSets sets(n);
  std::vector<std::uint8_t> used(n, 0);
  for (const Triangle& t : mesh.triangles) {
    sets.unite(t[0], t[1]);
    sets.unite(t[0], t[2]);
    used[t[0]] = used[t[1]] = used[t[2]] = 1;
  }
  const std::vector<std::uint32_t> root = sets.labels();
  std::vector<std::uint32_t> piece_of_root(n, kWeldNone);
  s.vertex_piece.resize(n);
  for (std::size_t v = 0; v < n; ++v) {
    std::uint32_t& piece = piece_of_root[root[v]];
    if (piece == kWeldNone) {
      piece = static_cast<std::uint32_t>(s.piece_triangles.size());
      s.piece_triangles.push_back(0);
    }
    s.vertex_piece[v] = piece;
  }
  for (const Triangle& t : mesh.triangles) ++s.piece_triangles[s.vertex_piece[t[0]]];
  std::uint32_t apart_used = 0;
  for (std::size_t v = 0; v < n; ++v) {
    if (keys[v] == kWeldNoKey) {
      apart_used += used[v];
      continue;
    }
    s.seam_index.push_back(static_cast<std::uint32_t>(v));
    s.seam_key.push_back(keys[v]);
    s.seam_used.push_back(used[v]);
    s.used_apart_before.push_back(apart_used);
  }
  s.used_apart = apart_used;
  if (chunk_cells <= 0) return s;
  std::vector<unsigned> axes(n, 0);
  for (const std::uint32_t v : s.seam_index) axes[v] = seam_plane_axes(keys[v], chunk_cells);
  for (const Triangle& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (!axes[a] || !axes[b]) continue;
      const std::uint64_t ka = keys[a], kb = keys[b];
      if (!weld_on_one_plane(ka, kb, axes[a], axes[b])) continue;
      s.edges.push_back({std::min(ka, kb), std::max(ka, kb), s.vertex_piece[a],
                         static_cast<std::uint8_t>(ka < kb ? 1 : 0)});
    }
  return s;
}

WeldPlan plan_weld(const std::vector<const ChunkSeams*>& chunks) {
  WeldPlan plan;
  const std::size_t count = chunks.size();
  plan.normals = plan.colors = plan.flags = true;
  plan.piece_offset.resize(count);
  std::vector<std::uint64_t> piece_triangles;
  for (std::size_t c = 0; c < count; ++c) {
    const ChunkSeams& s = *chunks[c];
    plan.normals = plan.normals && s.normals;
    plan.colors = plan.colors && s.colors;
    plan.flags = plan.flags && s.flags;
    plan.piece_offset[c] = static_cast<std::uint32_t>(piece_triangles.size());
    piece_triangles.insert(piece_triangles.end(), s.piece_triangles.begin(),
                           s.piece_triangles.end());
  }
  // Orientation: the pieces' relations through shared seam edges.
  plan.turn = weld_pieces_to_turn(piece_triangles, weld_relations(chunks, plan.piece_offset));
  for (std::size_t p = 0; p < piece_triangles.size(); ++p)
    if (plan.turn[p]) plan.turned += piece_triangles[p];
  // The weld: every copy of a key goes to its first (chunk, vertex); the group is kept when a
  // triangle uses any copy.
  std::vector<std::tuple<std::uint64_t, std::uint32_t, std::uint32_t>> order;  // key, chunk, i
  for (std::size_t c = 0; c < count; ++c)
    for (std::size_t i = 0; i < chunks[c]->seam_key.size(); ++i)
      order.emplace_back(chunks[c]->seam_key[i], static_cast<std::uint32_t>(c),
                         static_cast<std::uint32_t>(i));
  std::sort(order.begin(), order.end());
  std::vector<std::vector<std::uint8_t>> kept(count);
  plan.seam_target.resize(count);
  for (std::size_t c = 0; c < count; ++c) {
    kept[c].assign(chunks[c]->seam_key.size(), 0);
    plan.seam_target[c].assign(chunks[c]->seam_key.size(), kWeldNone);
  }
  for (std::size_t g = 0; g < order.size();) {
    std::size_t end = g + 1;
    bool used = chunks[std::get<1>(order[g])]->seam_used[std::get<2>(order[g])] != 0;
    for (; end < order.size() && std::get<0>(order[end]) == std::get<0>(order[g]); ++end)
      used = used || chunks[std::get<1>(order[end])]->seam_used[std::get<2>(order[end])] != 0;
    plan.merged += end - g - 1;
    if (used) kept[std::get<1>(order[g])][std::get<2>(order[g])] = 1;
    g = end;
  }
  // Output numbering: chunk by chunk, kept vertices in vertex order.
  plan.vertex_offset.resize(count);
  std::uint64_t next = 0;
  for (std::size_t c = 0; c < count; ++c) {
    plan.vertex_offset[c] = static_cast<std::uint32_t>(next);
    std::uint32_t kept_seam = 0;
    for (std::size_t i = 0; i < kept[c].size(); ++i)
      if (kept[c][i]) {
        plan.seam_target[c][i] =
            static_cast<std::uint32_t>(next + chunks[c]->used_apart_before[i] + kept_seam);
        ++kept_seam;
      }
    next += chunks[c]->used_apart + kept_seam;
  }
  plan.vertices = next;
  // Every copy points at its group's kept vertex.
  for (std::size_t g = 0; g < order.size();) {
    const std::uint32_t target = plan.seam_target[std::get<1>(order[g])][std::get<2>(order[g])];
    std::size_t end = g + 1;
    for (; end < order.size() && std::get<0>(order[end]) == std::get<0>(order[g]); ++end)
      plan.seam_target[std::get<1>(order[end])][std::get<2>(order[end])] = target;
    g = end;
  }
  for (const ChunkSeams* s : chunks)
    for (const std::uint64_t t : s->piece_triangles) plan.triangles += t;
  return plan;
}

TriangleMesh weld_chunk(const TriangleMesh& mesh, const std::vector<std::uint8_t>& vertex_flags,
                        const ChunkSeams& seams, const WeldPlan& plan, std::size_t index,
                        std::vector<std::uint8_t>* flags) {
  const std::size_t n = mesh.vertices.size();
  const std::uint32_t pieces = plan.piece_offset[index];
  const auto turned = [&](std::uint32_t v) { return plan.turn[pieces + seams.vertex_piece[v]]; };
  const std::vector<std::uint32_t>& target = plan.seam_target[index];
  std::vector<std::uint8_t> used(n, 0);
  for (const Triangle& t : mesh.triangles) used[t[0]] = used[t[1]] = used[t[2]] = 1;
  // Output index per vertex: a seam copy's kept vertex, or the next output vertex when used.
  std::vector<std::uint32_t> out_index(n, kWeldNone);
  TriangleMesh part;
  const bool keep_flags = plan.flags && flags != nullptr;
  if (keep_flags) flags->clear();
  std::uint32_t next = plan.vertex_offset[index];
  std::size_t s = 0;
  for (std::size_t v = 0; v < n; ++v) {
    const bool seam = s < seams.seam_index.size() && seams.seam_index[s] == v;
    if (seam) {
      out_index[v] = target[s++];
      if (out_index[v] != next) continue;  // another chunk's (or unused): not kept here
    } else if (!used[v]) {
      continue;
    } else {
      out_index[v] = next;
    }
    ++next;
    part.vertices.push_back(mesh.vertices[v]);
    if (plan.normals)
      part.normals.push_back(turned(static_cast<std::uint32_t>(v)) ? -mesh.normals[v]
                                                                   : mesh.normals[v]);
    if (plan.colors) part.colors.push_back(mesh.colors[v]);
    if (keep_flags) flags->push_back(vertex_flags[v]);
  }
  part.triangles.reserve(mesh.triangles.size());
  for (const Triangle& t : mesh.triangles) {
    Triangle o{out_index[t[0]], out_index[t[1]], out_index[t[2]]};
    if (turned(t[0])) std::swap(o[1], o[2]);
    part.triangles.push_back(o);
  }
  return part;
}

void append_welded(TriangleMesh& joined, const TriangleMesh& part) {
  joined.vertices.insert(joined.vertices.end(), part.vertices.begin(), part.vertices.end());
  joined.normals.insert(joined.normals.end(), part.normals.begin(), part.normals.end());
  joined.colors.insert(joined.colors.end(), part.colors.begin(), part.colors.end());
  joined.triangles.insert(joined.triangles.end(), part.triangles.begin(), part.triangles.end());
}

}  // namespace meshflow::chunk
