// Mesh compression: meshflow's Edgebreaker and progressive coders beside Google's Draco
// (Debian's libdraco, optional: MESHFLOW_HAVE_DRACO) on the same cleaned meshes, positions at
// 14 bits (Draco at its default compression level 7 and at its best, 10: the `level` argument),
// and with the `normals` argument 1 also the mesh's normals as each writes them at equal error:
// Draco at its default quantisation (-qn 10), meshflow at the largest --normal-error whose mean
// and p99 angle after decoding are no larger (bench/compress_vs_draco.sh: 0.6 degrees on the
// room, 0.8 on kurt3d). Threads: that many meshes coded at once (frames in flight), one
// coder each. Counters: bytes, bits per triangle (all, and connectivity alone), and MB/s of
// the raw mesh (12 bytes per vertex, per normal and per triangle) per thread count.

#include <tbb/parallel_for.h>

#include <memory>

#include "bench_support.h"
#include "nodes/compress/compressed_mesh.h"
#include "nodes/compress/progressive_mesh.h"
#include "runtime/threads.h"

#ifdef MESHFLOW_HAVE_DRACO
#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>
#endif

namespace meshflow::bench {
namespace {

constexpr unsigned kBits = 14;
constexpr int kDracoNormalBits = 10;  // draco_encoder's default -qn

compress::CompressConfig positions_only() {
  compress::CompressConfig c;
  c.position_bits = kBits;
  c.normals = c.colors = false;
  return c;
}

// The coded attributes of the Edgebreaker benchmarks: positions, and normals with `normals` at
// Draco's default error on `input` (bench/compress_vs_draco.sh).
compress::CompressConfig codec_config(bool normals, std::int64_t input) {
  compress::CompressConfig c = positions_only();
  c.normals = normals;
  c.normal_error = input == kKurt3d ? 0.8 : 0.6;
  return c;
}

bool with_normals(const benchmark::State& state, const TriangleMesh& m) {
  return state.range(2) != 0 && m.normals.size() == m.vertices.size();
}

double raw_bytes(const TriangleMesh& m, bool normals = false) {
  return 12.0 * static_cast<double>(m.vertices.size() + m.triangles.size() +
                                    (normals ? m.normals.size() : 0));
}

// thread_and_input_args, each with and without normals (the third argument).
void codec_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"threads", "input", "normals"});
  for (int input : {kSynthetic, kKurt3d})
    for (int normals : {0, 1})
      for (int threads : {1, 2}) b->Args({threads, input, normals});
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}

// codec_args with Draco's compression level (7, its default, and 10, its best) as a fourth.
void draco_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"threads", "input", "normals", "level"});
  for (int input : {kSynthetic, kKurt3d})
    for (int normals : {0, 1})
      for (int threads : {1, 2})
        for (int level : {7, 10}) b->Args({threads, input, normals, level});
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}

// Counters shared by every coder: sizes, and throughput over `copies` meshes per iteration.
void count_coding(benchmark::State& state, const TriangleMesh& m, std::size_t bytes,
                  double connectivity_bytes, int copies, bool normals = false) {
  const double t = static_cast<double>(m.triangles.size());
  state.counters["bytes"] = static_cast<double>(bytes);
  state.counters["bits/tri"] = 8.0 * static_cast<double>(bytes) / t;
  if (connectivity_bytes > 0) state.counters["conn_bits/tri"] = 8.0 * connectivity_bytes / t;
  state.counters["MB/s"] = benchmark::Counter(raw_bytes(m, normals) * copies / 1e6,
                                              benchmark::Counter::kIsIterationInvariantRate);
}

// Runs f(copy) for copies 0 .. threads - 1 at once.
template <typename F>
void in_flight(int threads, F f) {
  tbb::parallel_for(0, threads, [&](int k) { f(k); });
}

void BM_EdgebreakerEncode(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  const int threads = static_cast<int>(state.range(0));
  const bool normals = with_normals(state, *mesh);
  ThreadLimit limit(threads);
  compress::CompressReport report;
  std::size_t bytes = 0;
  for (auto _ : state)
    in_flight(threads, [&](int k) {
      compress::CompressReport r;
      const std::size_t n =
          compress::compress_mesh(*mesh, codec_config(normals, state.range(1)), &r).size();
      if (k == 0) {
        bytes = n;
        report = r;
      }
    });
  count_coding(state, *mesh, bytes, static_cast<double>(report.body.connectivity_bytes), threads,
               normals);
}
BENCHMARK(BM_EdgebreakerEncode)->Apply(codec_args);

void BM_EdgebreakerDecode(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  const int threads = static_cast<int>(state.range(0));
  const bool normals = with_normals(state, *mesh);
  ThreadLimit limit(threads);
  compress::CompressReport report;
  const std::vector<unsigned char> bytes =
      compress::compress_mesh(*mesh, codec_config(normals, state.range(1)), &report);
  for (auto _ : state)
    in_flight(threads, [&](int) {
      benchmark::DoNotOptimize(compress::decompress_mesh(bytes, "bench").triangles.size());
    });
  count_coding(state, *mesh, bytes.size(), static_cast<double>(report.body.connectivity_bytes),
               threads, normals);
}
BENCHMARK(BM_EdgebreakerDecode)->Apply(codec_args);

// One mesh as written (normals, and colours where the input has them) decoded at a time on
// state.range(0) threads: the decoder's own second thread (the output triangles and the colours'
// neighbourhood beside the positions and the normals; nodes/compress/side_by_side.h).
void BM_EdgebreakerDecodeOne(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  ThreadLimit limit(static_cast<int>(state.range(0)));
  compress::CompressConfig config = codec_config(with_normals(state, *mesh), state.range(1));
  config.colors = mesh->colors.size() == mesh->vertices.size();
  compress::CompressReport report;
  const std::vector<unsigned char> bytes = compress::compress_mesh(*mesh, config, &report);
  for (auto _ : state)
    benchmark::DoNotOptimize(compress::decompress_mesh(bytes, "bench").triangles.size());
  count_coding(state, *mesh, bytes.size(), static_cast<double>(report.body.connectivity_bytes), 1,
               config.normals);
  state.counters["colors"] = config.colors ? 1.0 : 0.0;
}
BENCHMARK(BM_EdgebreakerDecodeOne)
    ->ArgNames({"threads", "input", "normals"})
    ->ArgsProduct({{1, 2}, {kSynthetic, kKurt3d, kRedwood}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Progressive: the whole file, and the share of it the base mesh needs.
void BM_ProgressiveEncode(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  ThreadLimit limit(static_cast<int>(state.range(0)));
  compress::CompressReport report;
  std::size_t bytes = 0;
  for (auto _ : state)
    benchmark::DoNotOptimize(
        bytes = compress::compress_progressive(*mesh, positions_only(), &report).size());
  count_coding(state, *mesh, bytes, 0.0, 1);
  state.counters["base_%"] =
      100.0 * static_cast<double>(report.base_bytes) / static_cast<double>(bytes);
  state.counters["base_tri"] = static_cast<double>(report.base_triangles);
}
BENCHMARK(BM_ProgressiveEncode)->Apply(thread_and_input_args);

void BM_ProgressiveDecode(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  ThreadLimit limit(static_cast<int>(state.range(0)));
  const std::vector<unsigned char> bytes = compress::compress_progressive(*mesh, positions_only());
  for (auto _ : state)
    benchmark::DoNotOptimize(compress::decompress_mesh(bytes, "bench").triangles.size());
  count_coding(state, *mesh, bytes.size(), 0.0, 1);
}
BENCHMARK(BM_ProgressiveDecode)->Apply(thread_and_input_args);

#ifdef MESHFLOW_HAVE_DRACO
// `m` as a Draco mesh (positions, and normals with `normals`; points shared as in `m`).
std::unique_ptr<draco::Mesh> to_draco(const TriangleMesh& m, bool normals = false) {
  auto owned = std::make_unique<draco::Mesh>();
  draco::Mesh& d = *owned;
  d.set_num_points(static_cast<draco::PointIndex::ValueType>(m.vertices.size()));
  draco::GeometryAttribute position;
  position.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_FLOAT32, false,
                sizeof(float) * 3, 0);
  const int id = d.AddAttribute(position, true, static_cast<std::uint32_t>(m.vertices.size()));
  for (std::uint32_t i = 0; i < m.vertices.size(); ++i)
    d.attribute(id)->SetAttributeValue(draco::AttributeValueIndex(i), m.vertices[i].data());
  if (normals) {
    draco::GeometryAttribute normal;
    normal.Init(draco::GeometryAttribute::NORMAL, nullptr, 3, draco::DT_FLOAT32, false,
                sizeof(float) * 3, 0);
    const int n = d.AddAttribute(normal, true, static_cast<std::uint32_t>(m.vertices.size()));
    for (std::uint32_t i = 0; i < m.vertices.size(); ++i)
      d.attribute(n)->SetAttributeValue(draco::AttributeValueIndex(i), m.normals[i].data());
  }
  for (const Triangle& t : m.triangles)
    d.AddFace({draco::PointIndex(t[0]), draco::PointIndex(t[1]), draco::PointIndex(t[2])});
  return owned;
}

// Encodes at compression `level` (0 .. 10: speed 10 - level, as draco_encoder -cl).
std::size_t draco_encode(const draco::Mesh& d, int bits, int level, draco::EncoderBuffer& out) {
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, bits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, kDracoNormalBits);
  encoder.SetEncodingMethod(draco::MESH_EDGEBREAKER_ENCODING);
  encoder.SetSpeedOptions(10 - level, 10 - level);
  out.Clear();
  if (!encoder.EncodeMeshToBuffer(d, &out).ok()) return 0;
  return out.size();
}

// Draco's connectivity alone: the file with 1-bit positions (which then cost next to nothing).
double draco_connectivity_bytes(const draco::Mesh& d, int level) {
  draco::EncoderBuffer b;
  return static_cast<double>(draco_encode(d, 1, level, b));
}

void BM_DracoEncode(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  const int threads = static_cast<int>(state.range(0));
  const bool normals = with_normals(state, *mesh);
  const int level = static_cast<int>(state.range(3));
  ThreadLimit limit(threads);
  const std::unique_ptr<draco::Mesh> d = to_draco(*mesh, normals);
  std::size_t bytes = 0;
  for (auto _ : state)
    in_flight(threads, [&](int k) {
      draco::EncoderBuffer out;
      const std::size_t n = draco_encode(*d, kBits, level, out);
      if (k == 0) bytes = n;
    });
  if (bytes == 0) return state.SkipWithError("Draco failed to encode");
  count_coding(state, *mesh, bytes, draco_connectivity_bytes(*d, level), threads, normals);
}
BENCHMARK(BM_DracoEncode)->Apply(draco_args);

void BM_DracoDecode(benchmark::State& state) {
  const TriangleMesh* mesh = cleaned_mesh(state);
  if (mesh == nullptr) return;
  const int threads = static_cast<int>(state.range(0));
  const bool normals = with_normals(state, *mesh);
  const int level = static_cast<int>(state.range(3));
  ThreadLimit limit(threads);
  const std::unique_ptr<draco::Mesh> d = to_draco(*mesh, normals);
  draco::EncoderBuffer encoded;
  const std::size_t bytes = draco_encode(*d, kBits, level, encoded);
  if (bytes == 0) return state.SkipWithError("Draco failed to encode");
  bool ok = true;
  for (auto _ : state)
    in_flight(threads, [&](int) {
      draco::DecoderBuffer in;
      in.Init(encoded.data(), encoded.size());
      draco::Decoder decoder;
      auto result = decoder.DecodeMeshFromBuffer(&in);
      if (!result.ok()) ok = false;
      benchmark::DoNotOptimize(result);
    });
  if (!ok) return state.SkipWithError("Draco failed to decode");
  count_coding(state, *mesh, bytes, draco_connectivity_bytes(*d, level), threads, normals);
}
BENCHMARK(BM_DracoDecode)->Apply(draco_args);
#endif

}  // namespace
}  // namespace meshflow::bench
