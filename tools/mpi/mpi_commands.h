#pragma once
// meshflow-mpi's subcommands. Every rank parses the same command line and runs the chosen
// subcommand; rank 0 reads, gathers and reports, the others compute their share.

#include <CLI/CLI.hpp>

namespace meshflow::cli {

/// This process's place among the ranks of MPI_COMM_WORLD.
struct MpiWorld {
  int rank = 0;
  int ranks = 1;
};

/// `reconstruct IN -o OUT --chunk S`: the chunked path over the ranks; the callback stores the
/// exit status (0 ok, 1 failed) in `status`.
void add_mpi_reconstruct(CLI::App* cmd, const MpiWorld& world, int& status);

/// `run SEQUENCE -o DIR`: per-frame meshing with the frames dealt to the ranks in turn; the
/// callback stores the exit status in `status`.
void add_mpi_run(CLI::App* cmd, const MpiWorld& world, int& status);

}  // namespace meshflow::cli
