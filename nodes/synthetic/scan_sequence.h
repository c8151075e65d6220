#pragma once
// A synthetic laser-scan sequence: the scanner moves through the analytic demo room and takes
// a scan at each stop, with exact poses. The default input of `meshflow run --synthetic`.

#include <memory>

#include "nodes/io/sequence.h"
#include "nodes/synthetic/scan_simulator.h"

namespace meshflow::synthetic {

struct ScanSequenceConfig {
  int frames = 8;  ///< scanner stops along an ellipse around the room's centre
  ScanConfig scan = [] {
    ScanConfig c;
    c.azimuth_steps = 360;
    c.elevation_steps = 120;
    c.noise_sigma = 0.002f;
    return c;
  }();
};

/// The sequence over `scene`; frame i is a deterministic scan (seed = i + 1) from stop i.
std::unique_ptr<io::Sequence> make_scan_sequence(const Scene& scene,
                                                 const ScanSequenceConfig& config = {});

}  // namespace meshflow::synthetic
