#include "nodes/compress/edgebreaker_connectivity.h"

#include <algorithm>

#include "runtime/error.h"

namespace meshflow::compress {
namespace {

// The active loops: doubly linked nodes, each a loop edge from its vertex to the next node's.
// The walk changes them by four operations; the decoder undoes them (edgebreaker_replay.cpp).
struct LoopNodes {
  struct Node {
    std::uint32_t vertex, next, prev;
  };
  std::vector<Node> nodes;

  std::uint32_t& next(std::uint32_t n) { return nodes[n].next; }
  std::uint32_t& prev(std::uint32_t n) { return nodes[n].prev; }
  std::uint32_t vertex(std::uint32_t n) const { return nodes[n].vertex; }
  std::uint32_t next(std::uint32_t n) const { return nodes[n].next; }

  std::uint32_t add(std::uint32_t v) {
    nodes.push_back({v, kNone, kNone});
    return static_cast<std::uint32_t>(nodes.size() - 1);
  }
  void link(std::uint32_t a, std::uint32_t b) {
    next(a) = b;
    prev(b) = a;
  }
  // C: gate g (a -> b) becomes a -> x -> b; returns the node of x (the next gate).
  std::uint32_t attach(std::uint32_t g, std::uint32_t x) {
    const std::uint32_t nx = add(x);
    link(nx, next(g));
    link(g, nx);
    return nx;
  }
  // L: p -> a -> b becomes p -> b; returns p (the next gate).
  std::uint32_t close_left(std::uint32_t g) {
    const std::uint32_t p = prev(g);
    link(p, next(g));
    return p;
  }
  // R: a -> b -> q becomes a -> q; returns a (the next gate).
  std::uint32_t close_right(std::uint32_t g) {
    link(g, next(next(g)));
    return g;
  }
  // S or M with x's node xn: a -> b ... x -> y becomes a -> x' -> y ... and x -> b ...;
  // returns x' (the new node, on a's side).
  std::uint32_t split(std::uint32_t g, std::uint32_t xn) {
    const std::uint32_t b = next(g);
    const std::uint32_t xc = add(vertex(xn));
    link(xc, next(xn));
    link(g, xc);
    link(xn, b);
    return xc;
  }
};

[[noreturn]] void internal(const char* what) {
  throw Error("edgebreaker", "traversal", std::string("internal inconsistency: ") + what);
}

class Encoder {
 public:
  explicit Encoder(const ClosedSurface& s)
      : s_(s),
        visited_(s.triangle_count(), 0),
        decoded_(s.vertex_count(), kNone),
        node_of_half_(s.corner_vertex.size(), kNone) {
    // A node per C, S and M and three per component: one per triangle and two more per
    // component (meshes with many components only grow the vectors).
    const std::size_t nodes = s.triangle_count() + 2;
    nodes_.nodes.reserve(nodes);
    half_.reserve(nodes);
    label_.reserve(nodes);
    out_.connectivity.ops.reserve(s.triangle_count());
    out_.surface_triangle.reserve(s.triangle_count());
    out_.surface_vertex.reserve(s.vertex_count());
  }

  // Walks every component.
  Traversal run() {
    for (std::uint32_t t = 0; t < s_.triangle_count(); ++t)
      if (!visited_[t]) component(t);
    return std::move(out_);
  }

 private:
  struct Stacked {
    std::uint32_t node, label;
  };

  std::uint32_t decode_id(std::uint32_t v) {
    decoded_[v] = static_cast<std::uint32_t>(out_.surface_vertex.size());
    out_.surface_vertex.push_back(v);
    return decoded_[v];
  }
  std::uint32_t new_node(std::uint32_t v, std::uint32_t half, std::uint32_t label) {
    const std::uint32_t n = nodes_.add(v);
    half_.push_back(half);
    label_.push_back(label);
    node_of_half_[half] = n;
    return n;
  }
  void set_half(std::uint32_t node, std::uint32_t half) {
    half_[node] = half;
    node_of_half_[half] = node;
  }
  void emit(Op op, std::uint32_t t) {
    out_.connectivity.ops.push_back(op);
    out_.surface_triangle.push_back(t);
  }

  void component(std::uint32_t t0) {
    ++out_.connectivity.components;
    out_.component_first_symbol.push_back(out_.connectivity.ops.size());
    visited_[t0] = 1;
    out_.surface_triangle.push_back(t0);
    const std::uint32_t h0 = 3 * t0;
    std::uint32_t ids[3];
    for (std::uint32_t i = 0; i < 3; ++i) ids[i] = decode_id(s_.corner_vertex[h0 + i]);
    std::uint32_t label = new_label(3);
    std::uint32_t nodes[3];
    for (std::uint32_t i = 0; i < 3; ++i) nodes[i] = new_node(ids[i], h0 + i, label);
    for (std::uint32_t i = 0; i < 3; ++i) nodes_.link(nodes[i], nodes[(i + 1) % 3]);
    std::uint32_t g = nodes[0];
    std::vector<Stacked> stack;
    for (;;) {
      const std::uint32_t h = half_[g];
      const std::uint32_t tw = s_.twin[h];
      const std::uint32_t t = tw / 3;
      const std::uint32_t left_half = next_half(tw), right_half = prev_half(tw);
      const std::uint32_t x = s_.corner_vertex[right_half];
      const bool left = visited_[s_.twin[left_half] / 3] != 0;
      const bool right = visited_[s_.twin[right_half] / 3] != 0;
      visited_[t] = 1;
      node_of_half_[h] = kNone;
      if (decoded_[x] == kNone) {
        emit(Op::kC, t);
        const std::uint32_t nx = nodes_.attach(g, decode_id(x));
        half_.push_back(kNone);
        label_.push_back(label);
        set_half(g, left_half);
        set_half(nx, right_half);
        ++length_[label];
        g = nx;
      } else if (left && right) {
        emit(Op::kE, t);
        const std::uint32_t p = nodes_.prev(g);
        if (nodes_.next(nodes_.next(g)) != p || nodes_.vertex(p) != decoded_[x]) internal("E");
        node_of_half_[half_[p]] = kNone;
        node_of_half_[half_[nodes_.next(g)]] = kNone;
        if (stack.empty()) return;
        g = stack.back().node;
        label = stack.back().label;
        stack.pop_back();
      } else if (left) {
        emit(Op::kL, t);
        const std::uint32_t p = nodes_.prev(g);
        if (half_[p] != s_.twin[left_half]) internal("L");
        node_of_half_[half_[p]] = kNone;
        g = nodes_.close_left(g);
        set_half(g, right_half);
        --length_[label];
      } else if (right) {
        emit(Op::kR, t);
        const std::uint32_t b = nodes_.next(g);
        if (half_[b] != s_.twin[right_half]) internal("R");
        node_of_half_[half_[b]] = kNone;
        g = nodes_.close_right(g);
        set_half(g, left_half);
        --length_[label];
      } else {
        const std::uint32_t xn = node_of(x, right_half);
        const std::uint32_t b = nodes_.next(g);
        if (label_[xn] == label) {
          emit(Op::kS, t);
          // Walk both parts at once to the split, so the cost is that of the shorter one.
          const std::uint32_t length = length_[label];
          std::uint32_t r = b, l = nodes_.next(xn), steps = 0;
          while (r != xn && l != g) {
            r = nodes_.next(r);
            l = nodes_.next(l);
            ++steps;
          }
          // Nodes from b to xn: offset + 1; from xn's next to g: length - offset - 1.
          const std::uint32_t offset = r == xn ? steps : length - 1 - (steps + 1);
          const std::uint32_t xc = split(g, xn, left_half, right_half, label);
          const std::uint32_t right_length = offset + 1, left_length = length - offset;
          // The shorter part gets a new label.
          if (r == xn) {
            const std::uint32_t fresh = new_label(right_length);
            relabel(b, xn, fresh);
            length_[label] = left_length;
            stack.push_back({g, label});
            label = fresh;
          } else {
            const std::uint32_t fresh = new_label(left_length);
            relabel(xc, g, fresh);
            length_[label] = right_length;
            stack.push_back({g, fresh});
          }
          g = xn;
        } else {
          emit(Op::kM, t);
          std::size_t k = stack.size();
          while (k > 0 && stack[k - 1].label != label_[xn]) --k;
          if (k == 0) internal("M without its loop");
          const Stacked other = stack[k - 1];
          std::uint32_t offset = 0;
          for (std::uint32_t n = other.node; n != xn; n = nodes_.next(n)) ++offset;
          out_.connectivity.handles.push_back(
              {static_cast<std::uint32_t>(stack.size() - k), offset, length_[other.label]});
          const std::uint32_t xc = split(g, xn, left_half, right_half, label);
          relabel(xc, xn, label);
          length_[label] += length_[other.label] + 1;
          stack.erase(stack.begin() + static_cast<std::ptrdiff_t>(k - 1));
          g = xn;
        }
      }
    }
  }

  // S and M: the triangle across gate g (its half-edges a -> x `left_half`, x -> b
  // `right_half`) joins x's node xn; returns x's new node on a's side (labelled `label`, which
  // the caller corrects where the parts differ).
  std::uint32_t split(std::uint32_t g, std::uint32_t xn, std::uint32_t left_half,
                      std::uint32_t right_half, std::uint32_t label) {
    const std::uint32_t old_half = half_[xn];
    const std::uint32_t xc = nodes_.split(g, xn);
    half_.push_back(kNone);
    label_.push_back(label);
    set_half(xc, old_half);
    set_half(xn, right_half);
    set_half(g, left_half);
    return xc;
  }

  // The loop node of decoded vertex x whose unwalked fan holds the triangle of `from` (a
  // half-edge leaving x): turns around x through unwalked triangles to the first walked one.
  std::uint32_t node_of(std::uint32_t x, std::uint32_t from) const {
    std::uint32_t e = from;
    for (std::size_t guard = 0; guard <= s_.corner_vertex.size(); ++guard) {
      const std::uint32_t te = s_.twin[e];  // ends at x
      if (visited_[te / 3]) {
        const std::uint32_t n = node_of_half_[te];
        if (n == kNone || nodes_.vertex(nodes_.next(n)) != decoded_[x]) internal("fan");
        return nodes_.next(n);
      }
      e = next_half(te);
    }
    internal("fan without a walked triangle");
  }

  std::uint32_t new_label(std::uint32_t length) {
    length_.push_back(length);
    return static_cast<std::uint32_t>(length_.size() - 1);
  }
  // Labels the nodes from `first` to `last` (inclusive, along next).
  void relabel(std::uint32_t first, std::uint32_t last, std::uint32_t label) {
    for (std::uint32_t n = first;; n = nodes_.next(n)) {
      label_[n] = label;
      if (n == last) break;
    }
  }

  const ClosedSurface& s_;
  std::vector<std::uint8_t> visited_;
  std::vector<std::uint32_t> decoded_;       // per surface vertex
  std::vector<std::uint32_t> node_of_half_;  // per half-edge on a loop
  LoopNodes nodes_;
  std::vector<std::uint32_t> half_, label_;  // per node
  std::vector<std::uint32_t> length_;        // per label
  Traversal out_;
};

}  // namespace

Traversal edgebreaker_traverse(const ClosedSurface& surface) { return Encoder(surface).run(); }

}  // namespace meshflow::compress
