#pragma once
// What meshflow-mpi's ranks send each other: byte buffers of plain values, and point-to-point
// and broadcast transfers of any size (MPI counts are int: sent in pieces of 1 GiB).

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace meshflow::cli {

/// Plain byte (de)serialisation of what crosses ranks (every rank runs the same binary, so
/// values are copied as they are in memory). Not thread-safe.
class Bytes {
 public:
  /// Appends the bytes of a trivially copyable value.
  template <typename T>
  void put(const T& v) {
    const auto* p = reinterpret_cast<const char*>(&v);
    data.insert(data.end(), p, p + sizeof(T));
  }
  /// Appends a vector: its size, then its elements' bytes.
  template <typename T>
  void put_vector(const std::vector<T>& v) {
    put<std::uint64_t>(v.size());
    const auto* p = reinterpret_cast<const char*>(v.data());
    data.insert(data.end(), p, p + v.size() * sizeof(T));
  }
  /// Appends a string: its size, then its characters.
  void put_string(const std::string& s) {
    put<std::uint64_t>(s.size());
    data.insert(data.end(), s.begin(), s.end());
  }
  /// Reads a value written by put() at the read position.
  template <typename T>
  T get() {
    T v;
    std::memcpy(static_cast<void*>(&v), data.data() + at, sizeof(T));
    at += sizeof(T);
    return v;
  }
  /// Reads a vector written by put_vector().
  template <typename T>
  std::vector<T> get_vector() {
    std::vector<T> v(get<std::uint64_t>());
    std::memcpy(static_cast<void*>(v.data()), data.data() + at, v.size() * sizeof(T));
    at += v.size() * sizeof(T);
    return v;
  }
  /// Reads a string written by put_string().
  std::string get_string() {
    const auto n = get<std::uint64_t>();
    std::string s(data.data() + at, n);
    at += n;
    return s;
  }
  std::vector<char> data;  ///< the bytes
  std::size_t at = 0;      ///< read position
};

/// Sends `data` (its size first) to rank `to`. Blocks until sent.
void send_bytes(const std::vector<char>& data, int to);
/// Receives what send_bytes() sent from rank `from`. Blocks.
std::vector<char> receive_bytes(int from);
/// Rank 0's `data` to every rank (the others' is replaced). Collective.
void broadcast_bytes(std::vector<char>& data);

}  // namespace meshflow::cli
