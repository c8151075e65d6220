#pragma once
// What meshflow-mpi's ranks send each other: plain values in byte buffers, and point-to-point
// and broadcast transfers of any size (MPI counts are int: sent in pieces of 1 GiB).

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "nodes/chunk/chunk_store.h"
#include "nodes/chunk/phase_times.h"
#include "nodes/io/byte_buffer.h"
#include "runtime/triangle_mesh.h"

namespace meshflow::cli {

// Values cross ranks as their bytes in memory (every rank runs the same binary), through
// io::ByteWriter / io::ByteReader, whose reads are checked against the message's end.

/// Appends the bytes of a trivially copyable value.
template <typename T>
void put(io::ByteWriter& w, const T& v) {
  w.bytes(&v, sizeof(T));
}
/// Reads a value written by put(); `field` names it in errors.
template <typename T>
T get(io::ByteReader& r, const char* field) {
  T v;
  std::memcpy(static_cast<void*>(&v), r.bytes(sizeof(T), field), sizeof(T));
  return v;
}
/// Appends a vector: its size, then its elements' bytes.
template <typename T>
void put_vector(io::ByteWriter& w, const std::vector<T>& v) {
  w.u64(v.size());
  w.bytes(v.data(), v.size() * sizeof(T));
}
/// Reads a vector written by put_vector().
template <typename T>
std::vector<T> get_vector(io::ByteReader& r, const char* field) {
  const std::uint64_t n = r.u64(field);
  if (n > r.remaining() / sizeof(T)) r.fail(field, "more elements than the message holds");
  std::vector<T> v(n);
  std::memcpy(static_cast<void*>(v.data()), r.bytes(n * sizeof(T), field), n * sizeof(T));
  return v;
}
/// Appends a string: its size, then its characters.
inline void put_string(io::ByteWriter& w, const std::string& s) {
  w.u64(s.size());
  w.bytes(s.data(), s.size());
}
/// Reads a string written by put_string().
inline std::string get_string(io::ByteReader& r, const char* field) {
  const std::uint64_t n = r.u64(field);
  if (n > r.remaining()) r.fail(field, "a string longer than the message");
  const unsigned char* at = r.bytes(n, field);
  return std::string(reinterpret_cast<const char*>(at), n);
}

/// Appends a mesh: its vertices, normals, colours and triangles (put_vector()). O(size).
void put_mesh(io::ByteWriter& w, const TriangleMesh& mesh);
/// Reads a mesh written by put_mesh(); errors name the field. O(size).
TriangleMesh get_mesh(io::ByteReader& r);

/// Appends what a chunk file's rows hold (normals, colours) and their frame (origin, z_up),
/// field by field. O(1).
void put_rows(io::ByteWriter& w, const chunk::ChunkRows& rows);
/// Reads rows written by put_rows(); errors name the field. O(1).
chunk::ChunkRows get_rows(io::ByteReader& r);

/// Appends one rank's timing: rank, chunks, peak memory and its phases. O(phases).
void put_rank_times(io::ByteWriter& w, const chunk::RankTimes& times);
/// Reads a timing written by put_rank_times(); errors name the field. O(phases).
chunk::RankTimes get_rank_times(io::ByteReader& r);

/// Sends `data` (its size first) to rank `to`. Blocks until sent.
void send_bytes(const std::vector<unsigned char>& data, int to);
/// Receives what send_bytes() sent from rank `from`. Blocks.
std::vector<unsigned char> receive_bytes(int from);
/// Rank 0's `data` to every rank (the others' is replaced). Collective.
void broadcast_bytes(std::vector<unsigned char>& data);

}  // namespace meshflow::cli
