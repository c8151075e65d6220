#include "nodes/close/through_lines.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstddef>

namespace meshflow {
namespace {

// Walled nodes in a row along a line that make it a tunnel's (through_runs()).
constexpr int kThroughRun = 3;

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
// 0 (hit[j]: what the step into node j meets). Each node reads
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

// What a ray along d meets on its step into node j (from j - d): the nodes of the unit box
// between the two that the step passes, nearest first (those one axis step from j - d, then
// two, then j); on the first of these levels holding data, inside (2) if any node there is
// inside, else outside (1); 0 when the step passes no data. A diagonal step thus cannot slip
// between the nodes of a band one node thick (a sphere's band, seen in patches, let a face
// diagonal through its middle). Parallel over nodes; O(7 x nodes).
void through_step_hits(const Eigen::Vector3i& n, const Eigen::Vector3i& d,
                       const std::vector<std::uint8_t>& side, std::vector<std::uint8_t>& step) {
  const std::ptrdiff_t sx = 1, sy = n.x(), sz = static_cast<std::ptrdiff_t>(n.x()) * n.y();
  const auto offset = [&](const Eigen::Vector3i& q) {
    return q.x() * sx + q.y() * sy + q.z() * sz;
  };
  // The offsets from j - d of the nodes the step passes, grouped by their axis steps (the
  // nodes between j - d and j: inside the lattice when both ends are).
  std::array<std::array<std::ptrdiff_t, 3>, 3> levels{};
  std::array<int, 3> level_size{};
  for (int mask = 1; mask < 8; ++mask) {
    Eigen::Vector3i s = Eigen::Vector3i::Zero();
    int count = 0;
    bool fits = true;
    for (int a = 0; a < 3; ++a)
      if (mask >> a & 1) {
        fits = fits && d[a] != 0;
        s[a] = d[a];
        ++count;
      }
    if (!fits) continue;
    const auto l = static_cast<std::size_t>(count - 1);
    levels[l][static_cast<std::size_t>(level_size[l]++)] = offset(s);
  }
  const std::ptrdiff_t back = offset(d);
  // Nodes j with j - d inside: x in [x0, x1) of rows y - d.y() and z - d.z() inside.
  const int x0 = std::max(0, d.x()), x1 = n.x() + std::min(0, d.x());
  tbb::parallel_for(0, n.z(), [&](int z) {
    std::vector<std::uint8_t> level_row(static_cast<std::size_t>(n.x()));
    std::uint8_t* level = level_row.data();
    for (int y = 0; y < n.y(); ++y) {
      const std::ptrdiff_t row = y * sy + z * sz;
      const std::uint8_t* in = side.data() + row;
      std::uint8_t* out = step.data() + row;
      const bool row_inside =
          y - d.y() >= 0 && y - d.y() < n.y() && z - d.z() >= 0 && z - d.z() < n.z();
      const int from_x = row_inside ? x0 : n.x(), to_x = row_inside ? x1 : n.x();
      for (int x = 0; x < from_x; ++x) out[x] = in[x];
      for (int x = to_x; x < n.x(); ++x) out[x] = in[x];
      // Level by level over the row (vectorisable): a level counts where those before met
      // nothing.
      std::fill(out + from_x, out + to_x, std::uint8_t{0});
      for (std::size_t l = 0; l < 3; ++l) {
        if (level_size[l] == 0) continue;
        for (int x = from_x; x < to_x; ++x) level[x] = 0;
        for (int k = 0; k < level_size[l]; ++k) {
          const std::uint8_t* from = in - back + levels[l][static_cast<std::size_t>(k)];
          for (int x = from_x; x < to_x; ++x) level[x] = std::max(level[x], from[x]);
        }
        for (int x = from_x; x < to_x; ++x) out[x] = out[x] != 0 ? out[x] : level[x];
      }
    }
  });
}

// run[i] = 1 where node i starts kThroughRun walled nodes in a row along d (i, i + d, ...): a
// tunnel's observed part, deeper than a band is thick. A single walled node is a slit in a
// band (two patches of a sphere nearly meeting: at the slit's node the rays across meet the
// patches' outside layers), not a tunnel. Parallel over nodes; O(kThroughRun x nodes).
void through_runs(const Eigen::Vector3i& n, const Eigen::Vector3i& d,
                  const std::vector<std::uint8_t>& walled, std::vector<std::uint8_t>& run) {
  const std::ptrdiff_t sy = n.x(), sz = static_cast<std::ptrdiff_t>(n.x()) * n.y();
  const std::ptrdiff_t forward = d.x() + d.y() * sy + d.z() * sz;
  const int reach = kThroughRun - 1;
  // Nodes whose whole run q, q + d, ..., q + reach d is inside: x in [x0, x1).
  const int x0 = std::max(0, -reach * d.x()), x1 = n.x() - std::max(0, reach * d.x());
  tbb::parallel_for(0, n.z(), [&](int z) {
    for (int y = 0; y < n.y(); ++y) {
      std::uint8_t* out = run.data() + y * sy + z * sz;
      const std::uint8_t* in = walled.data() + y * sy + z * sz;
      const bool row_inside = y + reach * d.y() >= 0 && y + reach * d.y() < n.y() &&
                              z + reach * d.z() >= 0 && z + reach * d.z() < n.z();
      const int from_x = row_inside ? x0 : n.x(), to_x = row_inside ? x1 : n.x();
      for (int x = 0; x < from_x; ++x) out[x] = 0;
      for (int x = to_x; x < n.x(); ++x) out[x] = 0;
      for (int x = from_x; x < to_x; ++x) {
        std::uint8_t all = 1;
        for (int t = 0; t < kThroughRun && all; ++t) all = in[x + t * forward];
        out[x] = all;
      }
    }
  });
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
  std::vector<std::uint8_t> ahead(nodes), behind(nodes), walled(nodes), step(nodes), run(nodes);
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    through_step_hits(size, dirs[k], side, step);
    through_rays(size, dirs[k], step, ahead);
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
    through_runs(size, d, walled, run);
    through_rays(size, d, run, ahead);
    through_rays(size, -d, run, behind);
    tbb::parallel_for(std::size_t{0}, nodes, [&](std::size_t i) {
      if (side[i] != 0 || (blocked[i] & along) != 0) return;
      if (run[i] || ahead[i] || behind[i]) out[i] = 1;
    });
  }
  return out;
}

}  // namespace meshflow
