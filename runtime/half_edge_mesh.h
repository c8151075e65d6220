#pragma once
// An index-based half-edge mesh for mesh optimisation: every triangle is three half-edges, each
// knowing the vertex it points to, the next half-edge of its face and its twin on the
// neighbouring face (none on a border). Built from a TriangleMesh, with non-manifold input
// reported instead of corrupting the structure; edited in place (edge flips); converted back
// with compaction.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "runtime/triangle_mesh.h"

namespace meshflow {

class HalfEdgeMesh {
 public:
  static constexpr std::uint32_t kNone = UINT32_MAX;

  /// Builds the structure. Throws meshflow::Error naming the first offending edge or vertex for
  /// input that is not an oriented 2-manifold with border: an edge used by more than two
  /// triangles or twice in the same direction, a vertex whose triangles form more than one fan
  /// (a "bow tie"), a triangle repeating a vertex or an index out of range. O(T log T).
  explicit HalfEdgeMesh(const TriangleMesh& mesh);

  /// Vertices (isolated ones included).
  std::size_t vertex_count() const { return positions_.size(); }
  /// Half-edge slots: 3 per face slot.
  std::size_t half_edge_count() const { return to_.size(); }
  std::size_t face_count() const { return to_.size() / 3; }  ///< slots, removed ones included
  /// Whether face slot f holds a face (not removed by an edit).
  bool face_alive(std::uint32_t f) const { return alive_[f] != 0; }
  /// Faces not removed.
  std::size_t live_face_count() const { return live_faces_; }

  // Navigation (h: half-edge index, 3 per face: face f owns 3f, 3f + 1, 3f + 2).
  /// The vertex h points to.
  std::uint32_t to(std::uint32_t h) const { return to_[h]; }
  /// The vertex h leaves.
  std::uint32_t from(std::uint32_t h) const { return to_[prev(h)]; }
  /// The next half-edge of h's face (counter-clockwise).
  static std::uint32_t next(std::uint32_t h) { return h - h % 3 + (h + 1) % 3; }
  /// The previous half-edge of h's face.
  static std::uint32_t prev(std::uint32_t h) { return h - h % 3 + (h + 2) % 3; }
  /// The face h belongs to.
  static std::uint32_t face(std::uint32_t h) { return h / 3; }
  /// The opposite half-edge, or kNone on the border.
  std::uint32_t twin(std::uint32_t h) const { return twin_[h]; }
  /// Whether h has no twin (its edge is on the border).
  bool is_border(std::uint32_t h) const { return twin_[h] == kNone; }
  /// Vertex v's position (metres).
  const Eigen::Vector3f& position(std::uint32_t v) const { return positions_[v]; }
  /// Moves vertex v (metres). Safe from many threads for distinct vertices.
  void set_position(std::uint32_t v, const Eigen::Vector3f& p) { positions_[v] = p; }

  /// A half-edge leaving v (the one whose ring walk covers all of v's faces: on a border vertex,
  /// the border half-edge leaving it), or kNone for an isolated vertex.
  std::uint32_t outgoing(std::uint32_t v) const { return out_[v]; }
  /// Whether v lies on the border (has a border half-edge leaving it). O(1).
  bool is_border_vertex(std::uint32_t v) const;

  /// The half-edges leaving v, counter-clockwise (seen from the normal side) from outgoing(v).
  /// O(valence).
  std::vector<std::uint32_t> ring(std::uint32_t v) const;

  /// Every border loop as its half-edges in order (each followed by the border half-edge
  /// leaving its target), loops ordered by their smallest half-edge. O(H).
  std::vector<std::vector<std::uint32_t>> border_loops() const;

  /// Flips the interior edge of h = a -> b: its faces (a, b, c) and (b, a, d) become (a, d, c)
  /// and (d, b, c), replacing edge a-b by c-d; face and half-edge indices are reused. Refused
  /// (returns false, nothing changes) on a border edge, when c-d already exists, when a or b is
  /// interior with only three faces (the flip would fold two faces onto each other), or when a
  /// new face would have no area or face against the old pair (the quad is not convex at c-d).
  /// O(valence).
  bool flip(std::uint32_t h);

  /// Collapses h = a -> b: a is removed, its faces join b (which keeps its position), and the
  /// one or two faces along a-b disappear. Refused (false, nothing changes) when the result
  /// would not be a manifold (a and b share a neighbour other than the edge's opposite
  /// vertices, or both lie on the border while a-b is interior, or the mesh would shrink below
  /// a tetrahedron), or when a face moving with a would lose its area or turn against its old
  /// normal. O(valence).
  bool collapse(std::uint32_t h);

  /// Splits the edge of h = a -> b at `p` (metres): a new vertex m, and each face along the
  /// edge becomes two. Returns m. O(1) plus O(valence) to refresh outgoing half-edges.
  std::uint32_t split(std::uint32_t h, const Eigen::Vector3f& p);

  /// Checks every invariant (twins are mutual, opposite and alive; outgoing half-edges leave
  /// their vertex; every vertex's faces form one fan; no face repeats a vertex); returns an
  /// empty string or the first violation. O(V + H).
  std::string check() const;

  /// The triangles back, referenced vertices only, in vertex order. O(V + T).
  TriangleMesh to_triangle_mesh() const;

 private:
  std::vector<Eigen::Vector3f> positions_;
  std::vector<std::uint32_t> to_, twin_, out_;
  std::vector<std::uint8_t> alive_;  // per face slot
  std::size_t live_faces_ = 0;
  std::vector<std::uint32_t> neighbours(std::uint32_t v) const;  // sorted
  void link(std::uint32_t x, std::uint32_t y);                   // make x and y twins
  // The targets of the three half-edges of the face whose first half-edge is `first`.
  void set_face(std::uint32_t first, std::uint32_t to0, std::uint32_t to1, std::uint32_t to2);
  std::uint32_t find_half_edge(std::uint32_t a, std::uint32_t b) const;  // a -> b or kNone
  void set_outgoing(std::uint32_t v);
};

}  // namespace meshflow
