#pragma once
// Volumetric diffusion (Davis, Marschner, Garr and Levoy, "Filling holes in complex surfaces
// using volumetric diffusion", 3DPVT 2002) on a dense lattice: nodes without data take the
// values of a discrete Laplace equation whose boundary values are the nodes with data, held
// fixed. Solved coarse to fine: each level's held nodes are restricted to a lattice of half the
// resolution until it is small, solved there, then interpolated back and smoothed level by
// level, so a gap many nodes wide fills in a few sweeps per level.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace meshflow {

/// A dense lattice of values, x fastest. `fixed` nodes keep their values; the others are solved.
struct DiffusionLattice {
  Eigen::Vector3i size = Eigen::Vector3i::Zero();  ///< nodes per axis
  std::vector<float> values;                       ///< one per node
  std::vector<std::uint8_t> fixed;                 ///< 1 = held (data), 0 = free (to fill)
  /// Empty (the Laplace equation), or one per node: free node i then solves the Poisson
  /// equation sum over its lattice neighbours j of (value_i - value_j) = source_i.
  std::vector<float> source;

  /// Index of node (x, y, z); each in [0, size).
  std::size_t index(int x, int y, int z) const {
    return (static_cast<std::size_t>(z) * static_cast<std::size_t>(size.y()) +
            static_cast<std::size_t>(y)) *
               static_cast<std::size_t>(size.x()) +
           static_cast<std::size_t>(x);
  }
  /// Number of nodes: size.x() * size.y() * size.z().
  std::size_t node_count() const {
    return static_cast<std::size_t>(size.x()) * static_cast<std::size_t>(size.y()) *
           static_cast<std::size_t>(size.z());
  }
};

struct DiffusionConfig {
  int sweeps_per_level = 40;  ///< red-black Gauss-Seidel sweeps on each level after prolongation
  int coarsest_sweeps = 500;  ///< sweeps on the coarsest level (from zero)
  /// A level with no axis longer than this many nodes is the last. Each level halves every
  /// axis of at least 3 nodes (a flat lattice keeps halving its long axes).
  int coarsest_size = 8;
};

/// Replaces the value of every free node of `lattice` by the diffusion of the fixed ones
/// (each free node the mean of its 6 neighbours, at convergence; plus source_i / neighbours
/// with a source). A lattice without fixed nodes is left at zero. Returns the number of levels
/// used. Parallel over z planes, one colour of the red-black order at a time: the result does not
/// depend on the thread count. O(nodes x sweeps_per_level) time. Extra memory: the coarser levels,
/// 5 bytes a node, with 1/7 as many nodes as the lattice when all three axes halve, 1/3 when two do
/// (a flat lattice), at most as many when one does.
int diffuse_free_nodes(DiffusionLattice& lattice, const DiffusionConfig& config = {});

/// Trilinear interpolation of a coarse lattice at a node of a finer one: coarse node c stands
/// for fine node step * c (componentwise, each step >= 1), so fine node `fine_node` (>= 0) lies
/// between coarse nodes fine_node / step and the next, clamped to the coarse lattice's last
/// node. The 8-corner blend the coarse-to-fine levels and the close stage's tiles share.
/// Thread-safe (reads only); O(1).
float interpolate_coarse(const DiffusionLattice& coarse, const Eigen::Vector3i& step,
                         const Eigen::Vector3i& fine_node);

/// interpolate_coarse() along one row of the fine lattice (fine nodes (x, y, z), x varying):
/// the y and z parts found once, the same value at each node. Reads only; O(1) a node.
class CoarseRowInterpolation {
 public:
  /// The row of fine nodes (x, y, z) over `coarse` (kept by reference: it must outlive this),
  /// `step` as interpolate_coarse()'s; the row's y and z weights computed here. O(1).
  CoarseRowInterpolation(const DiffusionLattice& coarse, const Eigen::Vector3i& step, int y, int z);
  /// interpolate_coarse(coarse, step, {x, y, z}).
  float at(int x) const;

 private:
  const DiffusionLattice& coarse_;
  int step_x_;
  std::size_t
      rows_[4];    // the coarse rows at (lo y, lo z), (hi y, lo z), (lo y, hi z), (hi y, hi z)
  float wy_, wz_;  // the weights of the hi rows along y and z
};

}  // namespace meshflow
