#include "nodes/decimate/vertex_rings.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstring>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "runtime/simd.h"
#include "runtime/vertex_triangles.h"

namespace meshflow {
namespace {

// Room left in a ring placed in VertexRings::data_ beyond its size: a collapse onto a vertex
// usually grows its ring by a few entries, and a ring that outgrows its room moves to the end
// of the storage.
constexpr std::uint32_t kSlack = 6;

using Pair = std::pair<std::uint32_t, std::uint32_t>;  // (a, b) of a face (u, a, b)

// Per-thread lookups over the faces (u, a, b) of one vertex at a time: which face has a given
// a, and whether a vertex is some face's b. Stamped per vertex, so nothing is cleared between
// vertices: O(faces) per vertex, O(V) memory per thread.
struct FanIndex {
  std::vector<std::uint32_t> a_stamp, a_face, b_stamp;
  std::uint32_t stamp = 0;
  std::vector<Pair> pairs;  ///< the first `count` are u's faces
  std::size_t count = 0;
  std::vector<std::uint32_t> starts, entries;

  explicit FanIndex(std::size_t vertex_count)
      : a_stamp(vertex_count, 0), a_face(vertex_count, 0), b_stamp(vertex_count, 0) {}

  // Reads u's faces, the triangles listed in [first, last), as pairs (a, b) and indexes them;
  // false when a face repeats a corner or two faces share an a or a b (a non-manifold edge, a
  // face given twice).
  bool gather(std::uint32_t u, const std::uint32_t* first, const std::uint32_t* last,
              const std::vector<Triangle>& triangles) {
    if (++stamp == 0) {  // wrapped around: start the stamps again
      std::fill(a_stamp.begin(), a_stamp.end(), 0);
      std::fill(b_stamp.begin(), b_stamp.end(), 0);
      stamp = 1;
    }
    count = static_cast<std::size_t>(last - first);
    if (pairs.size() < count) pairs.resize(2 * count);
    bool manifold = true;
    for (std::uint32_t j = 0; j < count; ++j) {
      const Triangle& t = triangles[first[j]];
      const int i = t[0] == u ? 0 : t[1] == u ? 1 : 2;
      const std::uint32_t a = t[i == 2 ? 0 : i + 1], b = t[i == 0 ? 2 : i - 1];
      manifold &= (a != u) & (b != u) & (a != b) & (a_stamp[a] != stamp) & (b_stamp[b] != stamp);
      a_stamp[a] = stamp;
      a_face[a] = j;
      b_stamp[b] = stamp;
      pairs[j] = {a, b};
    }
    return manifold;
  }
  // The face with this a, or none.
  const Pair* next(std::uint32_t a) const {
    return a_stamp[a] == stamp ? &pairs[a_face[a]] : nullptr;
  }
  bool is_some_b(std::uint32_t x) const { return b_stamp[x] == stamp; }
};

// Orders u's faces, gathered into `fan`, into its ring: fan.entries gets the a's in fan order,
// for an open fan followed by its last face's b, fans separated by kSeparator; `fans` their
// number. Complex when gather() refused the faces or a closed fan is not the only one.
VertexRings::Kind order_fan(bool gathered, FanIndex& fan, std::size_t& fans) {
  using Kind = VertexRings::Kind;
  std::vector<std::uint32_t>& entries = fan.entries;
  entries.clear();
  fans = 1;
  const std::size_t k = fan.count;
  if (k == 0) return Kind::kClosed;
  if (!gathered) return Kind::kComplex;
  // a -> b is one-to-one, so the faces form chains from each a that is no face's b (open fans,
  // in the order of their first a) and cycles.
  fan.starts.clear();
  for (std::size_t j = 0; j < k; ++j)
    if (!fan.is_some_b(fan.pairs[j].first)) fan.starts.push_back(fan.pairs[j].first);
  const std::size_t open = fan.starts.size();
  if (open != 0) {
    if (open > 1) std::sort(fan.starts.begin(), fan.starts.end());
    std::size_t used = 0;
    for (std::size_t f = 0; f < open; ++f) {
      if (f != 0) entries.push_back(VertexRings::kSeparator);
      std::uint32_t a = fan.starts[f];
      for (const Pair* face = fan.next(a); face != nullptr; face = fan.next(a)) {
        entries.push_back(a);
        a = face->second;
        ++used;
      }
      entries.push_back(a);
    }
    if (used != k) return Kind::kComplex;  // a closed fan beside open ones
    fans = open;
    return open == 1 ? Kind::kOpen : Kind::kFans;
  }
  // One closed fan through every face, from the first face given.
  if (k < 3) return Kind::kComplex;
  const std::uint32_t first = fan.pairs.front().first;
  std::uint32_t a = first;
  for (std::size_t step = 0; step < k; ++step) {
    if (step != 0 && a == first) return Kind::kComplex;  // a closed fan of fewer faces
    entries.push_back(a);
    a = fan.next(a)->second;  // (every a has a face: no fan is open)
  }
  return a == first ? Kind::kClosed : Kind::kComplex;
}

// Faces around a vertex up to which order_small_fan() orders its fan (nearly every vertex);
// larger fans go through FanIndex's per-vertex stamps.
constexpr std::size_t kSmallFan = 16;

// Bit j set where lane j of the `vectors` x 4 lanes at `lanes` equals x (lanes 0 .. 15): with
// SSE2 (every x86-64), one compare and one sign-bit mask per vector.
std::uint32_t lanes_equal(const simd::Uints4* lanes, std::size_t vectors, std::uint32_t x) {
#if defined(__SSE2__)
  const __m128i key = _mm_set1_epi32(static_cast<int>(x));
  std::uint32_t bits = 0;
  for (std::size_t i = 0; i < vectors; ++i) {
    __m128i four;
    std::memcpy(&four, &lanes[i], sizeof four);
    const int signs = _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(four, key)));
    bits |= static_cast<std::uint32_t>(signs) << (4 * i);
  }
  return bits;
#else
  const simd::Uints4 weights = {1, 2, 4, 8};
  simd::Uints4 hits = {0, 0, 0, 0};
  for (std::size_t i = 0; i < vectors; ++i)
    hits |= reinterpret_cast<simd::Uints4>(lanes[i] == x) &
            (weights << static_cast<std::uint32_t>(4 * i));
  return hits[0] | hits[1] | hits[2] | hits[3];
#endif
}

// gather() and order_fan() for a vertex u of at most kSmallFan faces, the triangles listed in
// [first, last), with the same result: each face's successor (the face whose a is its b) is
// found by comparing its b with every a at once, four per SSE vector (no memory of the vertex
// count touched). Writes the ring to `entries` (room for 3 x kSmallFan), its length to `count`
// and the fan count to `fans`. O(faces^2 / 4).
VertexRings::Kind order_small_fan(std::uint32_t u, const std::uint32_t* first,
                                  const std::uint32_t* last, const std::vector<Triangle>& triangles,
                                  std::uint32_t* entries, std::size_t& count, std::size_t& fans) {
  using Kind = VertexRings::Kind;
  const auto k = static_cast<std::size_t>(last - first);
  count = 0;
  fans = 1;
  if (k == 0) return Kind::kClosed;
  // Face j is (u, as[j], bs[j]); lanes past the last face hold u, which no a or b may equal.
  std::uint32_t as[kSmallFan], bs[kSmallFan];
  bool manifold = true;
  for (std::size_t j = 0; j < k; ++j) {
    const Triangle& t = triangles[first[j]];
    const int i = t[0] == u ? 0 : t[1] == u ? 1 : 2;
    const std::uint32_t a = t[i == 2 ? 0 : i + 1], b = t[i == 0 ? 2 : i - 1];
    manifold &= (a != u) & (b != u) & (a != b);
    as[j] = a;
    bs[j] = b;
  }
  if (!manifold) return Kind::kComplex;
  const std::size_t vectors = (k + 3) / 4;
  std::fill(as + k, as + 4 * vectors, u);
  simd::Uints4 a_lanes[kSmallFan / 4];
  std::memcpy(a_lanes, as, 16 * vectors);
  // next[j]: the face whose a is bs[j], or kNone at the end of an open fan. The a's must be
  // distinct, and so must the b's: those that are a's then have distinct successors (no face
  // is the successor of two), those that are not are compared among themselves.
  constexpr std::uint8_t kNone = 0xFF;
  std::uint8_t next[kSmallFan];
  std::uint32_t with_predecessor = 0, ends[kSmallFan];
  std::size_t successors = 0, end_count = 0;
  for (std::size_t j = 0; j < k; ++j) {
    if (lanes_equal(a_lanes, vectors, as[j]) != (1u << j)) return Kind::kComplex;
    const std::uint32_t after = lanes_equal(a_lanes, vectors, bs[j]);
    if (after != 0) {
      next[j] = static_cast<std::uint8_t>(__builtin_ctz(after));
      with_predecessor |= after;
      ++successors;
    } else {
      next[j] = kNone;
      for (std::size_t e = 0; e < end_count; ++e)
        if (ends[e] == bs[j]) return Kind::kComplex;
      ends[end_count++] = bs[j];
    }
  }
  if (static_cast<std::size_t>(__builtin_popcount(with_predecessor)) != successors)
    return Kind::kComplex;
  // Open fans start at the faces without a predecessor (their a is no face's b), in the order
  // of that a.
  const std::uint32_t first_faces = ((std::uint32_t{1} << k) - 1) & ~with_predecessor;
  if (first_faces != 0) {
    std::uint64_t starts[kSmallFan];  // (a, face)
    std::size_t open = 0;
    for (std::uint32_t rest = first_faces; rest != 0; rest &= rest - 1) {
      const auto j = static_cast<std::uint32_t>(__builtin_ctz(rest));
      starts[open++] = (std::uint64_t{as[j]} << 32) | j;
    }
    if (open > 1) std::sort(starts, starts + open);
    std::size_t used = 0;
    for (std::size_t f = 0; f < open; ++f) {
      if (f != 0) entries[count++] = VertexRings::kSeparator;
      auto j = static_cast<std::size_t>(starts[f] & 0xFFFFFFFFu);
      while (true) {
        entries[count++] = as[j];
        ++used;
        if (next[j] == kNone) break;
        j = next[j];
      }
      entries[count++] = bs[j];
    }
    if (used != k) return Kind::kComplex;  // a closed fan beside open ones
    fans = open;
    return open == 1 ? Kind::kOpen : Kind::kFans;
  }
  // One closed fan through every face, from the first face given.
  if (k < 3) return Kind::kComplex;
  std::size_t j = 0;
  for (std::size_t step = 0; step < k; ++step) {
    if (step != 0 && j == 0) return Kind::kComplex;  // a closed fan of fewer faces
    entries[count++] = as[j];
    j = next[j];  // (every face has a successor: no fan is open)
  }
  return j == 0 ? Kind::kClosed : Kind::kComplex;
}

}  // namespace

VertexRings::VertexRings(const std::vector<Triangle>& triangles, std::size_t vertex_count)
    : VertexRings(triangles, vertex_triangles(triangles, vertex_count)) {}

VertexRings::VertexRings(const std::vector<Triangle>& triangles, const VertexTriangles& around)
    : records_(around.offsets.size() - 1) {
  const std::size_t vertex_count = around.offsets.size() - 1;
  tbb::enumerable_thread_specific<FanIndex> work([vertex_count] { return FanIndex(vertex_count); });
  // Orders v's fan into fan.entries and sets v's kind and fan count.
  const auto order = [&](std::uint32_t v, FanIndex& fan) {
    const bool gathered = fan.gather(v, around.begin(v), around.end(v), triangles);
    std::size_t fans = 1;
    Record& record = records_[v];
    record.kind = order_fan(gathered, fan, fans);
    if (fans > 0xFFFF) record.kind = Kind::kComplex;
    record.fans = static_cast<std::uint16_t>(fans);
  };
  // In parallel into every record; a ring longer than a record holds (rare: a vertex of
  // valence above kInline) is left for a serial pass that places it in data_.
  std::vector<std::uint8_t> too_big(vertex_count, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertex_count),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      std::uint32_t small[3 * kSmallFan];
                      for (std::size_t v = range.begin(); v != range.end(); ++v) {
                        const auto u = static_cast<std::uint32_t>(v);
                        Record& record = records_[v];
                        const std::uint32_t* entries = small;
                        std::size_t count = 0;
                        if (around.end(u) - around.begin(u) <= std::ptrdiff_t{kSmallFan}) {
                          std::size_t fans = 1;
                          record.kind = order_small_fan(u, around.begin(u), around.end(u),
                                                        triangles, small, count, fans);
                          record.fans = static_cast<std::uint16_t>(fans);
                        } else {
                          FanIndex& fan = work.local();
                          order(u, fan);
                          entries = fan.entries.data();
                          count = fan.entries.size();
                        }
                        if (record.kind == Kind::kComplex) continue;
                        if (count > kInline) {
                          too_big[v] = 1;
                          continue;
                        }
                        std::copy(entries, entries + count, record.local);
                        record.size = static_cast<std::uint32_t>(count);
                      }
                    });
  for (std::uint32_t v = 0; v < vertex_count; ++v)
    if (too_big[v]) {
      FanIndex& fan = work.local();
      order(v, fan);
      assign(v, fan.entries.data(), fan.entries.size());
    }
  // Locked: v of several fans or complex, or a corner of a complex vertex's faces (its
  // neighbours; a complex vertex has no ring to list them). Complex vertices are few: their
  // faces are visited, not every vertex's ring.
  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    if (kind(v) == Kind::kFans) records_[v].flags |= kLocked;
    if (kind(v) != Kind::kComplex) continue;
    records_[v].flags |= kLocked;
    for (const std::uint32_t* t = around.begin(v); t != around.end(v); ++t)
      for (const std::uint32_t corner : triangles[*t]) records_[corner].flags |= kLocked;
  }
  for (const Triangle& t : triangles)
    if (kind(t[0]) == Kind::kComplex && kind(t[1]) == Kind::kComplex &&
        kind(t[2]) == Kind::kComplex)
      complex_only_.push_back(t);
}

void VertexRings::make_room(std::uint32_t v, std::size_t count) {
  Record& record = records_[v];
  if (count <= capacity(record)) return;
  const bool spilled = (record.flags & kSpilled) != 0;
  const std::uint32_t old_offset = spilled ? record.outside.offset : 0;
  const auto offset = static_cast<std::uint32_t>(data_.size());
  const auto room = static_cast<std::uint32_t>(count + count / 2 + kSlack);
  data_.resize(data_.size() + room);
  // (Copied before `outside` is written: a record's own entries share its storage.)
  const std::uint32_t* from = spilled ? data_.data() + old_offset : record.local;
  std::copy(from, from + record.size, data_.data() + offset);
  record.outside = {offset, room};
  record.flags |= kSpilled;
}

void VertexRings::assign(std::uint32_t v, const std::uint32_t* entries_in, std::size_t count) {
  Record& record = records_[v];
  record.size = 0;  // (nothing to keep)
  make_room(v, count);
  std::copy(entries_in, entries_in + count, entries(record));
  record.size = static_cast<std::uint32_t>(count);
}

void VertexRings::erase_or_replace(std::uint32_t w, std::uint32_t u, std::uint32_t v, bool erase) {
  Record& record = records_[w];
  std::uint32_t* ring = entries(record);
  std::uint32_t* at = std::find(ring, ring + record.size, u);
  if (at == ring + record.size) return;  // (cannot happen: u is w's neighbour)
  if (!erase) {
    *at = v;
    return;
  }
  std::copy(at + 1, ring + record.size, at);
  --record.size;
}

void VertexRings::reserve_collapse(std::uint32_t u, std::uint32_t v) {
  // v's ring loses u and gains u's ring but v and the one or two wings (collapse()'s run).
  const std::size_t run_length = size(u) - (kind(u) == Kind::kClosed ? 3 : 2);
  make_room(v, size(v) - 1 + run_length);
}

std::size_t VertexRings::collapse(std::uint32_t u, std::uint32_t v) {
  const std::size_t n = records_[u].size;
  const std::uint32_t* ring_u = begin(u);
  const std::size_t j = static_cast<std::size_t>(std::find(ring_u, ring_u + n, v) - ring_u);
  // The wings (opposite corners of the faces that vanish) and the run of u's ring between them,
  // [run_begin, run_begin + run_length) cyclically, that takes u's place in v's ring.
  std::uint32_t wing_a = 0, wing_b = 0;
  std::size_t run_begin = 0, run_length = 0, removed = 0;
  if (kind(u) == Kind::kClosed) {
    wing_a = ring_u[(j + 1) % n];
    wing_b = ring_u[(j + n - 1) % n];
    run_begin = (j + 2) % n;
    run_length = n - 3;
    removed = 2;
  } else {  // open: v is the first or the last border neighbour
    wing_a = wing_b = j == 0 ? ring_u[1] : ring_u[n - 2];
    run_begin = j == 0 ? 2 : 0;
    run_length = n - 2;
    removed = 1;
  }
  // v's ring with u replaced by the run, in place once it has the room (moving it to the end
  // of data_, which may move it all: pointers are taken after).
  Record& record_v = records_[v];
  const std::size_t old_size = record_v.size;
  const std::size_t at = static_cast<std::size_t>(std::find(begin(v), end(v), u) - begin(v));
  const std::size_t tail = at < old_size ? old_size - at - 1 : 0;  // entries after u
  const std::size_t new_size = at + run_length + tail;
  make_room(v, new_size);
  std::uint32_t* const to = entries(record_v);
  std::uint32_t* const after = to + at + 1;
  if (run_length > 1)
    std::copy_backward(after, after + tail, to + new_size);
  else if (run_length == 0)
    std::copy(after, after + tail, to + at);
  record_v.size = static_cast<std::uint32_t>(new_size);
  ring_u = begin(u);
  for (std::size_t i = 0, k = run_begin; i < run_length; ++i, k = k + 1 == n ? 0 : k + 1)
    to[at + i] = ring_u[k];
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t w = ring_u[i];
    if (w != v) erase_or_replace(w, u, v, w == wing_a || w == wing_b);
  }
  records_[u].size = 0;
  return removed;
}

std::size_t VertexRings::neighbours_among(std::uint32_t v, const std::uint32_t* list,
                                          std::size_t count) const {
  using Lanes = simd::Uints4;  // four vertex numbers
  std::size_t found = 0;
  for (std::size_t first = 0; first < count; first += 8) {
    std::uint32_t chunk[8];  // padded with v, which is not in its own ring
    for (std::size_t k = 0; k < 8; ++k) chunk[k] = first + k < count ? list[first + k] : v;
    Lanes low, high;
    std::memcpy(&low, chunk, sizeof low);
    std::memcpy(&high, chunk + 4, sizeof high);
    Lanes hit_low = {0, 0, 0, 0}, hit_high = {0, 0, 0, 0};  // all ones where found
    for (const std::uint32_t* x = begin(v); x != end(v); ++x) {
      const std::uint32_t w = *x;
      hit_low |= reinterpret_cast<Lanes>(low == w);
      hit_high |= reinterpret_cast<Lanes>(high == w);
    }
    const Lanes hits = (hit_low & 1u) + (hit_high & 1u);
    found += hits[0] + hits[1] + hits[2] + hits[3];
  }
  return found;
}

bool VertexRings::share_face(std::uint32_t v, std::uint32_t x, std::uint32_t y) const {
  bool shared = false;
  for_each_face(v, [&](std::uint32_t a, std::uint32_t b) {
    shared = shared || (a == x && b == y) || (a == y && b == x);
  });
  return shared;
}

std::vector<Triangle> VertexRings::triangles() const {
  // In blocks of vertices, in parallel: each block's faces listed on their own, then copied to
  // the block's place (the prefix sums of their counts), so the order is the serial one for any
  // thread count.
  constexpr std::size_t kBlockVertices = 4096;
  const std::size_t n = records_.size();
  const std::size_t blocks = (n + kBlockVertices - 1) / kBlockVertices;
  const auto owner_or_later = [this](std::uint32_t corner, std::uint32_t owner) {
    return corner > owner || kind(corner) == Kind::kComplex;
  };
  std::vector<std::vector<Triangle>> listed(blocks);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t block) {
    std::vector<Triangle>& faces = listed[block];
    const auto last = static_cast<std::uint32_t>(std::min(n, (block + 1) * kBlockVertices));
    for (auto m = static_cast<std::uint32_t>(block * kBlockVertices); m < last; ++m)
      for_each_face(m, [&](std::uint32_t b, std::uint32_t c) {
        if (owner_or_later(b, m) && owner_or_later(c, m)) faces.push_back({m, b, c});
      });
  });
  std::vector<std::size_t> starts(blocks + 1, 0);
  for (std::size_t block = 0; block < blocks; ++block)
    starts[block + 1] = starts[block] + listed[block].size();
  std::vector<Triangle> out(starts[blocks] + complex_only_.size());
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t block) {
    std::copy(listed[block].begin(), listed[block].end(),
              out.begin() + static_cast<std::ptrdiff_t>(starts[block]));
  });
  std::copy(complex_only_.begin(), complex_only_.end(),
            out.begin() + static_cast<std::ptrdiff_t>(starts[blocks]));
  return out;
}

}  // namespace meshflow
