#pragma once
// Saving and loading a TsdfMap, so a fusion run can resume. The format ("meshflow TSDF map",
// version 1), all numbers little-endian:
//
//   bytes 0-7    magic "MFTSDF\r\n"
//   u32          version (1)
//   u32          block side (8)
//   f32          voxel size, metres (> 0)
//   f32          truncation, voxels (> 0)
//   f32          maximum weight (> 0)
//   u32          flags (bit 0: inverse-depth weighting; bit 1: colour fusion)
//   u64          block count N
//   N blocks     i32 bx, by, bz, then 512 voxels (x fastest, then y, then z) of
//                f32 distance (metres, finite), f32 weight (finite, >= 0), u8 r, g, b, u8 0
//   u64          FNV-1a 64 hash of every byte before it
//
// Blocks are written in key order (z, y, x), so equal volumes give equal files.

#include <cstddef>
#include <cstdint>
#include <string>

#include "nodes/fusion/tsdf_map.h"

namespace meshflow {

/// Writes `volume` to `path` atomically (complete file or none). Throws meshflow::Error.
void write_tsdf_map(const std::string& path, const TsdfMap& volume);

/// Reads a map written by write_tsdf_map(). Throws meshflow::Error naming the file and the
/// field on a wrong magic or version, a size that does not match the block count (truncated or
/// padded file), a checksum mismatch, non-finite values, negative weights or a block stored twice.
TsdfMap read_tsdf_map(const std::string& path);

/// Rewrites the checksum of a map file's image in memory (its last 8 bytes) to match the bytes
/// before it, for programs that edit maps on purpose (the fuzzers and the reader tests, so that
/// their mutations reach the fields behind the checksum). No effect below 8 bytes. O(size).
void reseal_tsdf_map(std::uint8_t* bytes, std::size_t size);

}  // namespace meshflow
