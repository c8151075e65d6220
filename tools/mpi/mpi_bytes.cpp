#include "tools/mpi/mpi_bytes.h"

#include <mpi.h>

#include <algorithm>

namespace meshflow::cli {
namespace {
constexpr std::size_t kMessagePiece = std::size_t{1} << 30;  // MPI counts are int

}  // namespace

void put_mesh(io::ByteWriter& w, const TriangleMesh& mesh) {
  put_vector(w, mesh.vertices);
  put_vector(w, mesh.normals);
  put_vector(w, mesh.colors);
  put_vector(w, mesh.triangles);
}

TriangleMesh get_mesh(io::ByteReader& r) {
  TriangleMesh mesh;
  mesh.vertices = get_vector<Eigen::Vector3f>(r, "vertices");
  mesh.normals = get_vector<Eigen::Vector3f>(r, "normals");
  mesh.colors = get_vector<Rgb8>(r, "colors");
  mesh.triangles = get_vector<Triangle>(r, "triangles");
  return mesh;
}

void put_rows(io::ByteWriter& w, const chunk::ChunkRows& rows) {
  put(w, rows.normals);
  put(w, rows.colors);
  put(w, rows.origin);
  put(w, rows.z_up);
}

chunk::ChunkRows get_rows(io::ByteReader& r) {
  chunk::ChunkRows rows;
  rows.normals = get<bool>(r, "normals");
  rows.colors = get<bool>(r, "colors");
  rows.origin = get<Eigen::Vector3d>(r, "origin");
  rows.z_up = get<bool>(r, "z_up");
  return rows;
}

void put_rank_times(io::ByteWriter& w, const chunk::RankTimes& times) {
  put(w, times.rank);
  w.u64(times.chunks);
  w.u64(times.peak_bytes);
  w.u64(times.phases.size());
  for (const chunk::PhaseTime& p : times.phases) {
    put_string(w, p.name);
    put(w, p.wall_s);
    put(w, p.cpu_s);
    put(w, p.work_s);
    put(w, p.serial);
    put(w, p.waiting);
  }
}

chunk::RankTimes get_rank_times(io::ByteReader& r) {
  chunk::RankTimes times;
  times.rank = get<int>(r, "rank");
  times.chunks = r.u64("chunks");
  times.peak_bytes = r.u64("peak memory");
  const std::uint64_t n = r.u64("phases");
  if (n > r.remaining()) r.fail("phases", "more phases than the message holds");
  times.phases.resize(n);
  for (chunk::PhaseTime& p : times.phases) {
    p.name = get_string(r, "phase name");
    p.wall_s = get<double>(r, "phase wall time");
    p.cpu_s = get<double>(r, "phase CPU time");
    p.work_s = get<double>(r, "phase work");
    p.serial = get<bool>(r, "phase serial");
    p.waiting = get<bool>(r, "phase waiting");
  }
  return times;
}

void send_bytes(const std::vector<unsigned char>& data, int to) {
  std::uint64_t size = data.size();
  MPI_Send(&size, 1, MPI_UINT64_T, to, 0, MPI_COMM_WORLD);
  for (std::size_t at = 0; at < data.size(); at += kMessagePiece) {
    const auto n = static_cast<int>(std::min(kMessagePiece, data.size() - at));
    MPI_Send(data.data() + at, n, MPI_BYTE, to, 1, MPI_COMM_WORLD);
  }
}

std::vector<unsigned char> receive_bytes(int from) {
  std::uint64_t size = 0;
  MPI_Recv(&size, 1, MPI_UINT64_T, from, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  std::vector<unsigned char> data(size);
  for (std::size_t at = 0; at < data.size(); at += kMessagePiece) {
    const auto n = static_cast<int>(std::min(kMessagePiece, data.size() - at));
    MPI_Recv(data.data() + at, n, MPI_BYTE, from, 1, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  }
  return data;
}

void broadcast_bytes(std::vector<unsigned char>& data) {
  std::uint64_t size = data.size();
  MPI_Bcast(&size, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
  data.resize(size);
  for (std::size_t at = 0; at < data.size(); at += kMessagePiece) {
    const auto n = static_cast<int>(std::min(kMessagePiece, data.size() - at));
    MPI_Bcast(data.data() + at, n, MPI_BYTE, 0, MPI_COMM_WORLD);
  }
}

}  // namespace meshflow::cli
