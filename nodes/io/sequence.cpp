#include "nodes/io/sequence.h"

#include <algorithm>
#include <filesystem>
#include <vector>

#include "nodes/io/parse_util.h"
#include "nodes/io/read_point_cloud.h"
#include "nodes/io/rgbd_sequences.h"
#include "nodes/io/scan3d_reader.h"
#include "runtime/error.h"

namespace meshflow::io {
namespace {

namespace fs = std::filesystem;

class SingleFileSequence final : public Sequence {
 public:
  explicit SingleFileSequence(std::string path) : path_(std::move(path)) {}
  std::size_t size() const override { return 1; }
  SequenceFrame frame(std::size_t) const override {
    const std::string path = path_;
    return {0, 0.0, path, [path] { return read_point_cloud(path); }, {}};
  }
  std::string description() const override { return "point cloud " + path_ + " (1 frame)"; }

 private:
  std::string path_;
};

// Clouds from files in name order (e.g. organized PCD frames of a grabber), no poses.
class CloudFileSequence final : public Sequence {
 public:
  CloudFileSequence(std::string directory, std::vector<std::string> files)
      : directory_(std::move(directory)), files_(std::move(files)) {}
  std::size_t size() const override { return files_.size(); }
  SequenceFrame frame(std::size_t i) const override {
    const std::string path = files_[i];
    return {i, static_cast<double>(i), path, [path] { return read_point_cloud(path); }, {}};
  }
  std::string description() const override {
    return "point clouds in " + directory_ + " (" + std::to_string(files_.size()) +
           " frames, no poses)";
  }

 private:
  std::string directory_;
  std::vector<std::string> files_;
};

std::vector<std::string> files_with_extension(const std::string& directory,
                                              const std::string& ext) {
  std::vector<std::string> out;
  for (const auto& entry : fs::directory_iterator(directory)) {
    if (entry.is_regular_file() && lower_extension(entry.path().string()) == ext)
      out.push_back(entry.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

class ScanDirectorySequence final : public Sequence {
 public:
  ScanDirectorySequence(std::string directory, std::vector<std::string> scans)
      : directory_(std::move(directory)), scans_(std::move(scans)) {}
  std::size_t size() const override { return scans_.size(); }
  SequenceFrame frame(std::size_t i) const override {
    const std::string scan = scans_[i];
    const std::string pose = fs::path(scan).replace_extension(".pose").string();
    return {i,
            static_cast<double>(i),
            scan,
            [scan, pose] {
              if (!fs::exists(pose)) throw Error(pose, "", "pose file missing for " + scan);
              return read_3dtk_scan(scan, Scan3dOptions{}, pose);
            },
            {}};
  }
  std::string description() const override {
    return "3DTK scans in " + directory_ + " (" + std::to_string(scans_.size()) + " frames)";
  }

 private:
  std::string directory_;
  std::vector<std::string> scans_;
};

// NNN of a file named "scanNNN.3d", or -1 for any other name.
long scan_number(const std::string& name) {
  const std::string prefix = "scan", suffix = ".3d";
  if (name.size() <= prefix.size() + suffix.size() || name.compare(0, prefix.size(), prefix) != 0 ||
      name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) {
    return -1;
  }
  const std::string digits =
      name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
  if (digits.size() > 9 ||
      !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    return -1;
  }
  return std::stol(digits);
}

}  // namespace

std::unique_ptr<Sequence> open_3dtk_directory(const std::string& directory) {
  std::vector<std::pair<long, std::string>> scans;
  for (const auto& entry : fs::directory_iterator(directory)) {
    const long number = scan_number(entry.path().filename().string());
    if (entry.is_regular_file() && number >= 0) scans.emplace_back(number, entry.path().string());
  }
  if (scans.empty()) throw Error(directory, "", "no scanNNN.3d files (3DTK format) found");
  std::sort(scans.begin(), scans.end());
  std::vector<std::string> paths;
  paths.reserve(scans.size());
  for (auto& s : scans) paths.push_back(std::move(s.second));
  return std::make_unique<ScanDirectorySequence>(directory, std::move(paths));
}

std::unique_ptr<Sequence> open_sequence(const std::string& path) {
  if (fs::is_directory(path)) {
    const fs::path dir(path);
    if (fs::exists(dir / "depth.txt")) return open_tum_directory(path);
    if (fs::is_directory(dir / "depth")) return open_redwood_directory(path);
    for (const char* ext : {".pcd", ".ply"}) {
      auto clouds = files_with_extension(path, ext);
      if (!clouds.empty()) return std::make_unique<CloudFileSequence>(path, std::move(clouds));
    }
    for (const char* ext : {".tiff", ".tif", ".png", ".pclzf"}) {
      for (const auto& f : files_with_extension(path, ext)) {
        if (fs::path(f).filename().string().find("depth") != std::string::npos)
          return open_depth_image_directory(path);
      }
    }
    bool scans = false;
    std::size_t entries = 0;
    for (const auto& entry : fs::directory_iterator(path)) {
      ++entries;
      scans |= entry.is_regular_file() && scan_number(entry.path().filename().string()) >= 0;
    }
    if (!scans)
      throw Error(path, "",
                  "holds no recognisable sequence (" +
                      (entries == 0   ? std::string("the directory is empty")
                       : entries == 1 ? std::string("1 entry, not a frame")
                                      : std::to_string(entries) + " entries, none of them frames") +
                      "); looked for 3DTK scans (scanNNN.3d + scanNNN.pose), point clouds "
                      "(*.pcd, *.ply), depth images (*depth*.png, .tif, .tiff, .pclzf), a "
                      "Redwood / Open3D RGB-D directory (depth/) and a TUM RGB-D directory "
                      "(depth.txt)");
    return open_3dtk_directory(path);
  }
  if (!fs::exists(path)) throw Error(path, "", "no such file or directory");
  return std::make_unique<SingleFileSequence>(path);
}

}  // namespace meshflow::io
