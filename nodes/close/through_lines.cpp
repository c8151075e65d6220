#include "nodes/close/through_lines.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstddef>

namespace meshflow {
namespace {

// The 26 lattice directions, and the index of each one's opposite.
std::array<Eigen::Vector3i, 26> through_directions() {
  std::array<Eigen::Vector3i, 26> d;
  int k = 0;
  for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
      for (int x = -1; x <= 1; ++x)
        if (x != 0 || y != 0 || z != 0) d[static_cast<std::size_t>(k++)] = Eigen::Vector3i(x, y, z);
  return d;
}

// ahead[i] = hit[] of the first node i + t d (t >= 1) inside the lattice where it is not 0, else
// 0. Each node reads
// the next one along d, so the nodes run from the far end: planes in order when d leaves the
// plane (each plane's rows in parallel), else planes in parallel and rows, then nodes, in order.
void through_rays(const Eigen::Vector3i& n, const Eigen::Vector3i& d,
                  const std::vector<std::uint8_t>& hit, std::vector<std::uint8_t>& ahead) {
  const auto index = [&](int x, int y, int z) {
    return (static_cast<std::size_t>(z) * static_cast<std::size_t>(n.y()) +
            static_cast<std::size_t>(y)) *
               static_cast<std::size_t>(n.x()) +
           static_cast<std::size_t>(x);
  };
  const std::size_t nx = static_cast<std::size_t>(n.x());
  // x0 <= x < x1: the nodes whose next node along d is in the row; the others see nothing.
  const int x0 = std::max(0, -d.x()), x1 = n.x() - std::max(0, d.x());
  const auto row = [&](int y, int z) {
    std::uint8_t* out = ahead.data() + index(0, y, z);
    const int y1 = y + d.y(), z1 = z + d.z();
    if (y1 < 0 || y1 >= n.y() || z1 < 0 || z1 >= n.z()) {
      std::fill(out, out + nx, std::uint8_t{0});
      return;
    }
    const std::uint8_t* h = hit.data() + index(0, y1, z1);
    const std::uint8_t* a = ahead.data() + index(0, y1, z1);
    const int dx = d.x();
    for (int x = 0; x < x0; ++x) out[x] = 0;
    for (int x = x1; x < n.x(); ++x) out[x] = 0;
    if (d.y() == 0 && d.z() == 0) {  // along the row: from its far end
      if (d.x() > 0)
        for (int x = x1 - 1; x >= x0; --x) out[x] = h[x + dx] != 0 ? h[x + dx] : a[x + dx];
      else
        for (int x = x0; x < x1; ++x) out[x] = h[x + dx] != 0 ? h[x + dx] : a[x + dx];
      return;
    }
    for (int x = x0; x < x1; ++x)
      out[x] = h[x + dx] != 0 ? h[x + dx] : a[x + dx];  // from another row: any order
  };
  if (d.z() == 0) {
    tbb::parallel_for(0, n.z(), [&](int z) {
      for (int k = 0; k < n.y(); ++k) row(d.y() > 0 ? n.y() - 1 - k : k, z);
    });
    return;
  }
  for (int k = 0; k < n.z(); ++k) {
    const int z = d.z() > 0 ? n.z() - 1 - k : k;
    tbb::parallel_for(0, n.y(), [&](int y) { row(y, z); });
  }
}

}  // namespace

std::vector<std::uint8_t> through_line_nodes(const Eigen::Vector3i& size,
                                             const std::vector<std::uint8_t>& side) {
  const std::size_t nodes = static_cast<std::size_t>(size.x()) *
                            static_cast<std::size_t>(size.y()) * static_cast<std::size_t>(size.z());
  const std::array<Eigen::Vector3i, 26> dirs = through_directions();
  // Bit k of blocked[i]: the ray from node i along dirs[k] meets a node with data; of
  // outward[i]: the first it meets is on the outside of the surface.
  std::vector<std::uint32_t> blocked(nodes, 0), outward(nodes, 0);
  std::vector<std::uint8_t> ahead(nodes), behind(nodes), walled(nodes);
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    through_rays(size, dirs[k], side, ahead);
    tbb::parallel_for(std::size_t{0}, nodes, [&](std::size_t i) {
      blocked[i] |= static_cast<std::uint32_t>(ahead[i] != 0) << k;
      outward[i] |= static_cast<std::uint32_t>(ahead[i] == 1) << k;
    });
  }
  std::vector<std::uint8_t> out(nodes, 0);
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    const Eigen::Vector3i& d = dirs[k];
    // One of each opposite pair: the first non-zero component positive.
    const int lead = d.x() != 0 ? d.x() : d.y() != 0 ? d.y() : d.z();
    if (lead < 0) continue;
    std::uint32_t across = 0, along = 0;
    for (std::size_t e = 0; e < dirs.size(); ++e) {
      if (dirs[e].dot(d) == 0) across |= std::uint32_t{1} << e;
      if (dirs[e] == d || dirs[e] == -d) along |= std::uint32_t{1} << e;
    }
    tbb::parallel_for(std::size_t{0}, nodes, [&](std::size_t i) {
      walled[i] = side[i] == 0 && (outward[i] & across) == across ? 1 : 0;
    });
    through_rays(size, d, walled, ahead);
    through_rays(size, -d, walled, behind);
    tbb::parallel_for(std::size_t{0}, nodes, [&](std::size_t i) {
      if (side[i] != 0 || (blocked[i] & along) != 0) return;
      if (walled[i] || ahead[i] || behind[i]) out[i] = 1;
    });
  }
  return out;
}

}  // namespace meshflow
