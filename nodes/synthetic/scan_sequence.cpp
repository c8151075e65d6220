#include "nodes/synthetic/scan_sequence.h"

#include <cmath>
#include <string>

namespace meshflow::synthetic {
namespace {

class ScanSequence final : public io::Sequence {
 public:
  ScanSequence(Scene scene, ScanSequenceConfig config)
      : scene_(std::move(scene)), config_(std::move(config)) {}
  std::size_t size() const override { return static_cast<std::size_t>(config_.frames); }
  io::SequenceFrame frame(std::size_t i) const override {
    ScanConfig scan = config_.scan;
    const double angle = 2.0 * M_PI * static_cast<double>(i) / std::max(1, config_.frames);
    scan.origin =
        scene_.room.center + Eigen::Vector3f(static_cast<float>(1.5 * std::cos(angle)),
                                             static_cast<float>(1.0 * std::sin(angle)), -0.3f);
    scan.seed = static_cast<std::uint32_t>(i + 1);
    const Scene* scene = &scene_;
    return {i,
            0.1 * static_cast<double>(i),
            "synthetic scan " + std::to_string(i),
            [scene, scan] { return simulate_scan(*scene, scan); },
            {}};
  }
  std::string description() const override {
    return "synthetic laser scans of the demo room (" + std::to_string(config_.frames) + " frames)";
  }

 private:
  Scene scene_;
  ScanSequenceConfig config_;
};

}  // namespace

std::unique_ptr<io::Sequence> make_scan_sequence(const Scene& scene,
                                                 const ScanSequenceConfig& config) {
  return std::make_unique<ScanSequence>(scene, config);
}

}  // namespace meshflow::synthetic
