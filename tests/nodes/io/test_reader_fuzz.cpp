// Mutation fuzzing of every reader, deterministic (fixed generator states) so a failure
// reproduces: thousands of truncated, flipped, spliced and extreme-number variants of valid
// files. Each either reads or throws meshflow::Error, and what reads is finite where it must be
// (poses, intrinsics, map voxels). Under the CI's ASan + UBSan build this is where memory errors
// and undefined conversions in the readers would show.

#include <gtest/gtest.h>
#include <lzf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "nodes/fusion/tsdf_map_file.h"
#include "nodes/fusion/tsdf_mesher.h"
#include "nodes/io/ply_reader.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/io/rgbd_sequences.h"
#include "nodes/io/scan3d_reader.h"
#include "runtime/error.h"
#include "test_support.h"

namespace meshflow::io {
namespace {

constexpr int kMutationsPerSeed = 300;

template <typename T>
std::string bytes_of(const T& value) {
  return std::string(reinterpret_cast<const char*>(&value), sizeof value);
}

// Runs `read` on kMutationsPerSeed mutations of `seed` written to `path`; every outcome but a
// meshflow::Error or a normal return fails the test (a crash or sanitizer report ends it).
void fuzz(const std::string& path, const std::string& seed, std::uint32_t state,
          const std::function<void(const std::string&)>& read) {
  std::size_t parsed = 0;
  for (int i = 0; i < kMutationsPerSeed; ++i) {
    const std::string text = test::mutate(seed, state);
    test::write_file(path, text);
    try {
      read(path);
      ++parsed;
    } catch (const Error&) {
    } catch (const std::exception& e) {
      ADD_FAILURE() << path << ": " << e.what() << " is not a meshflow::Error (mutation " << i
                    << ")";
    }
  }
  EXPECT_GT(parsed, 0u) << path << ": no mutation read (is the seed valid?)";
}

std::string fuzz_seed_ply() {
  std::string h =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n"
      "property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
      "property uchar blue\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n";
  for (int i = 0; i < 4; ++i) {
    const float p[3] = {static_cast<float>(i), static_cast<float>(i % 2), 1.0f};
    h += std::string(reinterpret_cast<const char*>(p), 12) + "\x0a\x14\x1e";
  }
  for (int f = 0; f < 2; ++f) {
    const std::int32_t ids[3] = {0, 1 + f, 2 + f};
    h += "\x03" + std::string(reinterpret_cast<const char*>(ids), 12);
  }
  return h;
}

std::string big_endian_ply() {
  std::string b =
      "ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty double x\n"
      "property double y\nproperty double z\nend_header\n";
  for (int i = 0; i < 6; ++i) {
    const double d = i;
    std::string s = bytes_of(d);
    std::reverse(s.begin(), s.end());
    b += s;
  }
  return b;
}

std::string fuzz_seed_pcd(bool compressed) {
  const std::string header =
      std::string("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\n") +
      "HEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA " +
      (compressed ? "binary_compressed\n" : "binary\n");
  std::string raw;
  for (int i = 0; i < 12; ++i) raw += bytes_of(0.5f * static_cast<float>(i));
  if (!compressed) return header + raw;
  std::string packed(raw.size() * 2 + 16, '\0');
  const unsigned n = lzf_compress(raw.data(), static_cast<unsigned>(raw.size()), packed.data(),
                                  static_cast<unsigned>(packed.size()));
  EXPECT_GT(n, 0u);
  return header + bytes_of(static_cast<std::uint32_t>(n)) +
         bytes_of(static_cast<std::uint32_t>(raw.size())) + packed.substr(0, n);
}

TEST(ReaderFuzz, PointCloudAndMeshFilesOnlyEverThrowMeshflowErrors) {
  const std::string dir = test::temp_dir();
  const auto cloud = [](const std::string& path) { read_point_cloud(path); };
  const auto cloud_and_mesh = [](const std::string& path) {
    read_point_cloud(path);
    read_ply_mesh(path);
  };
  fuzz(dir + "/a.xyz", "# c\n0 0 0\n1 2 3 0 0 1\n1.5e2 -3 4\nnan 1 2\n4 5 6 255 0 0\n", 1, cloud);
  fuzz(dir + "/a.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
       "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
       "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
       2, cloud_and_mesh);
  fuzz(dir + "/b.ply", fuzz_seed_ply(), 3, cloud_and_mesh);
  fuzz(dir + "/c.ply", big_endian_ply(), 4, cloud);
  fuzz(dir + "/a.pcd",
       "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 3\n"
       "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n0 0 0 4.2108e+06\n"
       "1 1 1 4.2108e+06\nnan nan nan 0\n",
       5, cloud);
  fuzz(dir + "/b.pcd", fuzz_seed_pcd(false), 6, cloud);
  fuzz(dir + "/c.pcd", fuzz_seed_pcd(true), 7, cloud);
  test::write_file(dir + "/s.pose", "10 -20 300\n0 90 -45\n");
  fuzz(dir + "/s.3d", "1 2 3\n4 5 6\n7 8 9 100\n-1e3 2 3\n", 8, cloud);
}

TEST(ReaderFuzz, SequenceFilesOnlyEverThrowMeshflowErrorsOrReadFiniteValues) {
  const std::string dir = test::temp_dir();
  fuzz(dir + "/p.pose", "10.5 -20 300\n0 90.5 -45\n", 11,
       [](const std::string& path) { EXPECT_TRUE(read_3dtk_pose(path).matrix().allFinite()); });
  fuzz(dir + "/t.log",
       "0 0 1\n1 0 0 0.5\n0 1 0 -2\n0 0 1 3\n0 0 0 1\n1 1 2\n0 -1 0 0\n1 0 0 0\n0 0 1 0\n"
       "0 0 0 1\n",
       12, [](const std::string& path) {
         for (const Eigen::Isometry3f& pose : read_trajectory_log(path))
           EXPECT_TRUE(pose.matrix().allFinite());
       });
  fuzz(
      dir + "/c.json",
      R"({"width": 640, "height": 480, "intrinsic_matrix": [525, 0, 0, 0, 525, 0, 319.5, 239.5, 1]})",
      13, [](const std::string& path) {
        const PinholeIntrinsics k = read_intrinsics_json(path);
        EXPECT_TRUE(k.width > 0 && k.height > 0 && std::isfinite(k.fx) && k.fx > 0.0f &&
                    std::isfinite(k.fy) && k.fy > 0.0f && std::isfinite(k.cx) &&
                    std::isfinite(k.cy));
      });
  const std::string tum = dir + "/tum";
  std::filesystem::create_directories(tum);
  const std::string depth_list = "# d\n1.160407 depth/1.160407.png\n1.194330 depth/1.19.png\n";
  const std::string groundtruth =
      "# gt\n1.15 1.3 0.6 1.6 0.65 0.62 -0.29 -0.32\n1.19 1.3 0.6 1.6 0.65 0.62 -0.29 -0.32\n";
  const auto open_tum = [&](const std::string&) {
    const auto sequence = open_tum_directory(tum);
    for (std::size_t i = 0; i < sequence->size(); ++i)
      EXPECT_TRUE(std::isfinite(sequence->frame(i).timestamp_s));
  };
  test::write_file(tum + "/groundtruth.txt", groundtruth);
  fuzz(tum + "/depth.txt", depth_list, 14, open_tum);
  test::write_file(tum + "/depth.txt", depth_list);
  fuzz(tum + "/groundtruth.txt", groundtruth, 15, open_tum);
}

// The map's checksum would catch nearly every mutation, so it is recomputed after each one: the
// fields behind it get fuzzed too. What loads must mesh to finite vertices.
TEST(ReaderFuzz, TsdfMapsBehindAValidChecksumOnlyEverThrowMeshflowErrors) {
  TsdfConfig config;
  config.voxel_size = 0.05f;
  TsdfMap volume(config);
  std::array<TsdfVoxel, kTsdfBlockVoxels> voxels;
  for (int b = 0; b < 2; ++b) {
    for (int i = 0; i < kTsdfBlockVoxels; ++i) {
      const int x = 8 * b + i % 8, y = (i / 8) % 8, z = i / 64;
      voxels[static_cast<std::size_t>(i)].distance =
          0.05f * std::sqrt(static_cast<float>((x - 8) * (x - 8) + (y - 4) * (y - 4) +
                                               (z - 4) * (z - 4))) -
          0.15f;
      voxels[static_cast<std::size_t>(i)].weight = 1.0f;
    }
    volume.insert_block(Eigen::Vector3i(b, 0, 0), voxels);
  }
  const std::string dir = test::temp_dir();
  write_tsdf_map(dir + "/good.tsdf", volume);
  const std::string good = test::read_file(dir + "/good.tsdf");
  std::uint32_t state = 21;
  std::size_t loaded = 0;
  for (int i = 0; i < kMutationsPerSeed; ++i) {
    std::string text = test::mutate(good, state);
    if (text.size() >= 16) text = test::resealed_tsdf_map(std::move(text));
    test::write_file(dir + "/case.tsdf", text);
    try {
      const TsdfMap map = read_tsdf_map(dir + "/case.tsdf");
      for (const Eigen::Vector3f& p : TsdfMesher().extract(map).vertices)
        ASSERT_TRUE(p.allFinite()) << "mutation " << i;
      ++loaded;
    } catch (const Error&) {
    }
  }
  EXPECT_GT(loaded, 0u);
}

}  // namespace
}  // namespace meshflow::io
