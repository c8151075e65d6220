// meshflow-mpi: meshflow's work spread over MPI ranks, on one machine or a cluster (mpirun). A
// program of its own, so that the meshflow CLI never loads Open MPI at start-up.
//
//   mpirun -n N meshflow-mpi reconstruct IN -o OUT --chunk S [stage options]
//   mpirun -n N meshflow-mpi run SEQUENCE -o DIR [stage options]

#include <mpi.h>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

#include "runtime/process_heap.h"
#include "tools/mpi/mpi_commands.h"

namespace meshflow::cli {
namespace {

// Parses the command line (every rank; only rank 0 prints help and parse errors) and runs the
// chosen subcommand; returns the exit status.
int parse_and_run(int argc, char** argv, const MpiWorld& world) {
  CLI::App app{"meshflow-mpi: meshflow over MPI ranks (mpirun -n N meshflow-mpi COMMAND ...)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "meshflow-mpi " MESHFLOW_VERSION);
  app.option_defaults()->always_capture_default();
  int status = 0;
  add_mpi_reconstruct(
      app.add_subcommand("reconstruct", "One cloud larger than memory, its chunks over the ranks"),
      world, status);
  add_mpi_run(
      app.add_subcommand("run", "A recorded sequence meshed per frame, frames over the ranks"),
      world, status);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {  // --help and --version too: printed once, by rank 0
    const int code = e.get_exit_code();
    if (world.rank == 0) app.exit(e);
    return code == 0 ? 0 : 2;
  }
  return status;
}

}  // namespace
}  // namespace meshflow::cli

int main(int argc, char** argv) {
  meshflow::tune_process_heap();  // before MPI starts its threads
  // Serialized: a rank's graph thread asks rank 0 for chunks while its main thread waits.
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_SERIALIZED, &provided);
  meshflow::cli::MpiWorld world;
  MPI_Comm_rank(MPI_COMM_WORLD, &world.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &world.ranks);
  if (provided < MPI_THREAD_SERIALIZED) {
    if (world.rank == 0)
      std::fprintf(stderr,
                   "meshflow-mpi: error: this MPI library does not provide "
                   "MPI_THREAD_SERIALIZED (graph threads exchange messages)\n");
    MPI_Finalize();
    return 1;
  }
  int status = 0;
  try {
    status = meshflow::cli::parse_and_run(argc, argv, world);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "meshflow-mpi: rank %d: error: %s\n", world.rank, e.what());
    MPI_Abort(MPI_COMM_WORLD, 1);
  } catch (...) {
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  MPI_Finalize();
  return status;
}
