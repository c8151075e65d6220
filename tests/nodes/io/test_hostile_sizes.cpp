// Headers that claim far more data than their file holds: each reader must refuse them with a
// meshflow::Error naming the file before it allocates what the header claims. Each case runs in
// a child process whose address space is limited to what it maps now plus 256 MiB, so an
// allocation of the claimed size would fail there as std::bad_alloc (or a crash) instead of
// passing unnoticed on a machine with memory to spare. Under AddressSanitizer or
// ThreadSanitizer, whose shadow memory needs more address space, the limit is left out.

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <new>
#include <string>
#include <vector>

#include "nodes/fusion/tsdf_map_file.h"
#include "nodes/io/image_io.h"
#include "nodes/io/mesh_readers.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/io/sequence.h"
#include "runtime/error.h"
#include "test_support.h"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define MESHFLOW_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define MESHFLOW_SANITIZED 1
#endif
#endif

namespace meshflow {
namespace {

#ifndef MESHFLOW_SANITIZED
// Bytes of address space the process maps now (VmSize of /proc/self/status).
std::uint64_t mapped_bytes() {
  std::ifstream status("/proc/self/status");
  std::string key;
  std::uint64_t kb = 0;
  while (status >> key) {
    if (key == "VmSize:") {
      status >> kb;
      return kb * 1024;
    }
    status.ignore(1 << 20, '\n');
  }
  return 0;
}
#endif

// In the child: limits the address space, runs `read`, exits 0 when it throws meshflow::Error
// (printing the message for the parent's regex), 3 on std::bad_alloc, 4 when it succeeds.
[[noreturn]] void read_in_limited_child(const std::function<void()>& read) {
#ifndef MESHFLOW_SANITIZED
  const rlim_t limit = mapped_bytes() + (rlim_t{256} << 20);
  const rlimit address_space{limit, limit};
  setrlimit(RLIMIT_AS, &address_space);
#endif
  try {
    read();
  } catch (const Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    std::_Exit(0);
  } catch (const std::bad_alloc&) {
    std::_Exit(3);
  }
  std::_Exit(4);
}

struct HostileFile {
  const char* name;
  std::string bytes;
  std::function<void(const std::string&)> read;
  const char* message;  // what the error must say (a regex)
};

std::string ply_header(const char* format, const char* element, const char* properties) {
  return std::string("ply\nformat ") + format + " 1.0\nelement " + element + "\n" + properties +
         "end_header\n";
}

std::string empty_map_claiming(std::uint64_t blocks, const std::string& dir) {
  write_tsdf_map(dir + "/empty.map", TsdfMap{});
  std::string bytes = test::read_file(dir + "/empty.map");
  std::memcpy(&bytes[bytes.size() - 16], &blocks, 8);  // the count before the checksum
  return test::resealed_tsdf_map(bytes);
}

TEST(HostileSizes, HeadersClaimingMoreThanTheFileAreErrorsBeforeAllocation) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const std::string dir = test::temp_dir();
  const auto cloud = [](const std::string& p) { io::read_point_cloud(p); };
  const auto mesh = [](const std::string& p) { io::read_mesh(p); };
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  std::string stl(80, ' ');
  stl += std::string("\xff\xff\xff\xff", 4) + std::string(100, '\0');  // 4 294 967 295 faces
  std::string png("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\xff\xff\0\0\x10\0\x10\0\0\0\0\0\0\0\0\0",
                  33);  // 65 535 x 4 096 16-bit grey (CRC ignored by the reader)
  std::string pclzf = "PCLZF";
  const std::uint32_t side = 16384, packed = 100, unpacked = side * side * 2;
  pclzf.append(reinterpret_cast<const char*>(&side), 4)
      .append(reinterpret_cast<const char*>(&side), 4);
  pclzf += std::string("depth16") + std::string(9, ' ');
  pclzf.append(reinterpret_cast<const char*>(&packed), 4)
      .append(reinterpret_cast<const char*>(&unpacked), 4)
      .append(100, '\0');
  const HostileFile files[] = {
      {"vertices.ply",
       ply_header("binary_little_endian", "vertex 1000000000000", xyz.c_str()) +
           std::string(1000, '\1'),
       cloud, "declares 1000000000000"},
      {"ascii.ply", ply_header("ascii", "vertex 1000000000000", xyz.c_str()) + "1 2 3\n", cloud,
       "declares 1000000000000"},
      {"faces.ply",
       ply_header(
           "binary_little_endian", "vertex 3",
           (xyz + "element face 1000000000000\nproperty list uchar int vertex_indices\n").c_str()) +
           std::string(36, '\0') + std::string(13, '\3'),
       mesh, "face"},
      {"overflow.pcd",
       "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4294967295\n"
       "HEIGHT 4294967295\nPOINTS 18446744065119617025\nDATA binary\n" +
           std::string(1000, '\0'),
       cloud, "WIDTH|HEIGHT|POINTS"},
      {"huge.off", "OFF\n1000000000000 1 0\n0 0 0\n", mesh, "more than the file"},
      {"faces.stl", stl, mesh, "size does not match a binary STL's triangle count"},
      {"huge.png", png, [](const std::string& p) { io::read_depth_image_file(p); },
       "cannot be held in a file of"},
      {"huge.pclzf", pclzf, [](const std::string& p) { io::read_depth_image_file(p); },
       "cannot be held in a file of"},
      {"blocks.map", empty_map_claiming(1000000000, dir),
       [](const std::string& p) { read_tsdf_map(p); },
       "block count at byte 40: 1000000000 blocks need"},
  };
  for (const HostileFile& f : files) {
    const std::string path = dir + "/" + f.name;
    test::write_file(path, f.bytes);
    EXPECT_EXIT(read_in_limited_child([&] { f.read(path); }), ::testing::ExitedWithCode(0),
                f.name + std::string(".*") + f.message)
        << f.name;
  }
}

// The harness itself: a reader that did allocate what a header claims (1 GiB here) is caught.
TEST(HostileSizes, TheLimitCatchesAnAllocationOfTheClaimedSize) {
#ifdef MESHFLOW_SANITIZED
  GTEST_SKIP() << "no address-space limit under the sanitizers";
#else
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(read_in_limited_child([] {
                std::vector<char> claimed(std::size_t{1} << 30, 1);
                std::printf("%d\n", claimed[12345]);
              }),
              ::testing::ExitedWithCode(3), "");
#endif
}

// A camera JSON claiming a 10^9-pixel-wide image: refused when the sequence is opened, before
// any frame is read or any image allocated.
TEST(HostileSizes, CameraJsonWithABillionPixelWideImageIsRefused) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const std::string dir = test::temp_dir();
  std::filesystem::create_directories(dir + "/depth");
  std::filesystem::create_directories(dir + "/color");
  test::write_file(dir + "/depth/000000.png", "not read");
  test::write_file(dir + "/color/000000.jpg", "not read");
  test::write_file(dir + "/trajectory.log", "0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  test::write_file(dir + "/camera_intrinsic.json",
                   R"({"width": 1000000000, "height": 480,
                       "intrinsic_matrix": [525, 0, 0, 0, 525, 0, 319.5, 239.5, 1]})");
  EXPECT_EXIT(read_in_limited_child([&] { io::open_sequence(dir); }), ::testing::ExitedWithCode(0),
              "width: 1000000000 is outside");
}

}  // namespace
}  // namespace meshflow
