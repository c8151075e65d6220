// meshflow compress IN OUT.mfc / decompress IN.mfc OUT: meshes to and from meshflow's
// compressed format (Edgebreaker single-rate or progressive), and the .mfc header for `info`.

#include <memory>
#include <string>

#include "nodes/compress/compressed_mesh.h"
#include "nodes/compress/progressive_mesh.h"
#include "nodes/io/byte_buffer.h"
#include "nodes/io/mesh_readers.h"
#include "nodes/io/mesh_writers.h"
#include "options/pipeline_options.h"
#include "runtime/threads.h"
#include "tools/commands.h"
#include "tools/console.h"
#include "tools/model_check.h"

namespace meshflow::cli {
namespace {

struct CompressOptions {
  std::string input, output;
  bool progressive = false;
  unsigned bits = 0;
  double step = 0.0;
  bool no_normals = false, no_colors = false;
  options::PipelineOptions model;  // the option model's settings (--normal-bits, --normal-error)
  float base_ratio = 0.02f;
};

const char* kind_name(compress::CompressionKind kind) {
  return kind == compress::CompressionKind::kProgressive ? "progressive" : "edgebreaker";
}

void run_compress(const CompressOptions& o) {
  compress::CompressConfig config;
  config.position_bits = o.bits;
  config.step = o.step;
  config.normals = !o.no_normals;
  config.colors = !o.no_colors;
  config.normal_bits = static_cast<unsigned>(o.model.normal_bits);
  config.normal_error = static_cast<double>(o.model.normal_error);
  config.base_ratio = o.base_ratio;
  const TriangleMesh mesh = io::read_mesh(o.input);
  const double t0 = monotonic_seconds();
  compress::CompressReport r;
  const std::vector<unsigned char> bytes = o.progressive
                                               ? compress::compress_progressive(mesh, config, &r)
                                               : compress::compress_mesh(mesh, config, &r);
  const double encode_s = monotonic_seconds() - t0;
  io::write_file_bytes(o.output, bytes);
  const double triangles = static_cast<double>(std::max<std::size_t>(1, mesh.triangles.size()));
  const double connectivity_bpt = 8.0 * static_cast<double>(r.body.connectivity_bytes) /
                                  static_cast<double>(std::max<std::size_t>(
                                      1, o.progressive ? r.base_triangles : mesh.triangles.size()));
  if (console().json) {
    nlohmann::json doc = {
        {"input", o.input},
        {"output", o.output},
        {"kind", kind_name(r.kind)},
        {"vertices", mesh.vertices.size()},
        {"triangles", mesh.triangles.size()},
        {"bytes", bytes.size()},
        {"bits_per_triangle", 8.0 * static_cast<double>(bytes.size()) / triangles},
        {"connectivity_bytes", r.body.connectivity_bytes},
        {"position_bytes", r.body.position_bytes},
        {"attribute_bytes", r.body.attribute_bytes},
        {"connectivity_bits_per_triangle", connectivity_bpt},
        {"quantisation_step_m", r.quantizer.step},
        {"quantisation_bits", r.quantizer.bits},
        {"holes", r.body.holes},
        {"handles", r.body.handles},
        {"encode_ms", 1e3 * encode_s}};
    if (o.progressive) {
      doc["base_triangles"] = r.base_triangles;
      doc["base_bytes"] = r.base_bytes;
      doc["splits"] = r.splits;
    }
    return print_json(doc);
  }
  report("input        %s: %zu vertices, %zu triangles\n", o.input.c_str(), mesh.vertices.size(),
         mesh.triangles.size());
  report("kind         %s\n", kind_name(r.kind));
  report("quantisation %u bits, step %.3g m (positions within %.3g m per axis)\n", r.quantizer.bits,
         r.quantizer.step, r.quantizer.step / 2);
  if (o.progressive) {
    report("base mesh    %zu triangles in %zu bytes (%.1f %% of the file), %zu vertex splits\n",
           r.base_triangles, r.base_bytes,
           100.0 * static_cast<double>(r.base_bytes) / static_cast<double>(bytes.size()), r.splits);
  }
  report("connectivity %zu bytes (%.2f bits per %striangle; %zu holes, %zu handles)\n",
         r.body.connectivity_bytes, connectivity_bpt, o.progressive ? "base " : "", r.body.holes,
         r.body.handles);
  report("positions    %zu bytes, attributes %zu bytes\n", r.body.position_bytes,
         r.body.attribute_bytes);
  report("output       %s: %zu bytes (%.2f bits per triangle), encoded in %.1f ms\n",
         o.output.c_str(), bytes.size(), 8.0 * static_cast<double>(bytes.size()) / triangles,
         1e3 * encode_s);
}

struct DecompressOptions {
  std::string input, output;
  long long splits = -1, triangles = -1;
  bool partial = false;
};

void run_decompress(const DecompressOptions& o) {
  io::check_mesh_output_format(o.output);
  const std::vector<unsigned char> bytes = io::read_file_bytes(o.input);
  const double t0 = monotonic_seconds();
  TriangleMesh mesh;
  compress::ProgressiveLevel level;
  if (o.splits >= 0) level.splits = static_cast<std::size_t>(o.splits);
  if (o.triangles >= 0) level.triangles = static_cast<std::size_t>(o.triangles);
  std::size_t packets = 0, packets_stated = 0;
  if (o.partial) {
    compress::PrefixDecode d = compress::decompress_progressive_prefix(bytes, o.input, level);
    mesh = std::move(d.mesh);
    packets = d.packets;
    packets_stated = d.packets_stated;
  } else if (o.splits >= 0 || o.triangles >= 0) {
    mesh = compress::decompress_progressive_level(bytes, o.input, level);
  } else {
    mesh = compress::decompress_mesh(bytes, o.input);
  }
  const double decode_s = monotonic_seconds() - t0;
  io::write_mesh(o.output, mesh);
  if (console().json)
    return print_json({{"input", o.input},
                       {"output", o.output},
                       {"vertices", mesh.vertices.size()},
                       {"triangles", mesh.triangles.size()},
                       {"packets", packets},
                       {"packets_stated", packets_stated},
                       {"decode_ms", 1e3 * decode_s}});
  if (o.partial) report("prefix %zu of %zu split packets\n", packets, packets_stated);
  report("mesh   %zu vertices, %zu triangles, decoded in %.1f ms\n", mesh.vertices.size(),
         mesh.triangles.size(), 1e3 * decode_s);
  report("output %s\n", o.output.c_str());
}

}  // namespace

bool is_compressed_mesh_file(const std::string& path) {
  return path.size() > 4 && path.compare(path.size() - 4, 4, ".mfc") == 0;
}

void add_compress_option(CLI::App* cmd, std::string& method) {
  cmd->add_option("--compress", method,
                  "Compress each mesh in the graph's last stage (.mfc outputs; profile: timed "
                  "as the 'compress' stage): edgebreaker (single-rate) or progressive "
                  "(levels of detail)")
      ->check(CLI::IsMember({"edgebreaker", "progressive"}));
}

MeshCompression compression_for(const std::string& method, const std::string& output) {
  if (method == "progressive") return MeshCompression::kProgressive;
  if (method == "edgebreaker" || is_compressed_mesh_file(output))
    return MeshCompression::kEdgebreaker;
  return MeshCompression::kNone;
}

void run_compressed_info(const std::string& path) {
  const std::vector<unsigned char> bytes = io::read_file_bytes(path);
  const compress::CompressedMeshInfo info = compress::compressed_mesh_info(bytes, path);
  if (console().json)
    return print_json({{"file", path},
                       {"format", "meshflow compressed mesh"},
                       {"version", info.version},
                       {"kind", kind_name(info.kind)},
                       {"vertices", info.vertices},
                       {"triangles", info.triangles},
                       {"normals", info.normals},
                       {"colors", info.colors},
                       {"recomputed_normals", info.recomputed_normals},
                       {"bytes", bytes.size()},
                       {"quantisation_step_m", info.quantizer.step},
                       {"quantisation_bits", info.quantizer.bits}});
  report("file         %s (meshflow compressed mesh, version %u, %zu bytes)\n", path.c_str(),
         info.version, bytes.size());
  report("kind         %s\n", kind_name(info.kind));
  report("mesh         %llu vertices, %llu triangles%s%s\n",
         static_cast<unsigned long long>(info.vertices),
         static_cast<unsigned long long>(info.triangles),
         info.normals              ? ", normals"
         : info.recomputed_normals ? ", normals (recomputed)"
                                   : "",
         info.colors ? ", colours" : "");
  report("quantisation %u bits, step %.3g m\n", info.quantizer.bits, info.quantizer.step);
}

void add_compress_options(CLI::App* cmd) {
  auto o = std::make_shared<CompressOptions>();
  cmd->add_option("input", o->input, "Mesh: .ply .obj .off .stl")->required();
  cmd->add_option("output,-o,--output", o->output, "Compressed mesh (.mfc)")->required();
  cmd->add_flag("--progressive", o->progressive,
                "Progressive mesh (a coarse base mesh and vertex splits) instead of Edgebreaker");
  cmd->add_option("--bits", o->bits,
                  "Position quantisation: the bounding box's longest side in 2^bits steps "
                  "(auto: from --step)")
      ->check(CLI::Range(1u, 30u))
      ->default_str("auto");
  cmd->add_option("--step", o->step,
                  "Quantisation step, metres (auto: 1/64 of the median edge length)")
      ->check(CLI::PositiveNumber)
      ->default_str("auto");
  cmd->add_flag("--no-normals", o->no_normals, "Leave the mesh's normals out");
  const options::OptionSpec& bits = options::option_spec("normal-bits");
  cmd->add_option("--normal-bits", o->model.normal_bits, bits.help)
      ->capture_default_str()
      ->check(model_check(bits, &options::PipelineOptions::normal_bits));
  const options::OptionSpec& error = options::option_spec("normal-error");
  cmd->add_option("--normal-error", o->model.normal_error, error.help)
      ->check(model_check(error, &options::PipelineOptions::normal_error))
      ->default_str(error.default_text);
  cmd->add_flag("--no-colors", o->no_colors, "Leave the mesh's colours out");
  cmd->add_option("--base-ratio", o->base_ratio,
                  "Progressive: share of the triangles in the base mesh")
      ->check(CLI::Range(0.0f, 1.0f))
      ->capture_default_str();
  add_console_flags(cmd, true);
  cmd->callback([o] { run_compress(*o); });
}

void add_decompress_options(CLI::App* cmd) {
  auto o = std::make_shared<DecompressOptions>();
  cmd->add_option("input", o->input, "Compressed mesh (.mfc)")->required();
  cmd->add_option("output,-o,--output", o->output, "Output mesh: .ply .obj .stl .off .glb")
      ->required();
  cmd->add_option("--level", o->splits,
                  "Progressive: apply this many vertex splits to the base mesh (0: the base; "
                  "default: all of them, the full mesh)")
      ->check(CLI::NonNegativeNumber)
      ->default_str("all");
  cmd->add_option("--triangles", o->triangles,
                  "Progressive: refine until the mesh has this many triangles")
      ->check(CLI::NonNegativeNumber)
      ->default_str("all");
  cmd->add_flag("--partial", o->partial,
                "Progressive: the input may be a prefix (a stream's first bytes) ending at a "
                "packet boundary; decode the levels it holds (every part's checksum checked)");
  add_console_flags(cmd, true);
  cmd->callback([o] { run_decompress(*o); });
}

}  // namespace meshflow::cli
