// meshflow-mpi run: a recorded sequence meshed per frame with the frames dealt to the ranks in
// turn (frame k of the selection to rank k mod N), each rank running its own flow graph and
// writing DIR/frame_NNNNNN.ply (NNNNNN: the frame's index in the sequence, so the directory is
// the index whatever rank wrote a file). Rank 0 sums the ranks' counts and reports frames/s.
//
//   mpirun -n N meshflow-mpi run SEQUENCE -o DIR [--every N] [--max-frames N] [stage options]

#include <mpi.h>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "graph/pipeline.h"
#include "graph/sequence_runner.h"
#include "nodes/io/atomic_file.h"
#include "nodes/io/mesh_writers.h"
#include "runtime/error.h"
#include "runtime/threads.h"
#include "runtime/tracing.h"
#include "tools/mpi/mpi_commands.h"
#include "tools/pipeline_options.h"

namespace meshflow::cli {
namespace {

struct RunOptions {
  PipelineOptions pipeline;
  SequenceArgument sequence;
  std::string output_dir;
};

// The frames of `base` at `indices` (their own indices and names kept), as a sequence.
class SelectedFrames final : public io::Sequence {
 public:
  SelectedFrames(const io::Sequence& base, std::vector<std::size_t> indices)
      : base_(base), indices_(std::move(indices)) {}
  std::size_t size() const override { return indices_.size(); }
  io::SequenceFrame frame(std::size_t i) const override { return base_.frame(indices_[i]); }
  std::string description() const override { return base_.description(); }

 private:
  const io::Sequence& base_;
  std::vector<std::size_t> indices_;
};

int run_frames(const RunOptions& o, const MpiWorld& world) {
  ThreadLimit limit(o.pipeline.threads);
  const double t0 = monotonic_seconds();
  // Every rank opens the sequence (a shared directory, or the same synthetic one).
  const std::unique_ptr<io::Sequence> sequence = open_sequence_argument(o.sequence);
  int ready = 1;
  if (world.rank == 0) {
    std::error_code ec;
    std::filesystem::create_directories(o.output_dir, ec);
    if (ec || !std::filesystem::is_directory(o.output_dir)) {
      std::fprintf(stderr, "meshflow-mpi: error: %s: cannot create output directory%s%s\n",
                   o.output_dir.c_str(), ec ? ": " : "", ec ? ec.message().c_str() : "");
      ready = 0;
    }
  }
  MPI_Bcast(&ready, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (!ready) return 1;

  const std::size_t every = std::max<std::size_t>(1, o.sequence.every);
  std::vector<std::size_t> mine;
  std::size_t selected = 0;
  for (std::size_t i = 0; i < sequence->size(); i += every, ++selected) {
    if (o.sequence.max_frames > 0 && selected == o.sequence.max_frames) break;
    if (selected % static_cast<std::size_t>(world.ranks) == static_cast<std::size_t>(world.rank))
      mine.push_back(i);
  }
  const SelectedFrames frames(*sequence, std::move(mine));
  ReconstructionPipeline pipeline(o.pipeline.config(), o.sequence.in_flight);
  const std::filesystem::path dir(o.output_dir);
  const SequenceRunStats stats =
      run_sequence(pipeline, frames, SequenceRunOptions{}, [&](const Frame& f) {
        if (!f.ok()) {
          std::fprintf(stderr, "meshflow-mpi: rank %d: frame %zu (%s) failed in %s: %s\n",
                       world.rank, f.source_index, f.name.c_str(), f.failed_stage.c_str(),
                       f.error.c_str());
          return;
        }
        char name[64];
        std::snprintf(name, sizeof name, "frame_%06zu.ply", f.source_index);
        io::write_ply((dir / name).string(), f.mesh, io::PlyEncoding::kBinary, f.origin);
      });

  // Rank 0: the sums over the ranks, and the slowest rank's time.
  unsigned long long counts[2] = {stats.frames_ok, stats.frames_failed}, totals[2] = {0, 0};
  MPI_Reduce(counts, totals, 2, MPI_UNSIGNED_LONG_LONG, MPI_SUM, 0, MPI_COMM_WORLD);
  double busy = stats.wall_s, slowest = 0.0;
  MPI_Reduce(&busy, &slowest, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
  if (world.rank != 0) return 0;
  const double wall = monotonic_seconds() - t0;
  std::printf("sequence   %s\n", sequence->description().c_str());
  std::printf("frames     %llu ok, %llu failed over %d ranks x %d threads\n", totals[0], totals[1],
              world.ranks, limit.threads());
  std::printf("time       %.2f s (slowest rank's frames %.2f s): %.2f frames/s\n", wall, slowest,
              static_cast<double>(totals[0] + totals[1]) / wall);
  std::printf("output     %llu mesh files in %s\n", totals[0], o.output_dir.c_str());
  return totals[0] == 0 ? 1 : 0;
}

}  // namespace

void add_mpi_run(CLI::App* cmd, const MpiWorld& world, int& status) {
  auto o = std::make_shared<RunOptions>();
  add_sequence_options(cmd, o->sequence);
  cmd->add_option("-o,--output", o->output_dir,
                  "Output directory (every rank writes its frames there: a shared file system "
                  "on a cluster)")
      ->required();
  add_pipeline_options(cmd, o->pipeline);
  cmd->callback([o, world, &status] { status = run_frames(*o, world); });
}

}  // namespace meshflow::cli
