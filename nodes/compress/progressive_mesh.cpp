#include "nodes/compress/progressive_mesh.h"

#include <algorithm>
#include <string>

#include "nodes/compress/attribute_coder.h"
#include "nodes/compress/closed_surface.h"
#include "nodes/compress/range_coder.h"
#include "nodes/decimate/qem_decimation.h"
#include "runtime/error.h"

namespace meshflow::compress {
namespace {

// The six orders of a triangle's corners (u, v, w): kOrders[k][i] is the role at corner i.
constexpr std::uint8_t kOrders[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1},
                                        {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};

unsigned bits_for_count(std::size_t count) {
  unsigned bits = 1;
  while (bits < 32 && (std::uint64_t{1} << bits) < count) ++bits;
  return bits;
}

// A triangle around v ordered by its other two corners, taken from v on.
std::uint64_t key_around(const Triangle& t, std::uint32_t v) {
  const std::size_t i = t[0] == v ? 0 : t[1] == v ? 1 : 2;
  return std::uint64_t{t[(i + 1) % 3]} << 32 | t[(i + 2) % 3];
}

// The distinct other corners of v's triangles, sorted.
std::vector<std::uint32_t> neighbours_of(const std::vector<Triangle>& around, std::uint32_t v) {
  std::vector<std::uint32_t> n;
  for (const Triangle& t : around)
    for (std::uint32_t c : t)
      if (c != v) n.push_back(c);
  std::sort(n.begin(), n.end());
  n.erase(std::unique(n.begin(), n.end()), n.end());
  return n;
}

// The models of one packet.
struct SplitModels {
  IntegerModel position[3], normal[2], color[3], rank;
  FrequencyModel<16> removed;
  FrequencyModel<8> order;
  BitModel moved[3];
};

// One collapse as the forward replay saw it, in input vertex numbers.
struct Collapse {
  std::uint32_t u, v;
  std::vector<Triangle> around;     // v's triangles after it
  std::vector<std::uint8_t> moved;  // per `around`: it had u before
  std::vector<Triangle> removed;    // the triangles it removed
  std::vector<std::uint32_t> removed_ids;
};

// Replays `sequence` on `triangles`; leaves the base mesh's triangles alive.
std::vector<Collapse> replay_collapses(std::vector<Triangle>& triangles,
                                       std::vector<std::uint8_t>& alive, std::size_t vertices,
                                       const std::vector<std::array<std::uint32_t, 2>>& sequence) {
  std::vector<std::vector<std::uint32_t>> around(vertices);
  for (std::uint32_t t = 0; t < triangles.size(); ++t)
    for (std::uint32_t c : triangles[t]) around[c].push_back(t);
  alive.assign(triangles.size(), 1);
  std::vector<std::uint32_t> stamp(triangles.size(), 0);
  std::vector<Collapse> out(sequence.size());
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const auto [u, v] = sequence[i];
    Collapse& c = out[i];
    c.u = u;
    c.v = v;
    for (std::uint32_t t : around[u]) {
      if (!alive[t]) continue;
      Triangle& f = triangles[t];
      if (f[0] == v || f[1] == v || f[2] == v) {
        c.removed.push_back(f);
        c.removed_ids.push_back(t);
        alive[t] = 0;
      } else {
        for (std::uint32_t& x : f)
          if (x == u) x = v;
        around[v].push_back(t);
        stamp[t] = static_cast<std::uint32_t>(i + 1);
      }
    }
    around[u].clear();
    std::vector<std::uint32_t>& av = around[v];
    av.erase(std::remove_if(av.begin(), av.end(), [&](std::uint32_t t) { return !alive[t]; }),
             av.end());
    for (std::uint32_t t : av) {
      c.around.push_back(triangles[t]);
      c.moved.push_back(stamp[t] == i + 1 ? 1 : 0);
    }
  }
  return out;
}

// The decoder's mesh while splits are applied.
struct LevelState {
  TriangleMesh mesh;
  std::vector<std::array<std::int32_t, 3>> grid;
  std::vector<std::vector<std::uint32_t>> around;
};

// Recomputes the normals of a file that asks for it, at the level decoded.
void finish_levels(LevelState& s, const CompressedMeshInfo& info) {
  if (info.recomputed_normals) detail::recompute_normals(s.mesh, s.grid);
}

}  // namespace

namespace {

// The collapses that make the base level, and the base mesh itself.
struct BaseLevel {
  std::vector<std::uint32_t> kept;           // input triangles the decimation took
  std::vector<std::uint32_t> degenerate;     // input triangles with a repeated corner: stored last
  std::vector<Collapse> collapses;           // in the order the decimation made them
  TriangleMesh base;                         // every vertex no collapse removed, the triangles left
  std::vector<std::uint32_t> base_vertex;    // per base vertex: its input vertex
  std::vector<std::uint32_t> base_triangle;  // per base triangle: its index in `kept` order
};

// Decimates the triangles without a repeated corner to config.base_ratio, recording the
// collapses (none removing a `locked` vertex), and keeps what is left (with the attributes
// `flags` names) as the base mesh.
BaseLevel decimate_to_base(const TriangleMesh& mesh, const CompressConfig& config,
                           AttributeFlags flags, const std::vector<std::uint8_t>& locked) {
  const std::size_t n = mesh.vertices.size();
  BaseLevel level;
  TriangleMesh work;
  work.vertices = mesh.vertices;
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& f = mesh.triangles[t];
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) {
      level.degenerate.push_back(t);
    } else {
      level.kept.push_back(t);
      work.triangles.push_back(f);
    }
  }
  QemConfig qem;
  qem.target_ratio = config.base_ratio;
  qem.divide_by_depth2 = false;
  // Borders still collapse only along themselves, but at any turn: coarse levels round them off,
  // and a scan's many holes do not hold the base up (kurt3d at 90 degrees: 5.9 % of the
  // triangles were left, 5.2 % of the file; now 4.3 % and 3.6 %).
  qem.max_border_turn_deg = 180.0f;
  qem.record_collapses = true;
  qem.locked = locked;
  QemReport decimation;
  qem_decimate(work, qem, &decimation);
  std::vector<Triangle> triangles = work.triangles;
  std::vector<std::uint8_t> alive;
  level.collapses = replay_collapses(triangles, alive, n, decimation.collapse_sequence);

  std::vector<char> removed_vertex(n, 0);
  for (const Collapse& c : level.collapses) removed_vertex[c.u] = 1;
  std::vector<std::uint32_t> local(n, kNone);
  for (std::uint32_t v = 0; v < n; ++v)
    if (!removed_vertex[v]) {
      local[v] = static_cast<std::uint32_t>(level.base_vertex.size());
      level.base_vertex.push_back(v);
      level.base.vertices.push_back(mesh.vertices[v]);
      if (flags.normals) level.base.normals.push_back(mesh.normals[v]);
      if (flags.colors) level.base.colors.push_back(mesh.colors[v]);
    }
  for (std::uint32_t t = 0; t < triangles.size(); ++t)
    if (alive[t]) {
      level.base_triangle.push_back(t);
      level.base.triangles.push_back(
          {local[triangles[t][0]], local[triangles[t][1]], local[triangles[t][2]]});
    }
  return level;
}

// The decoder's numbers: the base's vertices in their decoded order, then each split's u.
struct DecodedNumbers {
  std::vector<std::uint32_t> id;              // per input vertex: its decoded number
  std::vector<std::uint32_t> vertex_order;    // per decoded vertex: its input vertex
  std::vector<std::uint32_t> triangle_order;  // per decoded triangle: its input triangle
};

DecodedNumbers number_as_decoded(const BaseLevel& level, const BodyOrder& order, std::size_t n) {
  DecodedNumbers numbers;
  numbers.id.assign(n, kNone);
  for (std::uint32_t k = 0; k < order.vertex.size(); ++k) {
    numbers.id[level.base_vertex[order.vertex[k]]] = k;
    numbers.vertex_order.push_back(level.base_vertex[order.vertex[k]]);
  }
  for (std::uint32_t t : order.triangle)
    numbers.triangle_order.push_back(level.kept[level.base_triangle[t]]);
  const std::size_t splits = level.collapses.size();
  for (std::size_t j = 0; j < splits; ++j) {
    const std::uint32_t u = level.collapses[splits - 1 - j].u;
    numbers.id[u] = static_cast<std::uint32_t>(order.vertex.size() + j);
    numbers.vertex_order.push_back(u);
  }
  return numbers;
}

// What encoding a split needs beside its collapse. `numbers.triangle_order` and
// `decoded_normals` (the decoder's normals, per decoded vertex) grow as splits are encoded.
struct SplitEncoding {
  const TriangleMesh& mesh;
  const Quantizer& quantizer;
  AttributeFlags flags;
  const std::vector<std::uint32_t>& kept;
  DecodedNumbers& numbers;
  std::vector<Eigen::Vector3f>& decoded_normals;
};

// u's position, normal and colour as differences from v's (decoded number v).
void encode_split_attributes(const Collapse& c, std::uint32_t v, SplitEncoding& e,
                             RangeEncoder& enc, SplitModels& m) {
  const auto gu = e.quantizer.quantize(e.mesh.vertices[c.u]);
  const auto gv = e.quantizer.quantize(e.mesh.vertices[c.v]);
  for (std::size_t a = 0; a < 3; ++a) m.position[a].encode(enc, gu[a] - gv[a]);
  if (e.flags.normals) {
    Eigen::Vector3f decoded;
    const auto d =
        normal_residual(e.decoded_normals[v], e.mesh.normals[c.u], e.flags.normal_bits, decoded);
    for (std::size_t a = 0; a < 2; ++a) m.normal[a].encode(enc, d[a]);
    e.decoded_normals.push_back(decoded);
  }
  if (e.flags.colors) {
    const Rgb8 cu = e.mesh.colors[c.u], cv = e.mesh.colors[c.v];
    const std::uint8_t du[3] = {cu.r, cu.g, cu.b}, dv[3] = {cv.r, cv.g, cv.b};
    for (std::size_t a = 0; a < 3; ++a)
      m.color[a].encode(enc, static_cast<std::int8_t>(du[a] - dv[a]));
  }
}

// Which of v's triangles go to u (in the decoder's key order), then the triangles the split
// adds: each third corner by its rank among v's neighbours (or its number), and its corner
// order.
void encode_split_connectivity(const Collapse& c, std::uint32_t v, std::size_t vertex_count,
                               SplitEncoding& e, RangeEncoder& enc, SplitModels& m) {
  const std::vector<std::uint32_t>& id = e.numbers.id;
  const auto mapped = [&](const Triangle& t) { return Triangle{id[t[0]], id[t[1]], id[t[2]]}; };
  std::vector<Triangle> around(c.around.size());
  std::vector<std::pair<std::uint64_t, std::uint8_t>> keyed(c.around.size());
  for (std::size_t k = 0; k < c.around.size(); ++k) {
    around[k] = mapped(c.around[k]);
    keyed[k] = {key_around(around[k], v), c.moved[k]};
  }
  std::sort(keyed.begin(), keyed.end());
  unsigned previous = 2;
  for (const auto& [key, moved] : keyed) {
    enc.encode(m.moved[previous], moved);
    previous = moved;
  }
  if (c.removed.size() > 15)
    throw Error("progressive mesh", "collapse", "removes more than 15 triangles");
  m.removed.encode(enc, static_cast<unsigned>(c.removed.size()));
  const std::vector<std::uint32_t> neighbours = neighbours_of(around, v);
  const std::uint32_t u = id[c.u];
  for (std::size_t k = 0; k < c.removed.size(); ++k) {
    const Triangle t = mapped(c.removed[k]);
    std::uint32_t w = kNone;
    std::uint8_t role[3];
    for (std::size_t i = 0; i < 3; ++i) {
      role[i] = t[i] == u ? 0 : t[i] == v ? 1 : 2;
      if (role[i] == 2) w = t[i];
    }
    const auto it = std::lower_bound(neighbours.begin(), neighbours.end(), w);
    if (it != neighbours.end() && *it == w) {
      m.rank.encode(enc, static_cast<std::int32_t>(it - neighbours.begin()) + 1);
    } else {
      m.rank.encode(enc, 0);
      enc.encode_direct(w, bits_for_count(vertex_count + 1));
    }
    unsigned k6 = 0;
    while (!(kOrders[k6][0] == role[0] && kOrders[k6][1] == role[1])) ++k6;
    m.order.encode(enc, k6);
    e.numbers.triangle_order.push_back(e.kept[c.removed_ids[k]]);
  }
}

// The split records, finest collapse last undone, in packets of `per_packet`: each packet its
// own range-coded stream with fresh models, its split count, size and a checksum chained from
// the header and base mesh (so any prefix cut at a packet boundary verifies). Writes the
// split and packet counts first and the prefix checksum into the header.
void write_split_packets(io::ByteWriter& out, const std::vector<Collapse>& collapses,
                         std::uint32_t per_packet, std::size_t base_vertices, SplitEncoding& e) {
  const std::size_t splits = collapses.size();
  out.u64(splits);
  const auto packets = static_cast<std::uint32_t>((splits + per_packet - 1) / per_packet);
  out.u32(packets);
  std::uint64_t chain = detail::prefix_checksum(out.out.data(), out.out.size());
  for (std::size_t i = 0; i < 8; ++i)
    out.out[detail::kPrefixChecksumOffset + i] = static_cast<unsigned char>(chain >> (8 * i));
  std::size_t vertex_count = base_vertices;
  for (std::uint32_t p = 0; p < packets; ++p) {
    const std::size_t first = std::size_t{p} * per_packet;
    const std::size_t last = std::min(splits, first + per_packet);
    RangeEncoder enc;
    SplitModels m;
    for (std::size_t j = first; j < last; ++j) {
      const Collapse& c = collapses[splits - 1 - j];
      const std::uint32_t v = e.numbers.id[c.v];
      enc.encode_direct(v, bits_for_count(vertex_count));
      encode_split_attributes(c, v, e, enc, m);
      encode_split_connectivity(c, v, vertex_count, e, enc, m);
      ++vertex_count;
    }
    const std::vector<unsigned char> bytes = enc.finish();
    const std::size_t start = out.out.size();
    out.u32(static_cast<std::uint32_t>(last - first));
    out.u64(bytes.size() + 8);
    out.bytes(bytes.data(), bytes.size());
    chain = detail::fnv1a64_continue(chain, out.out.data() + start, out.out.size() - start);
    out.u64(chain);
  }
}

}  // namespace

std::vector<unsigned char> compress_progressive(const TriangleMesh& mesh,
                                                const CompressConfig& config,
                                                CompressReport* report) {
  return compress_progressive(mesh, {}, config, report);
}

std::vector<unsigned char> compress_progressive(const TriangleMesh& mesh,
                                                const std::vector<std::uint8_t>& locked,
                                                const CompressConfig& config,
                                                CompressReport* report) {
  require_corners_in_range(mesh.triangles, mesh.vertices.size(), "mesh");
  const std::size_t n = mesh.vertices.size();
  if (!locked.empty() && locked.size() != n)
    throw Error("progressive mesh", "locked vertices",
                std::to_string(locked.size()) + " flags for " + std::to_string(n) + " vertices");
  const Quantizer quantizer = choose_quantizer(mesh, config);
  const AttributeFlags flags = detail::attribute_flags(mesh, config);

  BaseLevel level = decimate_to_base(mesh, config, flags, locked);

  io::ByteWriter out;
  detail::write_header(out, CompressionKind::kProgressive, flags, n, mesh.triangles.size(),
                       quantizer, config.origin_offset);
  BodyOrder order;
  BodyCodes codes;
  const BodyStats stats = encode_body(level.base, quantizer, flags, out, &order, &codes);
  const std::size_t base_bytes = out.out.size();

  DecodedNumbers numbers = number_as_decoded(level, order, n);
  std::vector<Eigen::Vector3f> decoded_normals = std::move(codes.normals);  // per decoded id
  SplitEncoding encoding{mesh, quantizer, flags, level.kept, numbers, decoded_normals};
  write_split_packets(out, level.collapses, std::max<std::uint32_t>(1, config.splits_per_packet),
                      order.vertex.size(), encoding);

  out.u64(level.degenerate.size());
  for (std::uint32_t t : level.degenerate) {
    for (std::uint32_t c : mesh.triangles[t]) out.u32(numbers.id[c]);
    numbers.triangle_order.push_back(t);
  }
  detail::seal(out);
  if (report != nullptr) {
    *report = CompressReport{};
    report->kind = CompressionKind::kProgressive;
    report->total_bytes = out.out.size();
    report->body = stats;
    report->quantizer = quantizer;
    report->base_triangles = level.base.triangles.size();
    report->base_bytes = base_bytes;
    report->splits = level.collapses.size();
    report->vertex_order = std::move(numbers.vertex_order);
    report->triangle_order = std::move(numbers.triangle_order);
  }
  return std::move(out.out);
}

namespace {

// The little-endian bytes of a packet's header, for its checksum.
std::uint64_t chain_header(std::uint64_t chain, std::uint32_t count, std::uint64_t size) {
  unsigned char h[12];
  for (std::size_t i = 0; i < 4; ++i) h[i] = static_cast<unsigned char>(count >> (8 * i));
  for (std::size_t i = 0; i < 8; ++i) h[4 + i] = static_cast<unsigned char>(size >> (8 * i));
  return detail::fnv1a64_continue(chain, h, sizeof h);
}

}  // namespace

void reseal_progressive_mesh(std::vector<unsigned char>& bytes) {
  // Little-endian field reads and writes that give up (false) past the data.
  const auto get = [&](std::size_t at, std::size_t width, std::uint64_t& v) {
    if (at > bytes.size() || width > bytes.size() - at) return false;
    v = 0;
    for (std::size_t i = 0; i < width; ++i) v |= std::uint64_t{bytes[at + i]} << (8 * i);
    return true;
  };
  const auto put = [&](std::size_t at, std::uint64_t v) {
    for (std::size_t i = 0; i < 8; ++i) bytes[at + i] = static_cast<unsigned char>(v >> (8 * i));
  };
  const auto resealed_file = [&] { reseal_compressed_mesh(bytes); };
  // Header: magic 8, version 4, kind 4, flags 4, counts 16, quantiser 36, prefix checksum 8.
  constexpr std::size_t kKindOffset = 12, kBodyOffset = detail::kPrefixChecksumOffset + 8;
  std::uint64_t kind = 0;
  if (bytes.size() < kBodyOffset + 8 || !get(kKindOffset, 4, kind) ||
      kind != static_cast<std::uint64_t>(CompressionKind::kProgressive))
    return resealed_file();
  // The base body (mesh_codec.h): u32, u64, u64, five sections, u8, one section.
  std::size_t at = kBodyOffset + 20;
  std::uint64_t n = 0;
  for (int section = 0; section < 6; ++section) {
    if (section == 5) ++at;  // the normal bits
    if (!get(at, 8, n) || n > bytes.size()) return resealed_file();
    at += 8 + static_cast<std::size_t>(n);
  }
  std::uint64_t packets = 0;
  if (!get(at + 8, 4, packets)) return resealed_file();
  at += 12;
  const std::size_t data_end = bytes.size() - 8;  // before the file checksum
  if (at > data_end) return resealed_file();
  std::uint64_t chain = detail::prefix_checksum(bytes.data(), at);
  put(detail::kPrefixChecksumOffset, chain);
  for (std::uint64_t p = 0; p < packets; ++p) {
    std::uint64_t count = 0, size = 0;
    if (!get(at, 4, count) || !get(at + 4, 8, size) || size < 8 ||
        size > data_end - std::min(data_end, at + 12))
      break;
    const std::size_t stream = static_cast<std::size_t>(size - 8);
    chain = detail::fnv1a64_continue(chain_header(chain, static_cast<std::uint32_t>(count), size),
                                     bytes.data() + at + 12, stream);
    put(at + 12 + stream, chain);
    at += 12 + static_cast<std::size_t>(size);
  }
  resealed_file();
}

namespace {

// One split packet, its checksum verified: how many splits it holds and its range-coded bytes.
struct SplitPacket {
  std::uint32_t count = 0;
  const unsigned char* bytes = nullptr;
  std::size_t size = 0;
};

// Reads packet p's header and bytes and checks its checksum, chained on from `chain` (updated).
// `splits_left`: how many splits the file still states.
SplitPacket read_split_packet(io::ByteReader& in, std::uint32_t p, std::uint64_t splits_left,
                              std::uint64_t& chain) {
  SplitPacket packet;
  packet.count = in.u32("packet split count");
  const std::uint64_t size = in.u64("packet size");
  if (packet.count > splits_left) in.fail("packet split count", "more splits than stated");
  if (size < 8) in.fail("packet size", std::to_string(size) + " bytes hold no checksum");
  if (size > in.remaining())
    in.fail("packet size", "packet " + std::to_string(p) + " needs " + std::to_string(size) +
                               " bytes, " + std::to_string(in.remaining()) +
                               " left (truncated inside a packet, or corrupt)");
  packet.size = static_cast<std::size_t>(size - 8);
  packet.bytes = in.bytes(packet.size, "packet");
  chain =
      detail::fnv1a64_continue(chain_header(chain, packet.count, size), packet.bytes, packet.size);
  if (in.u64("packet checksum") != chain)
    in.fail("packet checksum", "packet " + std::to_string(p) + " does not match its contents");
  return packet;
}

// The new vertex u's position, normal and colour from v's and the coded differences.
void decode_split_attributes(LevelState& s, std::uint32_t v, const CompressedMeshInfo& info,
                             unsigned normal_bits, RangeDecoder& dec, SplitModels& m) {
  std::array<std::int32_t, 3> gu{};
  for (std::size_t a = 0; a < 3; ++a)
    gu[a] = static_cast<std::int32_t>(static_cast<std::uint32_t>(s.grid[v][a]) +
                                      static_cast<std::uint32_t>(m.position[a].decode(dec)));
  s.grid.push_back(gu);
  s.mesh.vertices.push_back(info.quantizer.position(gu));
  if (info.normals) {
    std::array<std::int32_t, 2> d{};
    for (std::size_t a = 0; a < 2; ++a) d[a] = m.normal[a].decode(dec);
    s.mesh.normals.push_back(apply_normal_residual(s.mesh.normals[v], d, normal_bits));
  }
  if (info.colors) {
    const Rgb8 cv = s.mesh.colors[v];
    const std::uint8_t dv[3] = {cv.r, cv.g, cv.b};
    std::uint8_t du[3];
    for (std::size_t a = 0; a < 3; ++a)
      du[a] = static_cast<std::uint8_t>(dv[a] + static_cast<std::uint8_t>(m.color[a].decode(dec)));
    s.mesh.colors.push_back(Rgb8{du[0], du[1], du[2]});
  }
}

// Moves the marked triangles of v to u (in key order) and adds the triangles the split made;
// `fail` reports a record that names no valid vertex or corner order.
template <typename Fail>
void decode_split_connectivity(LevelState& s, std::uint32_t u, std::uint32_t v, RangeDecoder& dec,
                               SplitModels& m, const Fail& fail) {
  s.around.emplace_back();
  std::vector<std::uint32_t>& av = s.around[v];
  std::vector<Triangle> around;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
  around.reserve(av.size());
  keyed.reserve(av.size());
  for (std::uint32_t t : av) {
    around.push_back(s.mesh.triangles[t]);
    keyed.push_back({key_around(s.mesh.triangles[t], v), t});
  }
  const std::vector<std::uint32_t> neighbours = neighbours_of(around, v);
  std::sort(keyed.begin(), keyed.end());
  unsigned previous = 2;
  std::vector<std::uint32_t> stay;
  for (const auto& [key, t] : keyed) {
    const unsigned moved = dec.decode(m.moved[previous]);
    previous = moved;
    if (moved) {
      for (std::uint32_t& x : s.mesh.triangles[t])
        if (x == v) x = u;
      s.around[u].push_back(t);
    } else {
      stay.push_back(t);
    }
  }
  s.around[v] = std::move(stay);
  const unsigned removed = m.removed.decode(dec);
  for (unsigned k = 0; k < removed; ++k) {
    const std::int32_t rank = m.rank.decode(dec);
    std::uint32_t w = kNone;
    if (rank == 0) {
      w = dec.decode_direct(bits_for_count(std::size_t{u} + 1));
    } else if (rank > 0 && static_cast<std::size_t>(rank) <= neighbours.size()) {
      w = neighbours[static_cast<std::size_t>(rank) - 1];
    } else {
      fail("third vertex rank " + std::to_string(rank) + " of " +
           std::to_string(neighbours.size()) + " neighbours");
    }
    if (w >= u || w == v) fail("third vertex " + std::to_string(w) + " is not valid");
    const unsigned k6 = m.order.decode(dec);
    if (k6 >= 6) fail("corner order " + std::to_string(k6));
    const std::uint32_t roles[3] = {u, v, w};
    const Triangle t{roles[kOrders[k6][0]], roles[kOrders[k6][1]], roles[kOrders[k6][2]]};
    const auto index = static_cast<std::uint32_t>(s.mesh.triangles.size());
    s.mesh.triangles.push_back(t);
    for (std::uint32_t c : t) s.around[c].push_back(index);
  }
}

// The triangles with a repeated corner, stored after the last packet.
void read_degenerate_triangles(io::ByteReader& in, TriangleMesh& mesh) {
  const std::uint64_t degenerate = in.u64("degenerate triangle count");
  if (degenerate > in.remaining() / 12)
    in.fail("degenerate triangle count", std::to_string(degenerate) + " do not fit the file");
  for (std::uint64_t i = 0; i < degenerate; ++i) {
    Triangle t;
    for (std::uint32_t& c : t) {
      c = in.u32("degenerate triangle corner");
      if (c >= mesh.vertices.size()) in.fail("degenerate triangle corner", "out of range");
    }
    mesh.triangles.push_back(t);
  }
}

}  // namespace

TriangleMesh decode_progressive(io::ByteReader& in, const CompressedMeshInfo& info,
                                const std::string& source, const ProgressiveLevel& level,
                                PrefixState* prefix) {
  const AttributeFlags flags{info.normals, info.colors};
  LevelState s;
  BodyCodes codes;
  s.mesh = decode_body(in, info.quantizer, flags, source, &codes);
  const std::size_t base_vertices = s.mesh.vertices.size();
  s.grid = std::move(codes.positions);
  const unsigned normal_bits = codes.normal_bits;
  s.around.resize(base_vertices);
  for (std::uint32_t t = 0; t < s.mesh.triangles.size(); ++t)
    for (std::uint32_t c : s.mesh.triangles[t]) s.around[c].push_back(t);

  const std::uint64_t splits = in.u64("split count");
  if (splits > info.vertices || base_vertices + splits != info.vertices)
    in.fail("split count", std::to_string(splits) + " splits on a base of " +
                               std::to_string(base_vertices) + " vertices do not make the " +
                               std::to_string(info.vertices) + " stated");
  const std::uint32_t packets = in.u32("packet count");
  if (prefix != nullptr) {
    prefix->packets_stated = packets;
    if (detail::prefix_checksum(prefix->image, in.position()) != info.prefix_checksum)
      in.fail("prefix checksum",
              "does not match the header and base mesh (corrupt data, or not a prefix of a "
              "progressive file)");
  }
  std::uint64_t applied = 0, chain = info.prefix_checksum;
  bool full = true;
  for (std::uint32_t p = 0; p < packets && full; ++p) {
    if (prefix != nullptr && in.remaining() == 0) {  // the prefix ends at a packet boundary
      finish_levels(s, info);
      return std::move(s.mesh);
    }
    const SplitPacket packet = read_split_packet(in, p, splits - applied, chain);
    if (prefix != nullptr) ++prefix->packets_read;
    RangeDecoder dec(packet.bytes, packet.size, source, "split packet " + std::to_string(p));
    SplitModels m;
    for (std::uint32_t j = 0; j < packet.count; ++j) {
      if (applied >= level.splits || s.mesh.triangles.size() >= level.triangles) {
        full = false;
        if (prefix != nullptr) prefix->stopped_at_level = true;
        break;
      }
      const auto fail = [&](const std::string& problem) {
        throw Error(source, "vertex split " + std::to_string(applied), problem);
      };
      const std::size_t vertex_count = s.mesh.vertices.size();
      const std::uint32_t v = dec.decode_direct(bits_for_count(vertex_count));
      if (v >= vertex_count)
        fail("names vertex " + std::to_string(v) + " of " + std::to_string(vertex_count));
      decode_split_attributes(s, v, info, normal_bits, dec, m);
      decode_split_connectivity(s, static_cast<std::uint32_t>(vertex_count), v, dec, m, fail);
      dec.check();
      ++applied;
    }
  }
  // A level short of the full mesh, or a prefix holding every packet but not the file's end.
  if (!full || applied < splits || (prefix != nullptr && in.remaining() == 0)) {
    finish_levels(s, info);
    return std::move(s.mesh);
  }
  read_degenerate_triangles(in, s.mesh);
  if (prefix != nullptr) prefix->complete = true;
  finish_levels(s, info);
  return std::move(s.mesh);
}

TriangleMesh decompress_progressive_level(const std::vector<unsigned char>& bytes,
                                          const std::string& source,
                                          const ProgressiveLevel& level) {
  io::ByteReader in = detail::body_reader(bytes, source);
  const CompressedMeshInfo info = detail::read_header(in, bytes);
  if (info.kind != CompressionKind::kProgressive)
    throw Error(source, "kind", "is single-rate (Edgebreaker): it has no levels of detail");
  return decode_progressive(in, info, source, level);
}

}  // namespace meshflow::compress

namespace meshflow::compress {

PrefixDecode decompress_progressive_prefix(const std::vector<unsigned char>& bytes,
                                           const std::string& source,
                                           const ProgressiveLevel& level) {
  PrefixDecode out;
  io::ByteReader in(source, bytes);
  const CompressedMeshInfo info = detail::read_header(in, bytes, false);
  if (info.kind != CompressionKind::kProgressive)
    throw Error(source, "kind", "is single-rate (Edgebreaker): only the whole file decodes");
  // A whole file: its checksum covers everything (the tail too).
  if (bytes.size() >= 8) {
    std::uint64_t stored = 0;
    for (std::size_t i = 0; i < 8; ++i)
      stored |= static_cast<std::uint64_t>(bytes[bytes.size() - 8 + i]) << (8 * i);
    if (stored == io::fnv1a64(bytes.data(), bytes.size() - 8)) {
      io::ByteReader body = detail::body_reader(bytes, source);
      detail::read_header(body, bytes);
      PrefixState state{bytes.data()};
      out.mesh = decode_progressive(body, info, source, level, &state);
      out.packets = state.packets_read;
      out.packets_stated = state.packets_stated;
      out.complete = state.complete;
      if (state.complete && body.remaining() != 0)
        body.fail("end of data",
                  std::to_string(body.remaining()) + " bytes left before the checksum");
      return out;
    }
  }
  PrefixState state{bytes.data()};
  out.mesh = decode_progressive(in, info, source, level, &state);
  out.packets = state.packets_read;
  out.packets_stated = state.packets_stated;
  if (!state.stopped_at_level && (state.complete || in.remaining() != 0))
    in.fail("checksum",
            "the file's end does not match its contents (corrupt, or cut inside "
            "its last part)");
  return out;
}

}  // namespace meshflow::compress
