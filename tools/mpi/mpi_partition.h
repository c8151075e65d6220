#pragma once
// meshflow-mpi reconstruct's partition when the input can be read by byte range (binary PLY):
// every rank reads only its own range of the file, for the whole-input decisions (its part of
// the voxel's sample) and for the chunk files (its own part of each chunk's points); rank 0
// joins the parts. No rank reads the whole input.

#include <memory>
#include <string>
#include <vector>

#include "graph/chunked_reconstruction.h"

namespace meshflow::cli {

/// What the partition gives every rank (rank 0 also owns `store`, the chunk directory).
struct RankedPartition {
  std::string error;  ///< non-empty on every rank when some rank failed (rank 0 reports it)
  chunk::ChunkGrid grid;
  chunk::ChunkRows rows;
  InputDecisions decided;
  std::vector<chunk::ChunkFile> files;  ///< rank 0 only (then broadcast with the plan)
  std::unique_ptr<chunk::ChunkStore> store;
};

/// Partitions `input` (whose `parts`, from input_parts(), are by byte range; rank r reads
/// parts.ranges[r] when it exists) into chunk files under chunking.directory, which every rank
/// must see. Collective: every rank calls it with the same arguments. The chunks equal those
/// of partition_input() on one process (same points, same order). Errors of any rank come back
/// in `error` on every rank. `clock` times this rank's phases: "decide", "setup" (rank 0 alone:
/// the grid; the others wait), "partition" and on rank 0 "join" (left running).
RankedPartition partition_by_ranks(const std::string& input, const std::string& columns,
                                   const ReconstructionConfig& config,
                                   const ChunkingConfig& chunking, const InputParts& parts,
                                   int rank, int ranks, chunk::PhaseClock& clock);

/// The chunk list as bytes and back (files, their parts and counts).
void put_chunk_files(io::ByteWriter& w, const std::vector<chunk::ChunkFile>& files);
std::vector<chunk::ChunkFile> get_chunk_files(io::ByteReader& r);

}  // namespace meshflow::cli
