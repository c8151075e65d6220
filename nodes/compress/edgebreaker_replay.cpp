#include "nodes/compress/edgebreaker_replay.h"

#include "runtime/error.h"

namespace meshflow::compress {

// The loops are the walk's (nodes/compress/edgebreaker_connectivity.cpp): node n is the loop
// edge from its vertex to the next node's; the walked side of each edge is the region the walk
// has covered, the rebuilt side the triangles replayed so far. Every node is its own vertex copy
// (node n's vertex is copy n, in the triangles too): a vertex split by an S (or an M) has a copy
// per loop until undoing the split merges them. Nodes are never reused.

ReverseReplay::ReverseReplay(std::uint32_t components, std::size_t symbols, std::size_t vertices,
                             const std::vector<HandleRecord>& handles, std::string source)
    : source_(std::move(source)),
      components_left_(components),
      index_(symbols),
      vertices_(vertices),
      c_left_(0),
      handles_(handles),
      handle_(handles.size()) {
  if (vertices < 3 * std::size_t{components})
    throw Error(source_, "surface vertex count",
                std::to_string(vertices) + " is fewer than three per component (" +
                    std::to_string(components) + ")");
  c_left_ = vertices - 3 * std::size_t{components};
  if (c_left_ > symbols)
    throw Error(source_, "surface vertex count",
                std::to_string(vertices) + " vertices need more than the " +
                    std::to_string(symbols) + " symbols");
  triangles_.resize(symbols + components);
  predictors_.resize(vertices);
  // A node per L and R, three per E (at most a symbol and a quarter on any mesh meshflow makes;
  // more only grows the vectors).
  const std::size_t nodes = symbols + symbols / 4 + 3 * std::size_t{components} + 16;
  nodes_.reserve(nodes);
  grow_copies(nodes);
  diamonds_.reserve(3 * (symbols + components) / 2 + 3);  // a closed surface's edges
  update_step();
}

void ReverseReplay::fail(const std::string& problem) const {
  // The symbol being undone (index_ - 1), or the first when none is left.
  throw Error(source_, "connectivity symbol " + std::to_string(index_ == 0 ? 0 : index_ - 1),
              problem);
}

void ReverseReplay::grow_copies(std::size_t copies) {
  const std::size_t old = parent_.size();
  number_.resize(copies, kNone);
  parent_.resize(copies);
  for (std::size_t id = old; id < copies; ++id) parent_[id] = static_cast<std::uint32_t>(id);
}

inline std::uint32_t ReverseReplay::add_node() {
  const auto n = static_cast<std::uint32_t>(nodes_.size());
  nodes_.push_back({kNone, kNone, kNone, 0, kNone});
  if (n >= parent_.size()) grow_copies(2 * std::size_t{n} + 16);
  return n;
}

inline void ReverseReplay::resolve(std::uint32_t n, std::uint32_t w) {
  LoopNode& node = nodes_[n];
  if (node.waiting != kNone) predictors_[node.waiting].w = w;
  node.waiting = kNone;
  if (node.opposite != kNone) diamonds_.push_back({n, node.next, node.opposite, w});
}

inline void ReverseReplay::triangle(std::uint32_t b, std::uint32_t a, std::uint32_t x) {
  // Walk triangle k of component c is number k + c + 1 (each component starts with one); the
  // symbol being undone is k = index_ - 1 and c = components_left_ - 1.
  triangles_[index_ + components_left_ - 1] = {b, a, x};
  ++nodes_[a].incident;
  ++nodes_[b].incident;
  ++nodes_[x].incident;
}

inline void ReverseReplay::merge(std::uint32_t gone, std::uint32_t kept) {
  parent_[gone] = kept;
  nodes_[kept].incident += nodes_[gone].incident;
}

inline void ReverseReplay::undo_e() {
  // The E closed the loop p -> a -> b (gate a) and then took the loop on top of the stack, or
  // ended the component: the current loop (if any) goes back on the stack, p, a and b return
  // as new copies.
  if (open_) stack_.push_back({gate_, length_});
  const std::uint32_t p = add_node(), a = add_node(), b = add_node();
  link(p, a);
  link(a, b);
  link(b, p);
  triangle(b, a, p);
  nodes_[p].opposite = b;
  nodes_[a].opposite = p;
  nodes_[b].opposite = a;
  gate_ = a;
  length_ = 3;
  open_ = true;
}

inline void ReverseReplay::undo_c() {
  // a -> x -> b (gate x -> b) was a -> b before x was met (a loop of two at least): x is
  // complete.
  if (length_ < 3) fail("C on a loop of " + std::to_string(length_) + " (needs 3 or more)");
  if (c_left_ == 0) fail("more C symbols than the vertex count allows");
  const std::uint32_t xn = gate_, an = nodes_[xn].prev, bn = nodes_[xn].next;
  triangle(bn, an, xn);
  // Vertex numbers: each component's three, then one per C, in walk order.
  const std::size_t k = 3 * std::size_t{components_left_} + --c_left_;
  number_[xn] = static_cast<std::uint32_t>(k);  // xn is on a loop, so not completed before
  predictors_[k] = {an, bn, kNone};
  resolve(an, bn);
  resolve(xn, an);
  link(an, bn);
  nodes_[an].opposite = xn;
  nodes_[an].waiting = static_cast<std::uint32_t>(k);
  gate_ = an;
  --length_;
}

inline void ReverseReplay::undo_l() {
  // p -> b (gate p) was p -> a -> b (gate a): a returns as a new copy.
  const std::uint32_t pn = gate_, bn = nodes_[pn].next;
  const std::uint32_t an = add_node();
  triangle(bn, an, pn);
  resolve(pn, an);
  link(pn, an);
  link(an, bn);
  nodes_[pn].opposite = bn;
  nodes_[an].opposite = pn;
  gate_ = an;
  ++length_;
}

inline void ReverseReplay::undo_r() {
  // a -> q (gate a) was a -> b -> q (gate a): b returns as a new copy.
  const std::uint32_t an = gate_, qn = nodes_[an].next;
  const std::uint32_t bn = add_node();
  triangle(bn, an, qn);
  resolve(an, bn);
  link(an, bn);
  link(bn, qn);
  nodes_[an].opposite = qn;
  nodes_[bn].opposite = an;
  ++length_;
}

inline void ReverseReplay::undo_s() {
  // The current loop x -> b ... -> x (gate x) and the stacked a -> x' -> y ... -> a (gate a)
  // were one loop a -> b ... -> x -> y ... -> a (gate a).
  if (stack_.empty()) fail("S with no loop stacked");
  const Stacked left = stack_.back();
  stack_.pop_back();
  unsplit(left.node, gate_);
  gate_ = left.node;
  length_ = length_ + left.length - 1;
}

inline void ReverseReplay::unsplit(std::uint32_t an, std::uint32_t xn) {
  const std::uint32_t xc = nodes_[an].next, yn = nodes_[xc].next;
  const std::uint32_t bn = nodes_[xn].next, last = nodes_[xn].prev;
  merge(xc, xn);
  triangle(bn, an, xn);
  resolve(an, bn);
  resolve(xn, an);
  nodes_[xn].waiting = nodes_[xc].waiting;  // xn takes over x' -> y
  nodes_[xn].opposite = nodes_[xc].opposite;
  link(an, bn);
  nodes_[an].opposite = xn;
  link(last, xn);
  link(xn, yn);
}

void ReverseReplay::undo_m() {
  // The loop a -> x' -> y ... -> x -> b ... -> a (gate x) was two: a -> b ... -> a (gate a)
  // and the stacked x -> y ... -> x, `depth` below the top, x `offset` after its gate.
  if (handle_ == 0) fail("M without a handle record");
  const HandleRecord& r = handles_[--handle_];
  if (r.depth > stack_.size())
    fail("M names loop " + std::to_string(r.depth) + " of a stack of " +
         std::to_string(stack_.size()));
  if (r.length < 2 || std::size_t{r.length} + 3 > length_ || r.offset >= r.length)
    fail("M's loop of " + std::to_string(r.length) + " (offset " + std::to_string(r.offset) +
         ") does not fit the current loop of " + std::to_string(length_));
  const std::uint32_t xn = gate_;
  std::uint32_t an = xn;  // x' is the other loop's length before x, a one more
  for (std::uint32_t i = 0; i <= r.length; ++i) an = nodes_[an].prev;
  unsplit(an, xn);
  std::uint32_t other_gate = xn;
  for (std::uint32_t i = 0; i < r.offset; ++i) other_gate = nodes_[other_gate].prev;
  stack_.insert(stack_.end() - static_cast<std::ptrdiff_t>(r.depth), {other_gate, r.length});
  gate_ = an;
  length_ -= r.length + 1;
}

void ReverseReplay::apply(Op op) {
  if (step_ != Step::kSymbol) fail("a symbol where none is expected");
  switch (op) {
    case Op::kC:
      undo_c();
      break;
    case Op::kL:
      undo_l();
      break;
    case Op::kR:
      undo_r();
      break;
    case Op::kS:
      undo_s();
      break;
    case Op::kE:
      undo_e();
      break;
    case Op::kM:
      undo_m();
      break;
    default:
      fail("unknown symbol " + std::to_string(static_cast<int>(op)));
  }
  --index_;
  after_ = op;
  asked_ = false;
  // The common case of update_step(): a component open (an undo leaves it so), symbols left
  // and no component start possible here.
  if (index_ != 0 && (length_ != 3 || !stack_.empty())) {
    step_ = Step::kSymbol;
    return;
  }
  update_step();
}

void ReverseReplay::answer(bool starts) {
  if (step_ != Step::kComponentStart) fail("a component start where none is asked");
  if (starts)
    start_component();
  else
    asked_ = true;
  update_step();
}

void ReverseReplay::start_component() {
  // The component's first triangle v0 -> v1 -> v2 with the gate on v0 -> v1.
  const std::uint32_t n0 = gate_, n1 = nodes_[n0].next, n2 = nodes_[n1].next;
  --components_left_;
  const std::size_t base = 3 * std::size_t{components_left_} + c_left_;
  triangles_[index_ + components_left_] = {n0, n1, n2};
  const std::uint32_t n[3] = {n0, n1, n2};
  for (std::uint32_t i = 0; i < 3; ++i) number_[n[i]] = static_cast<std::uint32_t>(base + i);
  predictors_[base] = {};
  predictors_[base + 1] = {n0, kNone, kNone};
  predictors_[base + 2] = {n0, n1, kNone};
  resolve(n0, n2);
  resolve(n1, n0);
  resolve(n2, n1);
  open_ = false;
  asked_ = false;
}

inline void ReverseReplay::update_step() {
  for (;;) {
    if (!open_) {
      if (components_left_ == 0) {
        if (index_ != 0) fail(std::to_string(index_) + " symbols left before the first component");
        step_ = Step::kDone;
        return;
      }
      if (index_ == 0)
        fail("missing: " + std::to_string(components_left_) + " components have no symbols");
      undo_e();  // the implied E that ends the component
      --index_;
      after_ = Op::kE;
      continue;
    }
    const bool could_start = stack_.empty() && length_ == 3;
    if (index_ == 0) {
      if (!could_start) fail("missing: the symbols end inside a component");
      start_component();  // no symbol left: it must start here
      continue;
    }
    step_ = could_start && components_left_ > 1 && !asked_ ? Step::kComponentStart : Step::kSymbol;
    return;
  }
}

ReplayedSurface ReverseReplay::finish() {
  if (step_ != Step::kDone) fail("the replay is not finished");
  if (c_left_ != 0)
    throw Error(source_, "surface vertex count",
                std::to_string(vertices_) + " stored, the symbols make " +
                    std::to_string(vertices_ - c_left_));
  // Every copy's number is its merge root's.
  const auto root_number = [&](std::uint32_t id) {
    std::uint32_t r = id;
    while (parent_[r] != r) r = parent_[r];
    while (parent_[id] != r) {
      const std::uint32_t up = parent_[id];
      parent_[id] = r;
      id = up;
    }
    return number_[r];
  };
  for (std::uint32_t id = 0; id < nodes_.size(); ++id) number_[id] = root_number(id);
  ReplayedSurface out;
  out.vertex_count = static_cast<std::uint32_t>(vertices_);
  out.triangles = std::move(triangles_);
  for (std::size_t t = 0; t < out.triangles.size(); ++t) {
    Triangle& f = out.triangles[t];
    for (std::uint32_t& v : f) {
      v = number_[v];
      if (v == kNone)
        throw Error(source_, "connectivity triangle " + std::to_string(t),
                    "has a vertex no symbol completes");
    }
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2])
      throw Error(source_, "connectivity triangle " + std::to_string(t), "has a repeated vertex");
  }
  out.predictors = std::move(predictors_);
  out.diamonds = std::move(diamonds_);
  for (EdgeDiamond& d : out.diamonds)
    for (std::uint32_t* v : {&d.x, &d.y, &d.left, &d.right}) *v = number_[*v];
  for (VertexPredictors& p : out.predictors)
    for (std::uint32_t* v : {&p.a, &p.b, &p.w})
      if (*v != kNone) *v = number_[*v];
  return out;
}

}  // namespace meshflow::compress
