#include "nodes/compress/mesh_codec.h"

#include <algorithm>

#include "nodes/compress/attribute_coder.h"
#include "nodes/compress/closed_surface.h"
#include "nodes/compress/color_coder.h"
#include "nodes/compress/coordinate_snap.h"
#include "nodes/compress/edgebreaker_connectivity.h"
#include "nodes/compress/edgebreaker_replay.h"
#include "nodes/compress/parallelogram_ring.h"
#include "nodes/compress/range_coder.h"
#include "nodes/compress/side_by_side.h"
#include "nodes/compress/vertex_adjacency.h"
#include "runtime/error.h"

namespace meshflow::compress {
namespace {

// The symbol section: the symbols last first, each by an adaptive choice of 6 (of 8) per replay
// context (nodes/compress/edgebreaker_replay.h), and where a component may start a bit saying
// whether it does. Each symbol holds at least 24 of the 2^15 parts: a symbol costs at least
// -log2(1 - 7 x 24 / 2^15) = 0.0074 bits, so a section of B bytes holds at most 1079 B symbols
// (decode_body() refuses more before allocating for them).
constexpr std::uint32_t kSymbolFloor = 24;
constexpr std::uint64_t kSymbolsPerByte = 1200;
using OpModel = FrequencyModel<8, kSymbolFloor>;
struct SymbolModels {
  std::vector<OpModel> symbol = std::vector<OpModel>(ReverseReplay::kContexts);
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

// The number of significant bits of v >= 0 (0 for 0).
unsigned bit_length64(std::int64_t v) {
  return v == 0 ? 0u : 64u - static_cast<unsigned>(__builtin_clzll(static_cast<std::uint64_t>(v)));
}

// The spread and extent part of one axis's residual context (kind_context() adds the kind):
// spread 0, 1, 2-3, 4-7, 8+ and extent 0, 1-3, 4-15, 16-63, 64+ by their bit lengths.
std::size_t shape_context(std::int64_t spread, std::int64_t extent) {
  const unsigned s = std::min(bit_length64(spread), 4u);
  const unsigned e = std::min((bit_length64(extent) + 1) / 2, 4u);
  return s * kExtents + e;
}

// The residual context of one axis from its shape_context().
std::size_t kind_context(Prediction kind, std::size_t shape) {
  return static_cast<std::size_t>(kind) * kSpreads * kExtents + shape;
}

// Grid positions of decoded vertices (only those already coded are read).
using Grid = std::vector<std::array<std::int32_t, 3>>;

// The position section's models: residuals per axis and context, and which parallelograms a
// vertex trusts (the subset as one choice, per count offered).
struct PositionModels {
  std::vector<std::array<IntegerModel, 3>> residual =
      std::vector<std::array<IntegerModel, 3>>(kPositionContexts);
  std::array<FrequencyModel<1u << kMaxParallelograms>, kMaxParallelograms> trusted{};
};

// What predicts decoded vertex k before its flags are read: the ring's parallelograms, their
// disagreement per axis, and the prediction without them.
struct Candidates {
  unsigned n = 0;
  ParallelogramRing::Parallelograms parallelogram;
  std::array<std::size_t, 3> shape{};  // shape_context() per axis
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
  std::array<std::int64_t, 3> spread{};  // how much the parallelograms disagree, per axis
  if (c.n > 1)
    for (std::size_t a = 0; a < 3; ++a) {
      std::int64_t low = c.parallelogram[0][a], high = low;
      for (unsigned i = 1; i < c.n; ++i) {
        low = std::min(low, c.parallelogram[i][a]);
        high = std::max(high, c.parallelogram[i][a]);
      }
      spread[a] = high - low;
    }
  const auto real = [&](std::uint32_t v) { return v != kNone && !hole[v]; };
  const bool ra = real(p.a), rb = real(p.b), rw = real(p.w);
  // The extent of the gate's decoded corners per axis.
  std::array<const std::array<std::int32_t, 3>*, 3> corner{};
  unsigned corners = 0;
  if (ra) corner[corners++] = &grid[p.a];
  if (rb) corner[corners++] = &grid[p.b];
  if (rw) corner[corners++] = &grid[p.w];
  for (std::size_t a = 0; a < 3; ++a) {
    std::int64_t low = 0, high = 0;
    if (corners > 0) {
      low = high = (*corner[0])[a];
      for (unsigned i = 1; i < corners; ++i) {
        low = std::min<std::int64_t>(low, (*corner[i])[a]);
        high = std::max<std::int64_t>(high, (*corner[i])[a]);
      }
    }
    c.shape[a] = shape_context(spread[a], high - low);
  }
  c.fallback = last;
  if (c.n == 0 && ra && rb && rw) {
    c.fallback_kind = kParallelogram;
    for (std::size_t i = 0; i < 3; ++i)
      c.fallback[i] =
          static_cast<std::int32_t>(std::int64_t{grid[p.a][i]} + grid[p.b][i] - grid[p.w][i]);
  } else if (ra && rb) {
    c.fallback_kind = kMidpoint;
    for (std::size_t i = 0; i < 3; ++i)
      c.fallback[i] = static_cast<std::int32_t>((std::int64_t{grid[p.a][i]} + grid[p.b][i]) / 2);
  } else if (ra || rb) {
    c.fallback_kind = kOne;
    c.fallback = grid[ra ? p.a : p.b];
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
std::int64_t rounded_mean(std::int64_t sum, unsigned n) {
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

// The mean of `n` >= 1 trusted parallelograms whose coordinates sum to `sum`, rounded; sets each
// axis's residual context.
std::array<std::int32_t, 3> mean_prediction(const Candidates& c,
                                            const std::array<std::int64_t, 3>& sum, unsigned n,
                                            std::array<std::size_t, 3>& context) {
  const Prediction kind = n == 1 ? kParallelogram : n == 2 ? kMean2 : kMean3;
  std::array<std::int32_t, 3> out;
  for (std::size_t a = 0; a < 3; ++a) {
    out[a] = static_cast<std::int32_t>(rounded_mean(sum[a], n));
    context[a] = kind_context(kind, c.shape[a]);
  }
  return out;
}

// The prediction without trusted parallelograms: the fallback; sets the contexts.
std::array<std::int32_t, 3> fallback_prediction(const Candidates& c,
                                                std::array<std::size_t, 3>& context) {
  for (std::size_t a = 0; a < 3; ++a) context[a] = kind_context(c.fallback_kind, c.shape[a]);
  return c.fallback;
}

// The prediction from the parallelograms `trusted` selects (bit i: parallelogram i), their
// rounded mean, or the fallback when none; sets each axis's residual context.
std::array<std::int32_t, 3> predict(const Candidates& c, unsigned trusted,
                                    std::array<std::size_t, 3>& context) {
  if (trusted == 0) return fallback_prediction(c, context);
  std::array<std::int64_t, 3> sum{};
  unsigned n = 0;
  for (unsigned i = 0; i < c.n; ++i) {
    if (((trusted >> i) & 1u) == 0) continue;
    ++n;
    for (std::size_t a = 0; a < 3; ++a) sum[a] += c.parallelogram[i][a];
  }
  return mean_prediction(c, sum, n, context);
}

// The coordinate sums of every subset of the offered parallelograms (index: the subset's mask),
// each from a smaller one: the encoder's trials read them instead of summing per trial.
using SubsetSums = std::array<std::array<std::int64_t, 3>, 1u << kMaxParallelograms>;
// The number of parallelograms in each subset (mask).
constexpr std::array<unsigned, 1u << kMaxParallelograms> kSubsetSize = {0, 1, 1, 2, 1, 2, 2, 3,
                                                                        1, 2, 2, 3, 2, 3, 3, 4};
void subset_sums(const Candidates& c, SubsetSums& sums) {
  sums[0] = {0, 0, 0};
  for (unsigned mask = 1; mask < (1u << c.n); ++mask) {
    const auto low = static_cast<unsigned>(__builtin_ctz(mask));
    for (std::size_t a = 0; a < 3; ++a)
      sums[mask][a] = sums[mask & (mask - 1)][a] + c.parallelogram[low][a];
  }
}

// The snap candidates of a vertex predicted at `predicted` on its three axes.
SnapModels::Axes snap_axes(const SnapNeighbours& nb, const std::array<std::int32_t, 3>& predicted) {
  return {snap_candidates(nb, 0, predicted[0]), snap_candidates(nb, 1, predicted[1]),
          snap_candidates(nb, 2, predicted[2])};
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

namespace {

// The side section: handles, hole and merged vertices (per decoded vertex), the count of
// vertices off the surface, the degenerate triangles (`mesh`'s, in output vertex numbers).
std::vector<unsigned char> encode_side(const Connectivity& c, std::uint32_t hole_count,
                                       const VertexRoles& roles, std::size_t off_surface,
                                       const TriangleMesh& mesh,
                                       const std::vector<std::uint32_t>& degenerate_triangles,
                                       const std::vector<std::uint32_t>& output_of_input) {
  RangeEncoder enc;
  SideModels m;
  const auto put = [&](IntegerModel& model, std::uint64_t v) {
    model.encode(enc, static_cast<std::int32_t>(v));
  };
  const auto decoded = static_cast<std::uint32_t>(roles.hole.size());
  put(m.count, c.handles.size());
  for (const HandleRecord& h : c.handles) {
    put(m.depth, h.depth);
    put(m.offset, h.offset);
    put(m.offset, h.length);
  }
  put(m.count, hole_count);
  std::uint32_t previous = 0;
  for (std::uint32_t k = 0; k < decoded; ++k)
    if (roles.hole[k]) {
      put(m.index, k - previous);
      previous = k;
    }
  std::size_t merges = 0;
  for (std::uint32_t k = 0; k < decoded; ++k) merges += roles.merged[k] != kNone;
  put(m.count, merges);
  previous = 0;
  for (std::uint32_t k = 0; k < decoded; ++k)
    if (roles.merged[k] != kNone) {
      put(m.index, k - previous);
      put(m.offset, k - roles.merged[k]);
      previous = k;
    }
  put(m.count, off_surface);
  put(m.count, degenerate_triangles.size());
  for (std::uint32_t t : degenerate_triangles)
    for (std::uint32_t v : mesh.triangles[t]) put(m.corner, output_of_input[v]);
  return enc.finish();
}

// The three position sections: the surface vertices (decoded vertex k is input vertex
// input_of_decoded[k]) in decoding order, then `off_surface`. The encoder flags the subset of
// the offered parallelograms whose residuals and choice cost least under the models as they
// stand. Adds to `stats`; returns the grid positions per output vertex.
std::vector<std::array<std::int32_t, 3>> encode_positions(
    const TriangleMesh& mesh, const Quantizer& quantizer, const ReplayedSurface& replayed,
    const VertexRoles& roles, const std::vector<std::uint32_t>& input_of_decoded,
    const std::vector<std::uint32_t>& off_surface, io::ByteWriter& out, BodyStats& stats) {
  const auto decoded = static_cast<std::uint32_t>(roles.hole.size());
  std::vector<std::array<std::int32_t, 3>> grid_out(roles.surface_outputs + off_surface.size());
  const ParallelogramRing ring(replayed.diamonds, roles.hole, decoded);
  RangeEncoder enc[3];
  PositionModels m;
  SnapModels snap;
  SnapNeighbourhood neighbourhood(decoded);
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
    if (roles.hole[k]) continue;
    if (roles.merged[k] != kNone) {
      grid[k] = grid[roles.merged[k]];
      continue;
    }
    const std::array<std::int32_t, 3> q = quantizer.quantize(mesh.vertices[input_of_decoded[k]]);
    const Candidates offer = candidates(k, replayed.predictors[k], ring, roles.hole, grid, last);
    const SnapNeighbours& nb =
        neighbourhood.gather(k, replayed.predictors[k], ring, roles.hole, grid);
    // Only the coordinates no neighbour shares pay a residual; one that does costs least when
    // predicted exactly (about a bit more otherwise).
    std::array<bool, 3> free{};
    for (std::size_t a = 0; a < 3; ++a) free[a] = !shares_value(nb, a, q[a]);
    unsigned best = 0;
    std::uint32_t best_cost = ~0u;
    std::array<std::size_t, 3> context;
    const TrustChoices& choices = kTrustChoices[offer.n];
    SubsetSums sums;
    subset_sums(offer, sums);
    for (unsigned choice = 0; choice < choices.count; ++choice) {
      const unsigned trusted = choices.mask[choice];
      std::uint32_t cost = m.trusted[offer.n - 1].cost(trusted);  // n > 0: there are choices
      // Residual costs only add: a choice whose flag alone costs as much as the best cannot
      // beat it (the same choice as pricing it in full, fewer trials).
      if (cost >= best_cost) continue;
      const std::array<std::int32_t, 3> predicted =
          trusted == 0 ? fallback_prediction(offer, context)
                       : mean_prediction(offer, sums[trusted], kSubsetSize[trusted], context);
      for (std::size_t a = 0; a < 3; ++a)
        cost += free[a]                ? m.residual[context[a]][a].cost(q[a] - predicted[a])
                : q[a] == predicted[a] ? 0u
                                       : 16u;
      if (cost < best_cost) {
        best_cost = cost;
        best = trusted;
      }
    }
    if (offer.n > 0) m.trusted[offer.n - 1].encode(enc[0], best);
    // A table, not __builtin_popcount: the baseline ISA has no popcnt (a libgcc call).
    stats.trusted_parallelograms += kSubsetSize[best];
    stats.offered_parallelograms += offer.n;
    const std::array<std::int32_t, 3> predicted = predict(offer, best, context);
    const unsigned snapped = snap.encode(enc[0], snap_axes(nb, predicted), q);
    for (std::size_t a = 0; a < 3; ++a) {
      if ((snapped >> a) & 1u) {
        ++stats.snapped_coordinates;
        continue;
      }
      m.residual[context[a]][a].encode(enc[a], q[a] - predicted[a]);
    }
    last = q;
    grid[k] = q;
    grid_out[roles.output[k]] = q;
  }
  for (std::size_t j = 0; j < off_surface.size(); ++j) {
    const std::array<std::int32_t, 3> q = quantizer.quantize(mesh.vertices[off_surface[j]]);
    grid_out[roles.surface_outputs + j] = q;
    code(q, last, kPreviousContext);
  }
  for (RangeEncoder& e : enc) {
    const std::vector<unsigned char> bytes = e.finish();
    stats.position_bytes += bytes.size();
    write_section(out, bytes);
  }
  return grid_out;
}

// The normal bits and the attribute section (nodes/compress/attribute_coder.h), predicted from
// the geometry the decoder will have (output order `o`, grid positions `grid`). Sets `codes` if
// given.
void encode_attributes(const TriangleMesh& mesh, std::vector<std::array<std::int32_t, 3>> grid,
                       AttributeFlags flags, const BodyOrder& o,
                       const std::vector<std::uint32_t>& output_of_input, io::ByteWriter& out,
                       BodyStats& stats, BodyCodes* codes) {
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
    decoded_normals = encode_normals(geometry, normals, flags.normal_step, enc);
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
  std::vector<std::uint32_t> input_of_decoded(decoded);
  std::vector<char> hole(decoded, 0);
  std::vector<std::uint32_t> merged(decoded, kNone);
  std::vector<std::uint32_t> first(mesh.vertices.size(), kNone);
  for (std::uint32_t k = 0; k < decoded; ++k) {
    const std::uint32_t v = surface.input_vertex[walk.surface_vertex[k]];
    input_of_decoded[k] = v;
    if (v == kNone) {
      hole[k] = 1;
    } else if (first[v] != kNone) {
      merged[k] = first[v];
    } else {
      first[v] = k;
    }
  }
  const VertexRoles roles = assign_outputs(std::move(hole), std::move(merged));
  std::vector<std::uint32_t> off_surface;
  for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v)
    if (first[v] == kNone) off_surface.push_back(v);
  std::vector<std::uint32_t> output_of_input(mesh.vertices.size(), kNone);
  BodyOrder local;
  BodyOrder& o = order != nullptr ? *order : local;
  o.vertex.clear();
  for (std::uint32_t k = 0; k < decoded; ++k)
    if (!roles.hole[k] && roles.merged[k] == kNone) o.vertex.push_back(input_of_decoded[k]);
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
  for (std::uint32_t m : roles.merged) stats.merged_fans += m != kNone;
  out.u32(c.components);
  out.u64(c.ops.size());
  out.u64(decoded);
  // Side data first (the decoder needs the handles before the symbols).
  const std::vector<unsigned char> side =
      encode_side(c, surface.hole_count, roles, off_surface.size(), mesh,
                  surface.degenerate_triangles, output_of_input);
  const std::vector<unsigned char> symbols = symbol_encoder.finish();
  stats.connectivity_bytes = side.size() + symbols.size();
  write_section(out, side);
  write_section(out, symbols);
  std::vector<std::array<std::int32_t, 3>> grid =
      encode_positions(mesh, quantizer, replayed, roles, input_of_decoded, off_surface, out, stats);
  encode_attributes(mesh, std::move(grid), flags, o, output_of_input, out, stats, codes);
  return stats;
}

namespace {

// A section of a body: its bytes (in the reader's data) and size.
struct Section {
  const unsigned char* bytes;
  std::size_t size;
};

// Reads a section's u64 byte count and its bytes; `field` names it in errors.
Section read_section(io::ByteReader& in, const char* field) {
  const std::uint64_t n = in.u64(field);
  if (n > in.remaining())
    in.fail(field, "section of " + std::to_string(n) + " bytes, " + std::to_string(in.remaining()) +
                       " left (truncated)");
  return {in.bytes(static_cast<std::size_t>(n), field), static_cast<std::size_t>(n)};
}

// What the side section holds.
struct SideData {
  std::vector<HandleRecord> handles;
  std::vector<char> hole;                 // per decoded vertex
  std::vector<std::uint32_t> merged;      // per decoded vertex: the earlier one it is, or kNone
  std::uint64_t off_surface = 0;          // vertices on no triangle
  std::vector<std::uint32_t> degenerate;  // three output corners per triangle
};

// Reads the side section of a body of `symbols` symbols and `decoded` surface vertices;
// `remaining`: the bytes of the body after it (which must hold the vertices off the surface).
SideData decode_side(Section section, std::uint64_t symbols, std::uint64_t decoded,
                     std::size_t remaining, const std::string& source) {
  SideData side;
  side.hole.assign(static_cast<std::size_t>(decoded), 0);
  side.merged.assign(static_cast<std::size_t>(decoded), kNone);
  RangeDecoder dec(section.bytes, section.size, source, "side section");
  SideModels m;
  const auto get = [&](IntegerModel& model, const char* field, std::uint64_t limit) {
    const std::int32_t v = model.decode(dec);
    dec.check();
    if (v < 0 || static_cast<std::uint64_t>(v) > limit)
      throw Error(source, std::string("side section: ") + field,
                  std::to_string(v) + " is outside 0 .. " + std::to_string(limit));
    return static_cast<std::uint32_t>(v);
  };
  side.handles.resize(get(m.count, "handle count", symbols));
  for (HandleRecord& h : side.handles) {
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
    side.hole[k] = 1;
    previous = static_cast<std::uint32_t>(k);
  }
  const std::uint32_t merges = get(m.count, "merge count", decoded);
  previous = 0;
  for (std::uint32_t i = 0; i < merges; ++i) {
    const std::uint64_t k = std::uint64_t{previous} + get(m.index, "merged vertex", decoded);
    const std::uint32_t back = get(m.offset, "merge target", decoded);
    if (k >= decoded || back == 0 || back > k || side.hole[k] || side.hole[k - back] ||
        side.merged[k - back] != kNone || (i > 0 && k == previous))
      throw Error(source, "side section: merged vertex", "out of order or range");
    side.merged[k] = static_cast<std::uint32_t>(k - back);
    previous = static_cast<std::uint32_t>(k);
  }
  // An integer costs at least -log2(1 - 63 x 2 / 2^15) = 0.0056 bits (IntegerModel): at most
  // 1440 per byte of a position stream, 480 degenerate triangles (3 corners) per byte here.
  side.off_surface = get(m.count, "vertices off the surface", 0x7FFFFFFF);
  if (side.off_surface > 1536 * std::uint64_t{remaining} + 64)
    throw Error(source, "side section: vertices off the surface",
                std::to_string(side.off_surface) + " do not fit the rest of the file");
  const std::uint32_t degenerates = get(m.count, "degenerate triangles", 0x7FFFFFFF);
  if (degenerates > 512 * std::uint64_t{section.size} + 64)
    throw Error(source, "side section: degenerate triangles", "more than the section holds");
  side.degenerate.resize(3 * std::size_t{degenerates});
  for (std::uint32_t& v : side.degenerate)
    v = get(m.corner, "degenerate triangle corner", 0x7FFFFFFF);
  return side;
}

// Reads the three position sections: sets `vertices` (output order) and returns each output
// vertex's grid position.
std::vector<std::array<std::int32_t, 3>> decode_positions(
    io::ByteReader& in, const ReplayedSurface& replayed, const VertexRoles& roles,
    const Quantizer& quantizer, const std::string& source, std::vector<Eigen::Vector3f>& vertices) {
  const std::size_t decoded = roles.hole.size(), outputs = vertices.size();
  std::vector<std::array<std::int32_t, 3>> grid_out(outputs);
  const ParallelogramRing ring(replayed.diamonds, roles.hole, decoded);
  const Section x = read_section(in, "position section x");
  const Section y = read_section(in, "position section y");
  const Section z = read_section(in, "position section z");
  RangeDecoder dec[3] = {RangeDecoder(x.bytes, x.size, source, "position section x"),
                         RangeDecoder(y.bytes, y.size, source, "position section y"),
                         RangeDecoder(z.bytes, z.size, source, "position section z")};
  PositionModels m;
  SnapModels snap;
  SnapNeighbourhood neighbourhood(decoded);
  Grid grid(decoded);
  std::array<std::int32_t, 3> last{};
  {
    // The three decoders' states stay in registers for the whole loop (stored back when the
    // sessions end, then checked).
    RangeDecoder::Session sx(dec[0]), sy(dec[1]), sz(dec[2]);
    RangeDecoderCore &cx = sx.core, &cy = sy.core, &cz = sz.core;
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
      // A corrupt stream can name parallelograms past the offer: they are ignored.
      const unsigned trusted =
          offer.n > 0 ? m.trusted[offer.n - 1].decode(cx) & ((1u << offer.n) - 1u) : 0u;
      std::array<std::size_t, 3> context;
      const std::array<std::int32_t, 3> predicted = predict(offer, trusted, context);
      const SnapNeighbours& nb =
          neighbourhood.gather(k, replayed.predictors[k], ring, roles.hole, grid);
      RangeDecoderCore* core[3] = {&cx, &cy, &cz};
      std::array<std::int32_t, 3> q{};
      const unsigned snapped = snap.decode(cx, snap_axes(nb, predicted), q);
      for (std::size_t a = 0; a < 3; ++a) {
        if ((snapped >> a) & 1u) continue;
        q[a] = static_cast<std::int32_t>(
            static_cast<std::uint32_t>(predicted[a]) +
            static_cast<std::uint32_t>(m.residual[context[a]][a].decode(*core[a])));
      }
      last = q;
      grid[k] = q;
      vertices[roles.output[k]] = quantizer.position(grid[k]);
      grid_out[roles.output[k]] = grid[k];
    }
    for (std::size_t i = roles.surface_outputs; i < outputs; ++i) {
      // A corrupt count can ask for millions of vertices past the streams' end: stop there
      // (the checks below report it).
      if ((i & 4095u) == 0 && (cx.overran() || cy.overran() || cz.overran())) break;
      const std::array<std::int32_t, 3> q = read(last, kPreviousContext);
      vertices[i] = quantizer.position(q);
      grid_out[i] = q;
    }
  }
  for (const RangeDecoder& d : dec) d.check();
  return grid_out;
}

// The output triangles: the replayed ones without a hole vertex (in output vertex numbers), then
// the degenerate ones (checked against the `outputs` vertices).
std::vector<Triangle> output_triangles(const ReplayedSurface& replayed, const VertexRoles& roles,
                                       const std::vector<std::uint32_t>& degenerate,
                                       std::size_t outputs, const std::string& source) {
  std::vector<Triangle> triangles;
  triangles.reserve(replayed.triangles.size() + degenerate.size() / 3);
  for (const Triangle& t : replayed.triangles) {
    if (roles.hole[t[0]] || roles.hole[t[1]] || roles.hole[t[2]]) continue;
    triangles.push_back({roles.output[t[0]], roles.output[t[1]], roles.output[t[2]]});
  }
  for (std::size_t i = 0; i < degenerate.size(); i += 3) {
    for (std::size_t j = 0; j < 3; ++j)
      if (degenerate[i + j] >= outputs)
        throw Error(source, "side section: degenerate triangle corner",
                    std::to_string(degenerate[i + j]) + " is not below the " +
                        std::to_string(outputs) + " vertices");
    triangles.push_back({degenerate[i], degenerate[i + 1], degenerate[i + 2]});
  }
  return triangles;
}

// Reads the normal bits and the attribute section into `mesh` (whose vertices, grid positions
// `grid` and triangles are decoded; `adjacency`: vertex_adjacency() of the triangles when the
// body has colours); returns the normal bits. The colours' neighbourhood is built beside the
// normals (on a second thread when there is one).
unsigned decode_attributes(io::ByteReader& in, AttributeFlags flags,
                           const std::vector<std::array<std::int32_t, 3>>& grid,
                           VertexAdjacency adjacency, TriangleMesh& mesh,
                           const std::string& source) {
  const unsigned normal_bits = in.u8("normal bits");
  if (flags.normals && (normal_bits < kMinNormalBits || normal_bits > kMaxNormalBits))
    in.fail("normal bits", std::to_string(normal_bits) + " is not " +
                               std::to_string(kMinNormalBits) + " .. " +
                               std::to_string(kMaxNormalBits));
  if (!flags.normals && normal_bits != 0)
    in.fail("normal bits", std::to_string(normal_bits) + " but the header flags no normals");
  const Section section = read_section(in, "attribute section");
  RangeDecoder dec(section.bytes, section.size, source, "attribute section");
  const DecodedGeometry geometry{grid, mesh.triangles};
  ColorNeighbourhood colour_neighbourhood;
  side_by_side(
      [&] {
        if (flags.normals) mesh.normals = decode_normals(geometry, dec, source);
      },
      [&] {
        if (flags.colors) colour_neighbourhood = color_neighbourhood(std::move(adjacency), grid);
      });
  if (flags.colors) mesh.colors = decode_colors(colour_neighbourhood, dec, source);
  dec.check();
  return normal_bits;
}

}  // namespace

TriangleMesh decode_body(io::ByteReader& in, const Quantizer& quantizer, AttributeFlags flags,
                         const std::string& source, BodyCodes* codes) {
  const std::uint32_t components = in.u32("components");
  const std::uint64_t symbols = in.u64("symbol count");
  const std::uint64_t decoded = in.u64("surface vertex count");
  const Section side_section = read_section(in, "side section");
  const Section symbol_section = read_section(in, "symbol section");
  // More symbols than the section can hold (SymbolModels) is corrupt, and would allocate
  // without bound.
  if (symbols > kSymbolsPerByte * symbol_section.size + 64 ||
      decoded > 3 * symbols + 3 * components + 3 || components > symbols + 1)
    in.fail("symbol count", std::to_string(symbols) + " symbols, " + std::to_string(decoded) +
                                " vertices and " + std::to_string(components) +
                                " components do not fit a section of " +
                                std::to_string(symbol_section.size) + " bytes");
  SideData side = decode_side(side_section, symbols, decoded, in.remaining(), source);
  RangeDecoder symbol_decoder(symbol_section.bytes, symbol_section.size, source, "symbol section");
  const ReplayedSurface replayed =
      decode_symbols(components, static_cast<std::size_t>(symbols),
                     static_cast<std::size_t>(decoded), side.handles, symbol_decoder, source);
  const VertexRoles roles = assign_outputs(std::move(side.hole), std::move(side.merged));
  const std::size_t outputs = roles.surface_outputs + static_cast<std::size_t>(side.off_surface);
  TriangleMesh mesh;
  mesh.vertices.resize(outputs);
  // The positions, and beside them what needs only the connectivity: the output triangles and
  // the colours' adjacency.
  std::vector<std::array<std::int32_t, 3>> grid;
  VertexAdjacency adjacency;
  side_by_side(
      [&] { grid = decode_positions(in, replayed, roles, quantizer, source, mesh.vertices); },
      [&] {
        mesh.triangles = output_triangles(replayed, roles, side.degenerate, outputs, source);
        if (flags.colors) adjacency = vertex_adjacency(outputs, mesh.triangles);
      });
  const unsigned normal_bits =
      decode_attributes(in, flags, grid, std::move(adjacency), mesh, source);
  if (codes != nullptr) {
    codes->positions = std::move(grid);
    codes->normals = mesh.normals;
    codes->normal_bits = normal_bits;
  }
  return mesh;
}

}  // namespace meshflow::compress
