#include "nodes/compress/mesh_codec.h"

#include <algorithm>
#include <optional>

#include "nodes/compress/attribute_coder.h"
#include "nodes/compress/closed_surface.h"
#include "nodes/compress/edgebreaker_connectivity.h"
#include "nodes/compress/edgebreaker_replay.h"
#include "nodes/compress/parallelogram_ring.h"
#include "nodes/compress/range_coder.h"
#include "runtime/error.h"

namespace meshflow::compress {
namespace {

// The symbol section: the symbols last first, each by a 6-symbol tree per replay context
// (nodes/compress/edgebreaker_replay.h), and where a component may start a bit saying whether it
// does.
struct SymbolModels {
  std::vector<SymbolModel<8>> symbol = std::vector<SymbolModel<8>>(ReverseReplay::kContexts);
  BitModel starts;
};

// Codes the walk's symbols; returns the surface the decoder will rebuild.
ReplayedSurface encode_symbols(const Traversal& walk, std::size_t vertices, RangeEncoder& enc) {
  const Connectivity& c = walk.connectivity;
  ReverseReplay replay(c.components, c.ops.size(), vertices, c.handles, "edgebreaker encoder");
  SymbolModels m;
  for (;;) {
    switch (replay.next()) {
      case ReverseReplay::Step::kSymbol: {
        const Op op = c.ops[replay.symbols_left() - 1];
        m.symbol[replay.context()].encode(enc, static_cast<unsigned>(op));
        replay.apply(op);
        break;
      }
      case ReverseReplay::Step::kComponentStart: {
        const bool starts =
            replay.symbols_left() == walk.component_first_symbol[replay.component()];
        enc.encode(m.starts, starts ? 1u : 0u);
        replay.answer(starts);
        break;
      }
      case ReverseReplay::Step::kDone:
        return replay.finish();
    }
  }
}

// Decodes the symbols while replaying them.
ReplayedSurface decode_symbols(std::uint32_t components, std::size_t symbols, std::size_t vertices,
                               const std::vector<HandleRecord>& handles, RangeDecoder& dec,
                               const std::string& source) {
  ReverseReplay replay(components, symbols, vertices, handles, source);
  SymbolModels m;
  {
    RangeDecoder::Session session(dec);  // the decoder's state in registers for the whole loop
    RangeDecoderCore& core = session.core;
    for (bool done = false; !done;) {
      switch (replay.next()) {
        case ReverseReplay::Step::kSymbol: {
          const unsigned v = m.symbol[replay.context()].decode(core);
          if (v >= kOpCount)
            throw Error(source, "connectivity symbol " + std::to_string(replay.symbols_left() - 1),
                        "unknown symbol " + std::to_string(v));
          replay.apply(static_cast<Op>(v));
          break;
        }
        case ReverseReplay::Step::kComponentStart:
          replay.answer(core.decode(m.starts) != 0);
          break;
        case ReverseReplay::Step::kDone:
          done = true;
          break;
      }
    }
  }  // the session stores the state back
  dec.check();
  return replay.finish();
}

// The side data's integer fields, each with its own model.
struct SideModels {
  IntegerModel count, depth, offset, index, corner;
};

// How a vertex's position is predicted: without parallelograms from what the gate gives; with
// them by the mean of the flagged ones (1, 2, 3 or more), or, all refused, by the gate's
// midpoint (a crease: kRefused).
enum Prediction {
  kPrevious = 0,
  kOne,
  kMidpoint,
  kParallelogram,
  kMean2,
  kMean3,
  kRefused,
  kPredictions
};

// Residuals are further split per axis by how much the vertex's parallelograms disagree on
// that axis (0, 1, 2-3, 4-7, 8 or more steps): where they agree (a plane along the axis) the
// residual is mostly zero.
// And by the extent of the gate's decoded corners along the axis (0, 1-3, 4-15, 16-63, 64 or more
// steps): a surface flat along an axis (a wall, a floor) keeps the new vertex on its plane.
constexpr std::size_t kSpreads = 5;
constexpr std::size_t kExtents = 5;
constexpr std::size_t kPositionContexts = kPredictions * kSpreads * kExtents;
constexpr std::array<std::size_t, 3> kPreviousContext = {0, 0, 0};  // kPrevious, no spread
constexpr unsigned kMaxParallelograms = ParallelogramRing::kMaxParallelograms;

// The residual context of one axis.
std::size_t spread_context(Prediction kind, std::int64_t spread, std::int64_t extent) {
  std::size_t s = 0;
  while (s + 1 < kSpreads && spread >= (std::int64_t{1} << s)) ++s;
  const std::size_t e = extent == 0 ? 0 : extent < 4 ? 1 : extent < 16 ? 2 : extent < 64 ? 3 : 4;
  return (static_cast<std::size_t>(kind) * kSpreads + s) * kExtents + e;
}

// Grid positions of decoded vertices (only those already coded are read).
using Grid = std::vector<std::array<std::int32_t, 3>>;

// The position section's models: residuals per axis and context, and the flags that say which
// parallelograms a vertex trusts (per count offered and position in the offer).
struct PositionModels {
  std::vector<std::array<IntegerModel, 3>> residual =
      std::vector<std::array<IntegerModel, 3>>(kPositionContexts);
  std::array<std::array<BitModel, kMaxParallelograms>, kMaxParallelograms> trusted{};
};

// What predicts decoded vertex k before its flags are read: the ring's parallelograms, their
// disagreement per axis, and the prediction without them.
struct Candidates {
  unsigned n = 0;
  ParallelogramRing::Parallelograms parallelogram;
  std::array<std::int64_t, 3> spread{};
  std::array<std::int64_t, 3> extent{};  // of the gate's decoded corners, per axis
  std::array<std::int32_t, 3> fallback{};
  Prediction fallback_kind = kPrevious;
};

// The candidates of vertex k from its gate predictors (skipping holes, `hole`) and the ring;
// `last` is the last coded position.
Candidates candidates(std::uint32_t k, const VertexPredictors& p, const ParallelogramRing& ring,
                      const std::vector<char>& hole, const Grid& grid,
                      const std::array<std::int32_t, 3>& last) {
  Candidates c;
  c.n = ring.gather(k, grid, c.parallelogram);
  for (std::size_t a = 0; a < 3 && c.n > 1; ++a) {
    std::int64_t low = c.parallelogram[0][a], high = low;
    for (unsigned i = 1; i < c.n; ++i) {
      low = std::min(low, c.parallelogram[i][a]);
      high = std::max(high, c.parallelogram[i][a]);
    }
    c.spread[a] = high - low;
  }
  const auto real = [&](std::uint32_t v) { return v != kNone && !hole[v]; };
  bool any = false;
  std::array<std::int64_t, 3> low{}, high{};
  for (std::uint32_t v : {p.a, p.b, p.w}) {
    if (!real(v)) continue;
    for (std::size_t a = 0; a < 3; ++a) {
      low[a] = any ? std::min<std::int64_t>(low[a], grid[v][a]) : grid[v][a];
      high[a] = any ? std::max<std::int64_t>(high[a], grid[v][a]) : grid[v][a];
    }
    any = true;
  }
  for (std::size_t a = 0; a < 3; ++a) c.extent[a] = high[a] - low[a];
  c.fallback = last;
  if (c.n == 0 && real(p.a) && real(p.b) && real(p.w)) {
    c.fallback_kind = kParallelogram;
    for (std::size_t i = 0; i < 3; ++i)
      c.fallback[i] =
          static_cast<std::int32_t>(std::int64_t{grid[p.a][i]} + grid[p.b][i] - grid[p.w][i]);
  } else if (real(p.a) && real(p.b)) {
    c.fallback_kind = kMidpoint;
    for (std::size_t i = 0; i < 3; ++i)
      c.fallback[i] = static_cast<std::int32_t>((std::int64_t{grid[p.a][i]} + grid[p.b][i]) / 2);
  } else if (real(p.a) || real(p.b)) {
    c.fallback_kind = kOne;
    c.fallback = grid[real(p.a) ? p.a : p.b];
  }
  if (c.n > 0) c.fallback_kind = kRefused;
  return c;
}

// The trust subsets the encoder tries when n parallelograms are offered: none, all, each one
// alone and all but one (every subset up to 3; 10 of the 16 for 4), each once. Trying all 16
// saved under 0.1 % of the position bytes and cost up to a third of the encoding time.
struct TrustChoices {
  unsigned count = 0;
  std::array<unsigned, 1u << kMaxParallelograms> mask{};
};

constexpr TrustChoices trust_choices(unsigned n) {
  TrustChoices t;
  if (n == 0) return t;
  const unsigned all = (1u << n) - 1;
  const auto add = [&t](unsigned mask) {
    for (unsigned i = 0; i < t.count; ++i)
      if (t.mask[i] == mask) return;
    t.mask[t.count++] = mask;
  };
  add(0);
  add(all);
  for (unsigned i = 0; i < n; ++i) add(1u << i);
  for (unsigned i = 0; i < n; ++i) add(all & ~(1u << i));
  return t;
}

constexpr std::array<TrustChoices, kMaxParallelograms + 1> kTrustChoices = {
    trust_choices(0), trust_choices(1), trust_choices(2), trust_choices(3), trust_choices(4)};
static_assert(kMaxParallelograms == 4, "kTrustChoices lists one entry per offer size");

// sum / n rounded half away from zero, n in 1 .. kMaxParallelograms: a division by a constant
// per case (a multiply and shifts; a 64-bit division by a variable takes tens of cycles, three
// per vertex and up to 30 per vertex in the encoder's trials).
std::int64_t rounded_mean(std::int64_t sum, std::int64_t n) {
  static_assert(kMaxParallelograms == 4, "rounded_mean() has a case per count");
  const std::int64_t half = n / 2, biased = sum >= 0 ? sum + half : sum - half;
  switch (n) {
    case 1:
      return sum;
    case 2:
      return biased / 2;
    case 3:
      return biased / 3;
    default:
      return biased / 4;
  }
}

// The prediction from the parallelograms `trusted` selects (bit i: parallelogram i), their
// rounded mean, or the fallback when none; sets each axis's residual context.
std::array<std::int32_t, 3> predict(const Candidates& c, unsigned trusted,
                                    std::array<std::size_t, 3>& context) {
  if (trusted == 0) {
    for (std::size_t a = 0; a < 3; ++a)
      context[a] = spread_context(c.fallback_kind, c.spread[a], c.extent[a]);
    return c.fallback;
  }
  std::array<std::int64_t, 3> sum{};
  std::int64_t n = 0;
  for (unsigned i = 0; i < c.n; ++i) {
    if (((trusted >> i) & 1u) == 0) continue;
    ++n;
    for (std::size_t a = 0; a < 3; ++a) sum[a] += c.parallelogram[i][a];
  }
  const Prediction kind = n == 1 ? kParallelogram : n == 2 ? kMean2 : kMean3;
  std::array<std::int32_t, 3> out;
  for (std::size_t a = 0; a < 3; ++a) {
    out[a] = static_cast<std::int32_t>(rounded_mean(sum[a], n));
    context[a] = spread_context(kind, c.spread[a], c.extent[a]);
  }
  return out;
}

void write_section(io::ByteWriter& out, const std::vector<unsigned char>& bytes) {
  out.u64(bytes.size());
  out.bytes(bytes.data(), bytes.size());
}

// What both sides derive from the replayed surface: each decoded vertex's fate.
struct VertexRoles {
  std::vector<char> hole;             // per decoded vertex
  std::vector<std::uint32_t> merged;  // per decoded vertex: the earlier one it is, or kNone
  std::vector<std::uint32_t> output;  // per decoded vertex: its output vertex (kNone: hole)
  std::uint32_t surface_outputs = 0;  // output vertices on the surface
};

VertexRoles assign_outputs(std::vector<char> hole, std::vector<std::uint32_t> merged) {
  VertexRoles r{std::move(hole), std::move(merged), {}, 0};
  r.output.assign(r.hole.size(), kNone);
  for (std::size_t k = 0; k < r.hole.size(); ++k) {
    if (r.hole[k]) continue;
    r.output[k] = r.merged[k] != kNone ? r.output[r.merged[k]] : r.surface_outputs++;
  }
  return r;
}

}  // namespace

BodyStats encode_body(const TriangleMesh& mesh, const Quantizer& quantizer, AttributeFlags flags,
                      io::ByteWriter& out, BodyOrder* order, BodyCodes* codes) {
  const ClosedSurface surface = build_closed_surface(mesh.triangles);
  const Traversal walk = edgebreaker_traverse(surface);
  const Connectivity& c = walk.connectivity;
  const std::size_t decoded = walk.surface_vertex.size();
  RangeEncoder symbol_encoder;
  const ReplayedSurface replayed = encode_symbols(walk, decoded, symbol_encoder);

  // Roles: holes, further fans of a vertex already met, outputs.
  std::vector<char> hole(decoded, 0);
  std::vector<std::uint32_t> merged(decoded, kNone);
  std::vector<std::uint32_t> first(mesh.vertices.size(), kNone);
  for (std::uint32_t k = 0; k < decoded; ++k) {
    const std::uint32_t v = surface.input_vertex[walk.surface_vertex[k]];
    if (v == kNone) {
      hole[k] = 1;
    } else if (first[v] != kNone) {
      merged[k] = first[v];
    } else {
      first[v] = k;
    }
  }
  const VertexRoles roles = assign_outputs(hole, merged);
  std::vector<std::uint32_t> off_surface;
  for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v)
    if (first[v] == kNone) off_surface.push_back(v);
  std::vector<std::uint32_t> output_of_input(mesh.vertices.size(), kNone);
  BodyOrder local;
  BodyOrder& o = order != nullptr ? *order : local;
  o.vertex.clear();
  for (std::uint32_t k = 0; k < decoded; ++k)
    if (!hole[k] && merged[k] == kNone)
      o.vertex.push_back(surface.input_vertex[walk.surface_vertex[k]]);
  o.vertex.insert(o.vertex.end(), off_surface.begin(), off_surface.end());
  for (std::uint32_t i = 0; i < o.vertex.size(); ++i) output_of_input[o.vertex[i]] = i;
  o.triangle.clear();
  for (std::uint32_t t : walk.surface_triangle)
    if (surface.input_triangle[t] != kNone) o.triangle.push_back(surface.input_triangle[t]);
  o.triangle.insert(o.triangle.end(), surface.degenerate_triangles.begin(),
                    surface.degenerate_triangles.end());

  BodyStats stats;
  stats.symbols = c.ops.size();
  stats.holes = surface.hole_count;
  stats.handles = c.handles.size();
  out.u32(c.components);
  out.u64(c.ops.size());
  out.u64(decoded);

  {  // Side data (the decoder needs the handles before the symbols).
    RangeEncoder enc;
    SideModels m;
    const auto put = [&](IntegerModel& model, std::uint64_t v) {
      model.encode(enc, static_cast<std::int32_t>(v));
    };
    put(m.count, c.handles.size());
    for (const HandleRecord& h : c.handles) {
      put(m.depth, h.depth);
      put(m.offset, h.offset);
      put(m.offset, h.length);
    }
    put(m.count, surface.hole_count);
    std::uint32_t previous = 0;
    for (std::uint32_t k = 0; k < decoded; ++k)
      if (hole[k]) {
        put(m.index, k - previous);
        previous = k;
      }
    std::size_t merges = 0;
    for (std::uint32_t k = 0; k < decoded; ++k) merges += merged[k] != kNone;
    stats.merged_fans = merges;
    put(m.count, merges);
    previous = 0;
    for (std::uint32_t k = 0; k < decoded; ++k)
      if (merged[k] != kNone) {
        put(m.index, k - previous);
        put(m.offset, k - merged[k]);
        previous = k;
      }
    put(m.count, off_surface.size());
    put(m.count, surface.degenerate_triangles.size());
    for (std::uint32_t t : surface.degenerate_triangles)
      for (std::uint32_t v : mesh.triangles[t]) put(m.corner, output_of_input[v]);
    const std::vector<unsigned char> bytes = enc.finish();
    stats.connectivity_bytes += bytes.size();
    write_section(out, bytes);
  }
  {  // Symbols.
    const std::vector<unsigned char> bytes = symbol_encoder.finish();
    stats.connectivity_bytes += bytes.size();
    write_section(out, bytes);
  }
  {  // Positions: one stream per axis (the decoder's three chains then overlap); a vertex's
     // trust flags go first on the x stream. The encoder flags the subset of the offered
     // parallelograms whose residuals and flags cost least under the models as they stand.
    const ParallelogramRing ring(replayed.triangles, hole, decoded);
    RangeEncoder enc[3];
    PositionModels m;
    Grid grid(decoded);
    std::array<std::int32_t, 3> last{};
    const auto code = [&](const std::array<std::int32_t, 3>& q,
                          const std::array<std::int32_t, 3>& predicted,
                          const std::array<std::size_t, 3>& context) {
      for (std::size_t a = 0; a < 3; ++a)
        m.residual[context[a]][a].encode(enc[a], q[a] - predicted[a]);
      last = q;
    };
    for (std::uint32_t k = 0; k < decoded; ++k) {
      if (hole[k]) continue;
      if (merged[k] != kNone) {
        grid[k] = grid[merged[k]];
        continue;
      }
      const std::array<std::int32_t, 3> q =
          quantizer.quantize(mesh.vertices[surface.input_vertex[walk.surface_vertex[k]]]);
      const Candidates offer = candidates(k, replayed.predictors[k], ring, hole, grid, last);
      unsigned best = 0;
      std::uint32_t best_cost = ~0u;
      std::array<std::size_t, 3> context;
      const TrustChoices& choices = kTrustChoices[offer.n];
      for (unsigned choice = 0; choice < choices.count; ++choice) {
        const unsigned trusted = choices.mask[choice];
        const std::array<std::int32_t, 3> predicted = predict(offer, trusted, context);
        std::uint32_t cost = 0;
        for (unsigned i = 0; i < offer.n; ++i)
          cost += bit_cost(m.trusted[offer.n - 1][i], (trusted >> i) & 1u);
        for (std::size_t a = 0; a < 3; ++a)
          cost += m.residual[context[a]][a].cost(q[a] - predicted[a]);
        if (cost < best_cost) {
          best_cost = cost;
          best = trusted;
        }
      }
      for (unsigned i = 0; i < offer.n; ++i)
        enc[0].encode(m.trusted[offer.n - 1][i], (best >> i) & 1u);
      stats.trusted_parallelograms += static_cast<std::size_t>(__builtin_popcount(best));
      stats.offered_parallelograms += offer.n;
      const std::array<std::int32_t, 3> predicted = predict(offer, best, context);
      grid[k] = q;
      code(q, predicted, context);
    }
    for (std::uint32_t v : off_surface)
      code(quantizer.quantize(mesh.vertices[v]), last, kPreviousContext);
    for (RangeEncoder& e : enc) {
      const std::vector<unsigned char> bytes = e.finish();
      stats.position_bytes += bytes.size();
      write_section(out, bytes);
    }
  }
  {  // Attributes (nodes/compress/attribute_coder.h), predicted from the decoded geometry.
    std::vector<std::array<std::int32_t, 3>> grid(o.vertex.size());
    for (std::size_t i = 0; i < o.vertex.size(); ++i)
      grid[i] = quantizer.quantize(mesh.vertices[o.vertex[i]]);
    std::vector<Triangle> triangles(o.triangle.size());
    for (std::size_t k = 0; k < o.triangle.size(); ++k)
      for (std::size_t j = 0; j < 3; ++j)
        triangles[k][j] = output_of_input[mesh.triangles[o.triangle[k]][j]];
    const DecodedGeometry geometry{grid, triangles};
    RangeEncoder enc;
    out.u8(static_cast<std::uint8_t>(flags.normals ? flags.normal_bits : 0));
    std::vector<Eigen::Vector3f> decoded_normals;
    if (flags.normals) {
      std::vector<Eigen::Vector3f> normals(o.vertex.size());
      for (std::size_t i = 0; i < o.vertex.size(); ++i) normals[i] = mesh.normals[o.vertex[i]];
      decoded_normals = encode_normals(geometry, normals, flags.normal_bits, enc);
    }
    if (flags.colors) {
      std::vector<Rgb8> colors(o.vertex.size());
      for (std::size_t i = 0; i < o.vertex.size(); ++i) colors[i] = mesh.colors[o.vertex[i]];
      encode_colors(geometry, colors, enc);
    }
    const std::vector<unsigned char> bytes = enc.finish();
    stats.attribute_bytes = bytes.size();
    write_section(out, bytes);
    if (codes != nullptr) {
      codes->positions = std::move(grid);
      codes->normals = std::move(decoded_normals);
      codes->normal_bits = flags.normals ? flags.normal_bits : 0;
    }
  }
  return stats;
}

TriangleMesh decode_body(io::ByteReader& in, const Quantizer& quantizer, AttributeFlags flags,
                         const std::string& source, BodyCodes* codes) {
  Connectivity c;
  c.components = in.u32("components");
  const std::uint64_t symbols = in.u64("symbol count");
  const std::uint64_t decoded = in.u64("surface vertex count");
  const auto section = [&](const char* field) {
    const std::uint64_t n = in.u64(field);
    if (n > in.remaining())
      in.fail(field, "section of " + std::to_string(n) + " bytes, " +
                         std::to_string(in.remaining()) + " left (truncated)");
    return std::make_pair(in.bytes(static_cast<std::size_t>(n), field),
                          static_cast<std::size_t>(n));
  };
  const auto [side_bytes, side_size] = section("side section");
  const auto [symbol_bytes, symbol_size] = section("symbol section");
  // A symbol costs at least 3 x 0.022 bits; more symbols than the section can hold is corrupt
  // (and would allocate without bound).
  if (symbols > 128 * std::uint64_t{symbol_size} + 64 ||
      decoded > 3 * symbols + 3 * c.components + 3 || c.components > symbols + 1)
    in.fail("symbol count", std::to_string(symbols) + " symbols, " + std::to_string(decoded) +
                                " vertices and " + std::to_string(c.components) +
                                " components do not fit a section of " +
                                std::to_string(symbol_size) + " bytes");
  std::vector<char> hole(static_cast<std::size_t>(decoded), 0);
  std::vector<std::uint32_t> merged(static_cast<std::size_t>(decoded), kNone);
  std::uint64_t off_surface = 0;
  std::vector<std::uint32_t> degenerate;
  {
    RangeDecoder dec(side_bytes, side_size, source, "side section");
    SideModels m;
    const auto get = [&](IntegerModel& model, const char* field, std::uint64_t limit) {
      const std::int32_t v = model.decode(dec);
      dec.check();
      if (v < 0 || static_cast<std::uint64_t>(v) > limit)
        throw Error(source, std::string("side section: ") + field,
                    std::to_string(v) + " is outside 0 .. " + std::to_string(limit));
      return static_cast<std::uint32_t>(v);
    };
    c.handles.resize(get(m.count, "handle count", symbols));
    for (HandleRecord& h : c.handles) {
      h.depth = get(m.depth, "handle depth", symbols);
      h.offset = get(m.offset, "handle offset", 3 * symbols + 3);
      h.length = get(m.offset, "handle loop length", 3 * symbols + 3);
    }
    const std::uint32_t holes = get(m.count, "hole count", decoded);
    std::uint32_t previous = 0;
    for (std::uint32_t i = 0; i < holes; ++i) {
      const std::uint64_t k = std::uint64_t{previous} + get(m.index, "hole vertex", decoded);
      if (k >= decoded || (i > 0 && k == previous))
        throw Error(source, "side section: hole vertex", "out of order or range");
      hole[k] = 1;
      previous = static_cast<std::uint32_t>(k);
    }
    const std::uint32_t merges = get(m.count, "merge count", decoded);
    previous = 0;
    for (std::uint32_t i = 0; i < merges; ++i) {
      const std::uint64_t k = std::uint64_t{previous} + get(m.index, "merged vertex", decoded);
      const std::uint32_t back = get(m.offset, "merge target", decoded);
      if (k >= decoded || back == 0 || back > k || hole[k] || hole[k - back] ||
          merged[k - back] != kNone || (i > 0 && k == previous))
        throw Error(source, "side section: merged vertex", "out of order or range");
      merged[k] = static_cast<std::uint32_t>(k - back);
      previous = static_cast<std::uint32_t>(k);
    }
    off_surface = get(m.count, "vertices off the surface", 0x7FFFFFFF);
    if (off_surface > 3 * in.remaining() + 64)
      throw Error(source, "side section: vertices off the surface",
                  std::to_string(off_surface) + " do not fit the rest of the file");
    const std::uint32_t degenerates = get(m.count, "degenerate triangles", 0x7FFFFFFF);
    if (degenerates > 8 * side_size + 64)
      throw Error(source, "side section: degenerate triangles", "more than the section holds");
    degenerate.resize(3 * std::size_t{degenerates});
    for (std::uint32_t& v : degenerate) v = get(m.corner, "degenerate triangle corner", 0x7FFFFFFF);
  }
  RangeDecoder symbol_decoder(symbol_bytes, symbol_size, source, "symbol section");
  const ReplayedSurface replayed =
      decode_symbols(c.components, static_cast<std::size_t>(symbols),
                     static_cast<std::size_t>(decoded), c.handles, symbol_decoder, source);
  const VertexRoles roles = assign_outputs(std::move(hole), std::move(merged));
  const std::size_t outputs = roles.surface_outputs + static_cast<std::size_t>(off_surface);
  TriangleMesh mesh;
  mesh.vertices.resize(outputs);
  std::vector<std::array<std::int32_t, 3>> grid_out(outputs);  // per output vertex
  {
    const ParallelogramRing ring(replayed.triangles, roles.hole, static_cast<std::size_t>(decoded));
    const auto [x_bytes, x_size] = section("position section x");
    const auto [y_bytes, y_size] = section("position section y");
    const auto [z_bytes, z_size] = section("position section z");
    RangeDecoder dec[3] = {RangeDecoder(x_bytes, x_size, source, "position section x"),
                           RangeDecoder(y_bytes, y_size, source, "position section y"),
                           RangeDecoder(z_bytes, z_size, source, "position section z")};
    PositionModels m;
    Grid grid(static_cast<std::size_t>(decoded));
    std::array<std::int32_t, 3> last{};
    // The three decoders' states stay in registers for the whole loop (stored back, and then
    // checked, when the sessions end).
    std::optional<RangeDecoder::Session> sx(std::in_place, dec[0]), sy(std::in_place, dec[1]),
        sz(std::in_place, dec[2]);
    RangeDecoderCore &cx = sx->core, &cy = sy->core, &cz = sz->core;
    const auto read = [&](const std::array<std::int32_t, 3>& predicted,
                          const std::array<std::size_t, 3>& context) {
      const std::array<std::int32_t, 3> residual =
          IntegerModel::decode_three(m.residual[context[0]][0], m.residual[context[1]][1],
                                     m.residual[context[2]][2], cx, cy, cz);
      std::array<std::int32_t, 3> q{};
      for (std::size_t a = 0; a < 3; ++a)
        q[a] = static_cast<std::int32_t>(static_cast<std::uint32_t>(predicted[a]) +
                                         static_cast<std::uint32_t>(residual[a]));
      last = q;
      return q;
    };
    for (std::uint32_t k = 0; k < decoded; ++k) {
      if (roles.hole[k]) continue;
      if (roles.merged[k] != kNone) {
        grid[k] = grid[roles.merged[k]];
        continue;
      }
      const Candidates offer = candidates(k, replayed.predictors[k], ring, roles.hole, grid, last);
      unsigned trusted = 0;
      for (unsigned i = 0; i < offer.n; ++i) trusted |= cx.decode(m.trusted[offer.n - 1][i]) << i;
      std::array<std::size_t, 3> context;
      const std::array<std::int32_t, 3> predicted = predict(offer, trusted, context);
      grid[k] = read(predicted, context);
      mesh.vertices[roles.output[k]] = quantizer.position(grid[k]);
      grid_out[roles.output[k]] = grid[k];
    }
    for (std::size_t i = roles.surface_outputs; i < outputs; ++i) {
      const std::array<std::int32_t, 3> q = read(last, kPreviousContext);
      mesh.vertices[i] = quantizer.position(q);
      grid_out[i] = q;
    }
    sx.reset();
    sy.reset();
    sz.reset();
    for (const RangeDecoder& d : dec) d.check();
  }
  mesh.triangles.reserve(replayed.triangles.size() + degenerate.size() / 3);
  for (const Triangle& t : replayed.triangles) {
    if (roles.hole[t[0]] || roles.hole[t[1]] || roles.hole[t[2]]) continue;
    mesh.triangles.push_back({roles.output[t[0]], roles.output[t[1]], roles.output[t[2]]});
  }
  for (std::size_t i = 0; i < degenerate.size(); i += 3) {
    for (std::size_t j = 0; j < 3; ++j)
      if (degenerate[i + j] >= outputs)
        throw Error(source, "side section: degenerate triangle corner",
                    std::to_string(degenerate[i + j]) + " is not below the " +
                        std::to_string(outputs) + " vertices");
    mesh.triangles.push_back({degenerate[i], degenerate[i + 1], degenerate[i + 2]});
  }
  const unsigned normal_bits = in.u8("normal bits");
  {
    if (flags.normals && (normal_bits < kMinNormalBits || normal_bits > kMaxNormalBits))
      in.fail("normal bits", std::to_string(normal_bits) + " is not " +
                                 std::to_string(kMinNormalBits) + " .. " +
                                 std::to_string(kMaxNormalBits));
    if (!flags.normals && normal_bits != 0)
      in.fail("normal bits", std::to_string(normal_bits) + " but the header flags no normals");
    const auto [bytes, size] = section("attribute section");
    RangeDecoder dec(bytes, size, source, "attribute section");
    const DecodedGeometry geometry{grid_out, mesh.triangles};
    if (flags.normals) mesh.normals = decode_normals(geometry, normal_bits, dec);
    if (flags.colors) mesh.colors = decode_colors(geometry, dec);
    dec.check();
  }
  if (codes != nullptr) {
    codes->positions = std::move(grid_out);
    codes->normals = mesh.normals;
    codes->normal_bits = normal_bits;
  }
  return mesh;
}

}  // namespace meshflow::compress
