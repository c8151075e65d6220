#pragma once
// meshflow-mpi's streamed output: every rank writes its own welded parts into the output file
// at their rows (the header planned first by rank 0, as `meshflow reconstruct --chunk` streams
// it in one process: graph/chunk_output.h), so no rank holds another's parts; rank 0 then
// finishes the seams from every rank's seam neighbourhood and renames the file into place.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "nodes/chunk/chunk_grid.h"
#include "nodes/chunk/chunk_store.h"
#include "nodes/chunk/phase_times.h"
#include "nodes/chunk/seam_weld.h"
#include "tools/mpi/mpi_weld.h"

namespace meshflow::cli {

/// What rank 0 learns from every rank's writing.
struct RanksWritten {
  std::vector<chunk::RankTimes> times;  ///< every rank's, rank 0's first (its phases to come)
  std::vector<std::string> failed;      ///< failed chunks' errors, in position order
  std::string error;                    ///< "": OUT was written; else why not
  std::size_t gathered_bytes = 0;       ///< the ranks' messages to rank 0
  std::size_t rewritten = 0;            ///< rows rewritten by the seams' finish
  std::size_t tiles = 0;                ///< tiles written
};

/// Collective: writes `output` (binary PLY; `origin` non-zero: world coordinates) from the
/// parts `results` of every rank (placed by weld_on_ranks(), with `weld` its plan, the same on
/// every rank; welded there, or here when weld_on_ranks() left them to weld_result(), spilled or
/// held), on `grid`. Rank 0 creates OUT.tmp with the header for weld's counts (phase "create"),
/// every rank opens it and writes its parts at their rows in order, each welded first if it is
/// not yet (a few at once) and freed once written (phase "write", parallel), then sends rank 0 its
/// timing (`chunks` meshed, its phases), failed chunks and the parts' seam neighbourhoods
/// (add_seam_neighbourhood()); rank 0 (phase "gather", then "finish": finish_seam_rows()) rewrites
/// the seams' rows; with a non-empty `tiles_dir` every rank then writes its own chunks' finished
/// rows as their tiles with their coarser levels and rank 0 their index (write_tiles_on_ranks();
/// `files`: the chunks by position); rank 0 renames OUT.tmp to OUT. Nothing appears under OUT
/// unless every rank wrote all its rows (a failed or dead rank leaves at most OUT.tmp; a failure
/// that rank 0 learns of removes it). Returns rank 0's view (other ranks: their own failures
/// only). No triangle at all: nothing is written, `error` says so. Memory: each rank its parts
/// being welded and written (all its parts when they were welded before) and their seam
/// neighbourhoods; rank 0 all neighbourhoods (seam-sized).
RanksWritten write_on_ranks(const std::string& output, std::vector<ChunkResult>& results,
                            const chunk::WeldPlan& weld, const chunk::ChunkGrid& grid,
                            const Eigen::Vector3d& origin, std::size_t chunks,
                            const std::string& tiles_dir,
                            const std::vector<chunk::ChunkFile>& files, chunk::PhaseClock& clock,
                            int rank, int ranks);

}  // namespace meshflow::cli
