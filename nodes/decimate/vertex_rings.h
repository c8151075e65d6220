#pragma once
// The neighbours of every vertex of a triangle mesh in fan order (a "ring"), kept current under
// half-edge collapses: what the QEM decimator reads for every candidate collapse, one short
// contiguous list per vertex instead of a walk over incidence rows and face corners. Used by
// qem_decimation.cpp.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "runtime/triangle_mesh.h"
#include "runtime/vertex_triangles.h"

namespace meshflow {

/// Reading (kind, ring, face counts, triangles()) is safe from any number of threads while
/// nothing collapses; collapse() must run alone.
class VertexRings {
 public:
  enum class Kind : std::uint8_t {
    /// An inner vertex (or one without faces): faces (v, r[i], r[(i + 1) mod n]).
    kClosed,
    /// A border vertex: faces (v, r[i], r[i + 1]) for i < n - 1; r[0] and r[n - 1] are its
    /// neighbours along the border.
    kOpen,
    /// Several border fans meeting at v (a "bow tie", common where depth maps lose pixels):
    /// their rings one after another, each as for kOpen, kSeparator between two.
    kFans,
    /// Faces that do not form consistently oriented open fans or one closed fan (a non-manifold
    /// edge, a face repeating a corner or given twice, a closed fan beside others): no ring.
    kComplex,
  };

  /// Rings of the `vertex_count` vertices of `triangles` (corners < vertex_count), oriented as
  /// the faces are. In parallel over vertices; the same for any thread count. O(V + T) time,
  /// 64 bytes per vertex (one cache line: kind, size and a ring of up to 14 entries), and
  /// 4 x (1.5 x entries + 6) bytes beside for each longer ring.
  VertexRings(const std::vector<Triangle>& triangles, std::size_t vertex_count);
  /// The same from the incidence `around` = vertex_triangles(triangles, vertex_count) (a caller
  /// that needs it too builds it once); the vertex count is its row count.
  VertexRings(const std::vector<Triangle>& triangles, const VertexTriangles& around);

  /// Between two fans of a kFans ring: skip it wherever ring entries are read as vertices.
  static constexpr std::uint32_t kSeparator = 0xFFFFFFFFu;

  /// What v's ring is: closed, open, several fans or complex (Kind).
  Kind kind(std::uint32_t v) const { return records_[v].kind; }
  /// Whether v must never be collapsed: v is kFans or kComplex, or next to a complex vertex (a
  /// vertex of several fans has more than two border neighbours, so the decimator's border
  /// rule refuses it; a complex one's neighbours could not be updated; fixed at construction:
  /// collapses of other vertices only ever give a vertex neighbours that are not complex), or
  /// the caller locked it (lock()).
  bool locked(std::uint32_t v) const { return (records_[v].flags & kLocked) != 0; }
  /// Locks v: locked() from now on (never the removed end of a collapse; other vertices may
  /// still collapse onto it). Not thread-safe for the same v. O(1).
  void lock(std::uint32_t v) { records_[v].flags |= kLocked; }
  /// First entry of v's ring (neighbour vertices, kSeparator between fans).
  const std::uint32_t* begin(std::uint32_t v) const { return entries(records_[v]); }
  /// One past the last entry of v's ring.
  const std::uint32_t* end(std::uint32_t v) const { return begin(v) + records_[v].size; }
  /// Entries in v's ring, separators included.
  std::size_t size(std::uint32_t v) const { return records_[v].size; }
  /// The faces around v: size for a closed ring, size - 1 for an open one, one less per fan
  /// and separator for several, 0 for a complex vertex or one removed by a collapse.
  std::size_t face_count(std::uint32_t v) const {
    const Record& r = records_[v];
    if (r.size == 0 || r.kind == Kind::kClosed) return r.size;
    return r.size + 1 - 2 * std::size_t{r.fans};
  }

  /// How many of the `count` distinct vertices in `list` are neighbours of v (v itself, if
  /// listed, is not). Branch-free over v's ring, eight of `list` at a time in two SSE vectors
  /// (no per-vertex marks): O(valence x (count / 8 + 1)).
  std::size_t neighbours_among(std::uint32_t v, const std::uint32_t* list, std::size_t count) const;

  /// Whether v has a face with x and y (they are consecutive in v's ring, in either order).
  /// O(valence).
  bool share_face(std::uint32_t v, std::uint32_t x, std::uint32_t y) const;

  /// Applies the half-edge collapse u -> v: u's faces not containing v get v in u's place, the
  /// one or two containing v vanish, and u's ring is emptied. Returns the faces removed.
  /// Preconditions (the caller's checks): u is not locked; v is in u's ring; v is one of the two
  /// border neighbours if u is open; the link condition holds (the common neighbours of u and v
  /// are exactly the opposite corners of the removed faces). O(valence of u and v), amortised.
  /// Not thread-safe (rings of u, v and u's neighbours change; storage may move), except as
  /// reserve_collapse() says.
  std::size_t collapse(std::uint32_t u, std::uint32_t v);

  /// Gives v's ring the room collapse(u, v) needs (same preconditions), moving it to the end of
  /// the storage when it has too little: after this, collapse(u, v) moves no storage, so
  /// collapses whose u's closed neighbourhoods (u and its ring) are disjoint may run in
  /// parallel, each prepared by this beforehand. Not thread-safe (storage may move). O(valence).
  void reserve_collapse(std::uint32_t u, std::uint32_t v);

  /// The faces of the mesh as it is now: every face with a non-complex corner, from the ring of
  /// the smallest such corner (in vertex order, then ring order), then the faces of only
  /// complex corners, as in the input (collapses never change them). O(V + T), in parallel over
  /// blocks of vertices; the same order for any thread count.
  std::vector<Triangle> triangles() const;

  /// Requests v's record (kind, size and, for rings of up to kInline entries, the ring).
  void prefetch_slot(std::uint32_t v) const { __builtin_prefetch(&records_[v]); }
  /// Requests v's ring entries where they lie outside its record (after prefetch_slot(v)).
  void prefetch_ring(std::uint32_t v) const {
    const Record& r = records_[v];
    if ((r.flags & kSpilled) != 0) __builtin_prefetch(data_.data() + r.outside.offset);
  }

 private:
  /// Ring entries a record holds itself: most rings (a vertex of valence up to 14) are read
  /// from the one cache line that also holds their size and kind.
  static constexpr std::uint32_t kInline = 14;
  static constexpr std::uint8_t kLocked = 1;   ///< Record::flags: locked()
  static constexpr std::uint8_t kSpilled = 2;  ///< Record::flags: the ring lies in data_
  /// One vertex's ring, one cache line: its entries in `local`, or, once it outgrew them, at
  /// `outside` in data_ (it stays there).
  struct alignas(64) Record {
    std::uint32_t size = 0;
    Kind kind = Kind::kClosed;
    std::uint8_t flags = 0;  ///< kLocked, kSpilled
    std::uint16_t fans = 1;  ///< of a kOpen or kFans ring (collapses never change it)
    struct Outside {
      std::uint32_t offset, capacity;
    };
    union {
      std::uint32_t local[kInline];
      Outside outside;
    };
    Record() : local{} {}
  };
  static_assert(sizeof(Record) == 64, "one cache line per vertex");
  // The ring's first entry, in the record or in data_.
  const std::uint32_t* entries(const Record& r) const {
    return (r.flags & kSpilled) != 0 ? data_.data() + r.outside.offset : r.local;
  }
  std::uint32_t* entries(Record& r) {
    return (r.flags & kSpilled) != 0 ? data_.data() + r.outside.offset : r.local;
  }
  // The entries the ring has room for where it lies.
  static std::size_t capacity(const Record& r) {
    return (r.flags & kSpilled) != 0 ? r.outside.capacity : kInline;
  }
  // Calls fn(a, b) for every face (v, a, b) of v's ring: consecutive entries, around for a closed
  // ring, none across a separator.
  template <typename Fn>
  void for_each_face(std::uint32_t v, Fn&& fn) const {
    const std::uint32_t* ring = begin(v);
    const std::size_t n = size(v);
    const std::size_t pairs = kind(v) == Kind::kClosed ? n : (n == 0 ? 0 : n - 1);
    for (std::size_t i = 0; i < pairs; ++i) {
      const std::uint32_t a = ring[i], b = ring[i + 1 == n ? 0 : i + 1];
      if (a != kSeparator && b != kSeparator) fn(a, b);
    }
  }
  // Gives v's ring room for `count` entries (plus growth slack) at the end of data_, its
  // entries copied there, when it has less. May reallocate data_: pointers into it are invalid
  // afterwards.
  void make_room(std::uint32_t v, std::size_t count);
  // Writes `count` entries as v's ring, moving it to the end of data_ when it does not fit.
  void assign(std::uint32_t v, const std::uint32_t* entries, std::size_t count);
  // In w's ring: u removed (`erase`) or replaced by v.
  void erase_or_replace(std::uint32_t w, std::uint32_t u, std::uint32_t v, bool erase);

  std::vector<Record> records_;
  std::vector<std::uint32_t> data_;     ///< rings longer than kInline
  std::vector<Triangle> complex_only_;  ///< faces whose corners are all complex
};

}  // namespace meshflow
