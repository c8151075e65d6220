#include "tools/mpi/mpi_bytes.h"

#include <mpi.h>

#include <algorithm>

namespace meshflow::cli {
namespace {
constexpr std::size_t kMessagePiece = std::size_t{1} << 30;  // MPI counts are int

}  // namespace

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
