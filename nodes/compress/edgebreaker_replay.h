#pragma once
// Rebuilds a surface from its Edgebreaker symbols read backwards, last symbol first (Isenburg and
// Snoeyink's Spirale Reversi; Draco's decoder works the same way). Undoing the walk's symbols one
// by one keeps exactly the walk's loops and stack, so:
//  - an S needs no offset: undoing it joins the loop on top of the stack to the current one
//    (their split vertex's two copies become one);
//  - the triangles already rebuilt are those the walk had still ahead of it, so a symbol can be
//    predicted from how many of them meet the gate's two vertices (the valences Draco's default
//    coder uses as contexts); context() gives that context to the symbol coder.
// The encoder drives the same replay with its known symbols, so both sides see the same
// contexts, and gets the same numbering the decoder will make. Each component's last symbol (an
// E) is implied; where a component may start (a loop of three, nothing stacked) the coder is
// asked whether it does.

#include <cstdint>
#include <string>
#include <vector>

#include "nodes/compress/edgebreaker_connectivity.h"

namespace meshflow::compress {

/// The replay state machine. Usage: while (next() != kDone) apply() or answer(); then finish().
/// Not thread-safe; O(T) overall (an M walks its other loop) plus O(T log* T) for merging the
/// copies of split vertices.
class ReverseReplay {
 public:
  /// What the replay needs next.
  enum class Step : std::uint8_t {
    kSymbol,          ///< the walk's symbol symbols_left() - 1, through apply()
    kComponentStart,  ///< whether the current component starts here, through answer()
    kDone,            ///< every symbol and component is replayed; call finish()
  };
  /// Number of distinct values context() returns.
  static constexpr unsigned kContexts = 9 * 9 * kOpCount;

  /// `components` components of `symbols` symbols and `vertices` surface vertices, the walk's M
  /// records `handles` (in walk order; read in place, so they must outlive the replay). `source`
  /// names the data in errors. Throws Error for counts that cannot fit together.
  ReverseReplay(std::uint32_t components, std::size_t symbols, std::size_t vertices,
                const std::vector<HandleRecord>& handles, std::string source);

  /// What to supply next.
  Step next() const { return step_; }
  /// Symbols not yet undone: apply() expects the walk's symbol symbols_left() - 1.
  std::size_t symbols_left() const { return index_; }
  /// The component being replayed (they are replayed last first).
  std::uint32_t component() const { return components_left_ - 1; }
  /// The symbol's context: the number of rebuilt triangles at the gate's two vertices (each
  /// capped at 8) and the symbol after it in the walk. Below kContexts.
  unsigned context() const {
    const LoopNode& g = nodes_[gate_];
    const std::uint32_t a = g.incident, b = nodes_[g.next].incident;
    return ((a < 8 ? a : 8) * 9 + (b < 8 ? b : 8)) * kOpCount + static_cast<unsigned>(after_);
  }
  /// Undoes symbol symbols_left() - 1. Throws Error(source, "connectivity symbol K", ...) where the
  /// symbol cannot be undone on the current loops (so the data is not a walk).
  void apply(Op op);
  /// Whether the current component's first triangle comes next (answer to kComponentStart).
  void answer(bool starts);
  /// The surface: vertices numbered as the walk met them, triangles in walk order, predictors.
  /// Throws Error where the symbols leave vertices or triangles undefined.
  ReplayedSurface finish();

 private:
  // A loop edge from its vertex copy (the node's own number) to the next node's.
  struct LoopNode {
    std::uint32_t next, prev;
    std::uint32_t waiting;   // a C vertex whose predictor w is this edge's walked-side vertex
    std::uint32_t incident;  // rebuilt triangles at the copy (merged copies: all of them)
    std::uint32_t opposite;  // the third vertex (copy) of the edge's rebuilt-side triangle
  };
  struct Stacked {
    std::uint32_t node, length;
  };

  [[noreturn]] void fail(const std::string& problem) const;
  std::uint32_t add_node();              // a new node, its copy on no triangle yet
  void grow_copies(std::size_t copies);  // parent_ and number_ for `copies` nodes
  void link(std::uint32_t a, std::uint32_t b) {
    nodes_[a].next = b;
    nodes_[b].prev = a;
  }
  // The edge of node n loses its walked-side triangle, whose third vertex is `w`: the edge is
  // inside the rebuilt surface now (a diamond).
  void resolve(std::uint32_t n, std::uint32_t w);
  void triangle(std::uint32_t b, std::uint32_t a, std::uint32_t x);
  // Makes copy `gone` (its node leaving the loops) the same vertex as `kept`.
  void merge(std::uint32_t gone, std::uint32_t kept);
  void undo_e();
  void start_component();
  void undo_c();
  void undo_l();
  void undo_r();
  void undo_s();
  void undo_m();
  // Undoes a split (S or M) at the triangle b, a, x: a's node an is followed by x's copy x',
  // x's node xn (the gate) by b; a -> x' -> y and ... -> x -> b become a -> b and ... -> x -> y.
  void unsplit(std::uint32_t an, std::uint32_t xn);
  void update_step();

  std::string source_;
  std::uint32_t components_left_;
  std::size_t index_;     // symbols not yet undone
  std::size_t vertices_;  // surface vertices
  std::size_t c_left_;    // C symbols not yet undone (the vertex numbers they give)
  const std::vector<HandleRecord>& handles_;
  std::size_t handle_;  // M records not yet used
  bool open_ = false;   // a component is being replayed
  bool asked_ = false;  // kComponentStart answered "no" at this index
  Op after_ = Op::kE;   // the symbol undone last (the walk's next one)
  Step step_ = Step::kSymbol;

  std::vector<LoopNode> nodes_;
  std::uint32_t gate_ = 0, length_ = 0;
  std::vector<Stacked> stack_;
  // Per node (vertex copy; sized ahead of nodes_): its parent in the merge forest, its number
  // once completed.
  std::vector<std::uint32_t> parent_, number_;
  std::vector<Triangle> triangles_;           // per walk triangle, in copies
  std::vector<VertexPredictors> predictors_;  // per vertex number, in copies
  std::vector<EdgeDiamond> diamonds_;         // in copies
};

}  // namespace meshflow::compress
