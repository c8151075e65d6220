#pragma once
// Out-of-core reconstruction of a cloud larger than memory (LVR2's chunked path, exact seams):
//
//   input --stream--> chunk files (one pass, nodes/chunk/chunk_store.h)
//         --> flow graph over chunks, K in flight: read -> ... -> extract, each chunk keeping
//             the cells it owns on the global grid (Frame::chunk)
//         --> stitch (seam vertices welded by their lattice edge) --> rim trim, optimize once
//
// Every chunk sees its points plus an overlap of a few voxels, so the normals, distances and
// rim trimming near its cells are those of the whole cloud; the grid is global, so the chunks'
// cells tile the single-process grid and their seam vertices coincide.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "graph/frame.h"
#include "graph/reconstruction_config.h"
#include "nodes/chunk/chunk_store.h"
#include "nodes/chunk/mesh_stitch.h"
#include "nodes/chunk/phase_times.h"
#include "nodes/voxelize/spacing_sample.h"

namespace meshflow {

struct ChunkingConfig {
  /// Chunk edge, metres (rounded to whole voxels); <= 0: chosen from `memory_budget` and the
  /// whole input's point density (auto_chunk_size(), from decide_from_input()'s sample).
  float chunk_size = 10.0f;
  /// Bytes the chunks in flight may take together (the automatic chunk size); 0 = 1 GiB.
  std::size_t memory_budget = 0;
  /// Points within this many voxels of a chunk go to it too: enough for the normals' and the
  /// distance's neighbours of its border corners (distance.max_distance_voxels + 2 suffices).
  int overlap_voxels = 5;
  std::string directory;                ///< parent of the chunk files; "" = the system's temp dir
  std::size_t in_flight = 2;            ///< chunks inside the flow graph at once (bounds memory)
  std::size_t batch_points = 1u << 20;  ///< points read from the input at a time
  /// Byte ranges of the input read at once, each by its own thread into its own part of the
  /// chunk files (io::point_ranges: binary PLY); 0 = one per thread. Inputs that cannot be
  /// read by byte range are streamed by one thread.
  std::size_t read_parts = 0;
  /// Each chunk is finished where it is meshed (graph/chunk_finish.h: flips, rim trim,
  /// clean and holes with its seam vertices held fixed), leaving the stitched mesh only its
  /// seams: no serial pass over the whole mesh. False, or optimize steps other than clean and
  /// holes: finished once on the stitched mesh (the single-process mesh but for a few
  /// triangles; slower, serial, and the whole mesh several times in memory).
  bool finish_in_place = true;
};

/// Whether `chunking` and `config` finish the chunks in place (finish_in_place, and config's
/// optimize steps are among clean and holes, without splitting non-manifold vertices). O(1).
bool finishes_in_place(const ReconstructionConfig& config, const ChunkingConfig& chunking);

/// The parts a partition reads: the input's byte ranges [first, first + count), or, when it
/// cannot be read by byte range (`why_not`), one part streamed whole.
struct InputParts {
  bool by_byte_range = false;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> ranges;  ///< (first, count) per part
  std::string why_not;
};

/// `parts` (>= 1) ranges of about equal point counts over `path` when io::point_ranges()
/// allows it (fewer when a range would hold under 4096 points), else one part. O(header).
InputParts input_parts(const std::string& path, const std::string& columns, std::size_t parts);

/// Hands every batch of `parts` to `sink(part, batch)`, the parts read at once (one task each;
/// batches of one part in file order, from one thread at a time). Throws the first reader's
/// meshflow::Error.
void for_each_input_part(const std::string& path, const std::string& columns,
                         const InputParts& parts, std::size_t batch_points,
                         const std::function<void(std::size_t, const PointCloud&)>& sink);

/// What the whole input decides once for every chunk, as one process decides it for the whole
/// cloud (the statistics pass of partition_input(), over spacing_sample.h's sample).
struct InputDecisions {
  float voxel_size = 0.0f;       ///< metres: given, or auto_voxel_size()'s rule
  bool voxel_automatic = false;  ///< chosen from the points, not given
  /// The extraction method: the configured one, or for kAuto extended marching cubes when the
  /// sample's median plane-fit variation is below NormalsConfig::clean_variation (and the
  /// normals would be estimated without a sensor, or come from the input), else marching cubes.
  ExtractMethod method = ExtractMethod::kMarchingCubes;
  /// Estimated normals fit over 2 kn neighbours: the sample's median variation exceeds
  /// NormalsConfig::noisy_variation.
  bool noisy = false;
  float median_variation = 0.0f;  ///< of the sample's kn-neighbourhoods (0: not measured)
  /// Points per m^2 of surface (SpacingSample::surface_density() of the whole input's sample),
  /// what the automatic chunk size is made from; 0: not measured (no sample taken).
  float density = 0.0f;
};

/// What a chunked reconstruction did.
struct ChunkedReport {
  float voxel_size = 0.0f;         ///< metres (given, or decided from the whole input)
  InputDecisions decided;          ///< what the whole input decided for every chunk
  int chunk_cells = 0;             ///< chunk edge in cells
  std::size_t chunks = 0;          ///< chunks meshed
  std::uint64_t points = 0;        ///< finite points read
  std::uint64_t dropped = 0;       ///< NaN / Inf points dropped
  std::uint64_t rows_written = 0;  ///< points spilled, overlap copies included
  std::uint64_t max_chunk_points = 0;
  std::size_t seam_vertices = 0;       ///< vertices welded across chunk seams
  std::uint64_t output_vertices = 0;   ///< of the output mesh (held or streamed)
  std::uint64_t output_triangles = 0;  ///< of the output mesh (held or streamed)
  std::size_t rim_trimmed = 0;         ///< triangles peeled off the rim (max_rim_voxels), stitched
  std::size_t tiles = 0;            ///< tiles written by reconstruct_chunked_to_ply() (`tiles_dir`)
  std::vector<std::string> failed;  ///< "chunk name: error" of chunks that failed (skipped)
  std::vector<StageRecord> timings;  ///< every stage record of every chunk
  /// The phases of this process: "decide" (the whole-input sample), "partition" (spilling to
  /// chunk files), "chunks", then "stitch" (welding, feature flips, rim trim) and "finish"
  /// (optimize), serial; the caller adds "write".
  chunk::PhaseClock clock;
  OptimizeReport optimize;
};

struct ChunkedResult {
  TriangleMesh mesh;  ///< local coordinates of `origin`
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  ChunkedReport report;
};

/// The configuration each chunk runs with: `config` with the voxel, the extraction method and
/// the normals' neighbourhood size as `decided` (no chunk decides them on its own), extended
/// marching cubes' edge flips left to the "optimize" stage or the stitched mesh, no
/// optimisation unless `finish_in_place` (then config's clean and holes steps run per chunk,
/// seams held: ChunkPart::finish_cells) and no compression.
ReconstructionConfig chunk_stage_config(const ReconstructionConfig& config,
                                        const InputDecisions& decided,
                                        bool finish_in_place = false);

/// The decisions of `config` for a cloud streamed from `path` in batches of `batch_points`:
/// when the voxel or the extraction method is automatic, or `measure_density` (the automatic
/// chunk size needs InputDecisions::density), two passes over the input (the sample and its
/// nearest neighbours; memory: one batch and its kd-tree per part, the `parts` read at once;
/// no parts: the input streamed whole). Points outside the
/// crop box are left out as the filter stage leaves them; voxel-grid downsampling and
/// statistical outlier removal (--filter-voxel, --outlier-k) are not applied to the sample,
/// so with them the automatic voxel can differ from one process's. Throws meshflow::Error
/// naming `path` when no voxel can be chosen.
InputDecisions decide_from_input(const std::string& path, const std::string& columns,
                                 const ReconstructionConfig& config, std::size_t batch_points,
                                 const InputParts& parts = {}, bool measure_density = false);

/// Bytes a chunk holds in the graph per point (points, normals, Morton order, kd-tree, the
/// normals' neighbours) and per cell of surface (voxel^2 of it: the grid's cells and corners
/// in the band, distances, the extracted mesh and the finish's tables); measured on the
/// synthetic city (bench/RESULTS.md, "Clouds larger than memory"), with margin.
constexpr std::size_t kChunkBytesPerPoint = 160;
constexpr std::size_t kChunkBytesPerCell = 1024;

/// The bytes auto_chunk_size()'s model gives a chunk of edge `edge` metres with
/// `overlap_voxels` of overlap at `density` points per m^2 of surface and `voxel_size`: 2 e^2
/// of surface (terrain and walls; e the edge with the overlap on both sides), its points at
/// kChunkBytesPerPoint and its cells at kChunkBytesPerCell. O(1).
double chunk_bytes_estimate(double edge, double density, double voxel_size, int overlap_voxels);

/// A chunk edge (metres) for which `in_flight` chunks fit `memory_budget` bytes (0 = 1 GiB) by
/// chunk_bytes_estimate(), at the whole input's `density` (InputDecisions::density; 0: unknown,
/// the cells alone); at least 4 voxels. O(1).
float auto_chunk_size(float density, float voxel_size, std::size_t memory_budget,
                      std::size_t in_flight, int overlap_voxels);

/// The chunk grid for `voxel_size` and `chunking` (chunk edge rounded to whole cells, >= 1).
chunk::ChunkGrid make_chunk_grid(float voxel_size, const ChunkingConfig& chunking);

/// Whether `config` leaves the voxel or the extraction method to decide_from_input() (then it
/// needs the sample of the whole input). O(1).
bool decisions_need_sample(const ReconstructionConfig& config);

/// Whether a chunked run of `config` with `chunking` takes the whole input's sample: its
/// decisions need it, or the chunk size is automatic (the density). O(1).
bool input_needs_sample(const ReconstructionConfig& config, const ChunkingConfig& chunking);

/// An empty sample keeping the neighbourhood size `config`'s normals fit over (kn, at least 3),
/// for callers that read the parts of the input themselves (MPI ranks). O(1).
SpacingSample empty_input_sample(const ReconstructionConfig& config);

/// The points of `batch` that go into the sample: finite, inside the crop box and range of
/// `filter` (the filter stage's per-point part, in the batch's local frame). O(batch).
std::vector<Eigen::Vector3f> points_to_sample(const PointCloud& batch, const FilterConfig& filter);

/// decide_from_input()'s decisions from the joined, measured `sample`, given whether the input
/// carries normals and a sensor position (its first batch). Throws meshflow::Error naming
/// `path` when the voxel is automatic and cannot be chosen. O(samples x neighbours).
InputDecisions decisions_from_sample(const SpacingSample& sample,
                                     const ReconstructionConfig& config, bool input_normals,
                                     bool sensor, const std::string& path);

/// The chunk grid at decided.voxel_size: chunking.chunk_size, or when that is <= 0
/// auto_chunk_size() of the whole input's decided.density (chunking's budget and chunks in
/// flight). O(1).
chunk::ChunkGrid grid_for_input(const InputDecisions& decided, ChunkingConfig chunking);

/// Streams `path` (columns as io::read_point_cloud) into chunk files, its byte ranges
/// (input_parts(), chunking.read_parts) each read by a thread of its own into its own part of
/// the chunk files (ChunkWriter; a chunk's points stay in file order), after decide_from_input()
/// (`decided` receives its result; the voxel is one process's automatic voxel when none is
/// given); the chunk edge is chunking.chunk_size or, when that is <= 0, auto_chunk_size() of
/// the whole input's density (grid_for_input(); the store's grid() holds the one used). Returns the
/// store; `files` receives the chunks to mesh in Morton order. `clock` (optional) times the phases
/// "decide" and "partition" (serial when the input cannot be read by byte range: one thread streams
/// it). Throws meshflow::Error for unreadable input or a cloud without finite points.
std::unique_ptr<chunk::ChunkStore> partition_input(
    const std::string& path, const std::string& columns, const ReconstructionConfig& config,
    const ChunkingConfig& chunking, std::vector<chunk::ChunkFile>& files, InputDecisions& decided,
    chunk::PhaseClock* clock = nullptr);

/// Meshes `files` (chunk files of `grid` with rows `rows`) through one flow graph with
/// chunk_stage_config(config, decided, finish_in_place), `in_flight` at a time (with
/// `finish_in_place` each chunk is finished in its graph: finishes_in_place()); hands each
/// finished chunk frame
/// (failed ones with `error` set; the mesh in the input's local frame, with ChunkPart::beyond_data
/// for the rim trim; Frame::source_index = its position in `files`) to `sink` in the order of
/// `files`, from one thread at a time. Each chunk's file is deleted once read.
void mesh_chunk_files(const std::vector<chunk::ChunkFile>& files, const chunk::ChunkGrid& grid,
                      const chunk::ChunkRows& rows, const ReconstructionConfig& config,
                      const InputDecisions& decided, std::size_t in_flight, bool finish_in_place,
                      const std::string& name, const std::function<void(const FramePtr&)>& sink);

/// The same with the chunks taken as the graph asks for them: `next()` returns the position in
/// `files` of the next chunk to mesh, or a negative value when there is none left (a work
/// queue shared with other processes: MPI ranks). Called from graph threads, never
/// concurrently with itself; `sink` sees the chunks in the order `next` gave them.
void mesh_chunk_files(const std::vector<chunk::ChunkFile>& files,
                      const std::function<long long()>& next, const chunk::ChunkGrid& grid,
                      const chunk::ChunkRows& rows, const ReconstructionConfig& config,
                      const InputDecisions& decided, std::size_t in_flight, bool finish_in_place,
                      const std::string& name, const std::function<void(const FramePtr&)>& sink);

/// Bits of the byte per vertex a chunk hands the stitcher (chunk_vertex_flags()).
constexpr std::uint8_t kBeyondDataFlag = 1;  ///< its rim verdict (ChunkPart::beyond_data)
constexpr std::uint8_t kFeatureFlag = 2;     ///< a feature vertex (ChunkPart::feature_vertices)

/// The stitcher for chunk meshes at `voxel_size` in chunks of `chunk_cells` (feature vertices
/// kept apart: kFeatureFlag). O(1).
chunk::MeshStitcher chunk_stitcher(float voxel_size, int chunk_cells);

/// The byte per vertex a chunk hands the stitcher: kBeyondDataFlag and kFeatureFlag; empty
/// when it has neither.
std::vector<std::uint8_t> chunk_vertex_flags(const Frame& frame);

/// A chunk's stage records (and, finished in place, its rim trim and optimize counts) into
/// `report`, or its error into report.failed; returns whether it has a mesh (frame.ok()).
bool report_chunk_frame(const Frame& frame, ChunkedReport& report);

/// What a chunk's sink does: its stage records (and, finished in place, its rim trim and
/// optimize counts) into `report`, its mesh (and rim verdicts) into `stitcher`, or its error
/// into report.failed; frees the frame's mesh.
void collect_chunk_frame(Frame& frame, chunk::MeshStitcher& stitcher, ChunkedReport& report);

/// Welds chunk meshes delivered in order (MeshStitcher, with chunk_vertex_flags()), flips the
/// edges between feature vertices (extended marching cubes' pass, on the stitched mesh so that
/// seams flip as inside one process), trims the rim over the stitched mesh
/// (config.max_rim_voxels) and runs config's optimize steps once; fills the report's seam,
/// rim and optimize fields and times the serial phases "stitch" and "finish" on report.clock
/// (ending "finish"). `on_step` (optional) is told each optimize step. With
/// `finished_in_place` (the chunks were: mesh_chunk_files()), only the seams are finished
/// (chunk::finish_seams(), chunk edge `chunk_cells`): no pass over the whole mesh but the weld.
TriangleMesh finish_chunked_mesh(chunk::MeshStitcher& stitcher, const ReconstructionConfig& config,
                                 float voxel_size, ChunkedReport& report,
                                 const std::function<void(const std::string&)>& on_step = {},
                                 bool finished_in_place = false, int chunk_cells = 0);

/// finish_chunked_mesh() after the weld: `joined` is the welded mesh (MeshStitcher::stitch(), or
/// seam_weld.h's parts concatenated in chunk order by MPI rank 0) with `flags` its vertices'
/// chunk_vertex_flags() bytes (or empty). Flips, trims and optimizes in the phase running on
/// report.clock, then "finish"; with `finished_in_place` only chunk::finish_seams(). Not
/// thread-safe on one report. O(V + T) plus the optimize steps.
TriangleMesh finish_joined_mesh(TriangleMesh joined, const std::vector<std::uint8_t>& flags,
                                const ReconstructionConfig& config, float voxel_size,
                                ChunkedReport& report,
                                const std::function<void(const std::string&)>& on_step = {},
                                bool finished_in_place = false, int chunk_cells = 0);

/// The whole path in one process: partition, mesh the chunks, stitch, optimise (config's
/// steps, on the stitched mesh). `on_stage` (optional) is told each phase ("partition",
/// "chunk i/n", "stitch", optimize steps) for progress lines. Memory: the chunks in flight
/// plus the stitched mesh; disk: about the input's points (with overlap copies) as chunk files.
ChunkedResult reconstruct_chunked(const std::string& path, const std::string& columns,
                                  const ReconstructionConfig& config,
                                  const ChunkingConfig& chunking,
                                  const std::function<void(const std::string&)>& on_stage = {});

/// Whether reconstruct_chunked_to_ply() streams `output`: a .ply file (binary) from chunks
/// finished in place (finishes_in_place()). O(1).
bool streams_output(const std::string& output, const ReconstructionConfig& config,
                    const ChunkingConfig& chunking);

/// reconstruct_chunked() with the mesh written to `output` instead of returned (result.mesh
/// stays empty; report.output_vertices and output_triangles count it). When streams_output():
/// each finished chunk's seam is summarized and its mesh spilled beside the chunk files as it
/// arrives; once all are in, the weld is planned from the summaries, each chunk is read back,
/// welded (a few at once) and written at its rows (chunk::StreamedChunkOutput), then the seams
/// are finished and their rows rewritten; with a non-empty `tiles_dir` each chunk's finished
/// rows are read back as its tile (StreamedChunkOutput::finish(); report.tiles counts them;
/// phase "tiles"). The file is byte for byte io::write_mesh() of
/// reconstruct_chunked()'s mesh; memory: the chunks in flight and the seams' neighbourhood, not
/// the output; disk: the chunk meshes once more until written. Otherwise reconstruct_chunked()
/// then io::write_mesh() (and the tiles cut from the mesh: chunk::split_into_tiles()). Nothing is
/// written when no triangle was extracted. Times "chunks", "stitch" (the plan), "write" and
/// "finish" (the seams) on report.clock. Throws meshflow::Error as reconstruct_chunked() and for a
/// failed write (no file left under `output`).
ChunkedResult reconstruct_chunked_to_ply(
    const std::string& path, const std::string& columns, const ReconstructionConfig& config,
    const ChunkingConfig& chunking, const std::string& output, const std::string& tiles_dir = {},
    const std::function<void(const std::string&)>& on_stage = {});

}  // namespace meshflow
