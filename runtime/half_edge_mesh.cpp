#include "runtime/half_edge_mesh.h"

#include <algorithm>
#include <string>

#include "runtime/error.h"

namespace meshflow {
namespace {

std::string edge_name(std::uint32_t a, std::uint32_t b) {
  return "edge " + std::to_string(a) + "-" + std::to_string(b);
}

}  // namespace

HalfEdgeMesh::HalfEdgeMesh(const TriangleMesh& mesh)
    : positions_(mesh.vertices),
      to_(mesh.triangles.size() * 3),
      twin_(mesh.triangles.size() * 3, kNone),
      out_(mesh.vertices.size(), kNone),
      alive_(mesh.triangles.size(), 1),
      live_faces_(mesh.triangles.size()) {
  const std::size_t v_count = positions_.size();
  require_corners_in_range(mesh.triangles, v_count, "half-edge mesh");
  for (std::uint32_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
      throw Error("half-edge mesh", "face " + std::to_string(f), "repeats a vertex");
    to_[3 * f] = t[1];
    to_[3 * f + 1] = t[2];
    to_[3 * f + 2] = t[0];
  }
  // Twins: each directed edge at most once; its reverse, when present, is the twin.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> directed(to_.size());
  for (std::uint32_t h = 0; h < to_.size(); ++h)
    directed[h] = {std::uint64_t{from(h)} << 32 | to_[h], h};
  std::sort(directed.begin(), directed.end());
  for (std::size_t i = 1; i < directed.size(); ++i)
    if (directed[i].first == directed[i - 1].first) {
      const std::uint32_t h = directed[i].second;
      throw Error("half-edge mesh", edge_name(from(h), to_[h]),
                  "used twice in the same direction (non-manifold or inconsistently oriented)");
    }
  for (std::uint32_t h = 0; h < to_.size(); ++h) {
    const std::uint64_t reverse = std::uint64_t{to_[h]} << 32 | from(h);
    const auto it = std::lower_bound(directed.begin(), directed.end(),
                                     std::make_pair(reverse, std::uint32_t{0}));
    if (it != directed.end() && it->first == reverse) twin_[h] = it->second;
  }
  // Outgoing half-edges, then one fan per vertex.
  std::vector<std::uint32_t> faces_at(v_count, 0);
  for (std::uint32_t h = 0; h < to_.size(); ++h) {
    out_[from(h)] = h;
    ++faces_at[from(h)];
  }
  for (std::uint32_t v = 0; v < v_count; ++v) {
    if (out_[v] == kNone) continue;
    set_outgoing(v);
    // ring() lists one outgoing half-edge per face reachable around v.
    const std::size_t fan = ring(v).size();
    if (fan != faces_at[v])
      throw Error("half-edge mesh", "vertex " + std::to_string(v),
                  "its " + std::to_string(faces_at[v]) + " triangles form more than one fan (" +
                      std::to_string(fan) + " reachable around it): non-manifold vertex");
  }
}

void HalfEdgeMesh::set_outgoing(std::uint32_t v) {
  // Turn clockwise (next of the twin) until a border half-edge leaves v, or back to the start.
  const std::uint32_t start = out_[v];
  std::uint32_t h = start;
  while (twin_[h] != kNone) {
    h = next(twin_[h]);
    if (h == start) break;
  }
  out_[v] = h;
}

bool HalfEdgeMesh::is_border_vertex(std::uint32_t v) const {
  return out_[v] != kNone && twin_[out_[v]] == kNone;
}

std::vector<std::uint32_t> HalfEdgeMesh::ring(std::uint32_t v) const {
  std::vector<std::uint32_t> out;
  const std::uint32_t start = out_[v];
  if (start == kNone) return out;
  std::uint32_t h = start;
  do {
    out.push_back(h);
    h = twin_[prev(h)];  // counter-clockwise to the next face
  } while (h != kNone && h != start && out.size() <= to_.size());
  return out;
}

std::vector<std::vector<std::uint32_t>> HalfEdgeMesh::border_loops() const {
  std::vector<std::vector<std::uint32_t>> loops;
  std::vector<std::uint8_t> seen(to_.size(), 0);
  for (std::uint32_t h = 0; h < to_.size(); ++h) {
    if (twin_[h] != kNone || seen[h] || !alive_[face(h)]) continue;
    std::vector<std::uint32_t> loop;
    for (std::uint32_t e = h; !seen[e]; e = out_[to_[e]]) {
      seen[e] = 1;
      loop.push_back(e);
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

std::uint32_t HalfEdgeMesh::find_half_edge(std::uint32_t a, std::uint32_t b) const {
  for (std::uint32_t h : ring(a))
    if (to_[h] == b) return h;
  return kNone;
}

bool HalfEdgeMesh::flip(std::uint32_t h) {
  const std::uint32_t t = twin_[h];
  if (t == kNone) return false;
  const std::uint32_t a = from(h), b = to_[h], c = to_[next(h)], d = to_[next(t)];
  if (c == d || find_half_edge(c, d) != kNone || find_half_edge(d, c) != kNone) return false;
  for (std::uint32_t v : {a, b})
    if (!is_border_vertex(v) && ring(v).size() <= 3) return false;
  // Geometry: both new faces keep area and face the way the old pair faced (the quad a, d, b, c
  // is convex at c-d).
  auto normal = [&](std::uint32_t x, std::uint32_t y, std::uint32_t z) -> Eigen::Vector3f {
    return (positions_[y] - positions_[x]).cross(positions_[z] - positions_[x]);
  };
  const Eigen::Vector3f before = normal(a, b, c) + normal(b, a, d);
  const Eigen::Vector3f n1 = normal(a, d, c), n2 = normal(d, b, c);
  if (!(n1.dot(before) > 0.0f && n2.dot(before) > 0.0f)) return false;
  if (!has_area(positions_[a], positions_[d], positions_[c]) ||
      !has_area(positions_[d], positions_[b], positions_[c]))
    return false;
  // Outer half-edges and their twins before rewriting.
  const std::uint32_t bc = next(h), ca = prev(h), ad = next(t), db = prev(t);
  const std::uint32_t x_bc = twin_[bc], x_ca = twin_[ca], x_ad = twin_[ad], x_db = twin_[db];
  const std::uint32_t f1 = 3 * face(h), f2 = 3 * face(t);
  // Face 1 = (a, d, c): a->d, d->c, c->a. Face 2 = (d, b, c): d->b, b->c, c->d.
  set_face(f1, d, c, a);
  set_face(f2, b, c, d);
  link(f1, x_ad);
  link(f1 + 2, x_ca);
  link(f2, x_db);
  link(f2 + 1, x_bc);
  link(f1 + 1, f2 + 2);
  out_[a] = f1;
  out_[d] = f2;
  out_[b] = f2 + 1;
  out_[c] = f1 + 2;
  for (std::uint32_t v : {a, b, c, d}) set_outgoing(v);
  return true;
}

void HalfEdgeMesh::set_face(std::uint32_t first, std::uint32_t to0, std::uint32_t to1,
                            std::uint32_t to2) {
  to_[first] = to0;
  to_[first + 1] = to1;
  to_[first + 2] = to2;
}

void HalfEdgeMesh::link(std::uint32_t x, std::uint32_t y) {
  if (x != kNone) twin_[x] = y;
  if (y != kNone) twin_[y] = x;
}

std::vector<std::uint32_t> HalfEdgeMesh::neighbours(std::uint32_t v) const {
  std::vector<std::uint32_t> n;
  for (std::uint32_t h : ring(v)) {
    n.push_back(to_[h]);
    n.push_back(from(prev(h)));  // the face's third vertex (covers a border's last neighbour)
  }
  std::sort(n.begin(), n.end());
  n.erase(std::unique(n.begin(), n.end()), n.end());
  return n;
}

bool HalfEdgeMesh::collapse(std::uint32_t h) {
  if (!alive_[face(h)]) return false;
  const std::uint32_t t = twin_[h];
  const std::uint32_t a = from(h), b = to_[h], c = to_[next(h)];
  const std::uint32_t d = t != kNone ? to_[next(t)] : kNone;
  // Topology: the link condition.
  if (t != kNone && is_border_vertex(a) && is_border_vertex(b)) return false;
  const auto na = neighbours(a), nb = neighbours(b);
  std::vector<std::uint32_t> common;
  std::set_intersection(na.begin(), na.end(), nb.begin(), nb.end(), std::back_inserter(common));
  if (common.size() != (t != kNone ? 2u : 1u)) return false;
  if (live_faces_ <= 4) return false;
  // Geometry: faces that move with a keep area and orientation.
  const std::vector<std::uint32_t> around_a = ring(a);
  for (std::uint32_t e : around_a) {
    const std::uint32_t f = face(e);
    if (f == face(h) || (t != kNone && f == face(t))) continue;
    const std::uint32_t x = to_[e], y = to_[next(e)];  // face (a, x, y)
    const Eigen::Vector3f before =
        (positions_[x] - positions_[a]).cross(positions_[y] - positions_[a]);
    const Eigen::Vector3f after =
        (positions_[x] - positions_[b]).cross(positions_[y] - positions_[b]);
    if (!(after.dot(before) > 0.0f) || !has_area(positions_[b], positions_[x], positions_[y]))
      return false;
  }
  // The faces along a-b go; their outer edges pair up: (c->b's twin, a->c's twin), and on the
  // other side (a->d's twin... d->a), (b->d).
  const std::uint32_t x_bc = twin_[next(h)], x_ca = twin_[prev(h)];
  link(x_bc, x_ca);
  alive_[face(h)] = 0;
  --live_faces_;
  std::uint32_t x_ad = kNone, x_db = kNone;
  if (t != kNone) {
    x_ad = twin_[next(t)];
    x_db = twin_[prev(t)];
    link(x_ad, x_db);
    alive_[face(t)] = 0;
    --live_faces_;
  }
  // a's remaining half-edges now start / end at b.
  for (std::uint32_t e : around_a)
    if (alive_[face(e)]) to_[prev(e)] = b;
  out_[a] = kNone;
  // Fresh outgoing half-edges for b, c, d from the surviving neighbours of the removed faces.
  auto refresh = [&](std::uint32_t v, std::initializer_list<std::uint32_t> candidates) {
    for (std::uint32_t e : candidates) {
      if (e == kNone || !alive_[face(e)]) continue;
      for (std::uint32_t k : {e, next(e), prev(e)})
        if (from(k) == v) {
          out_[v] = k;
          set_outgoing(v);
          return;
        }
    }
    out_[v] = kNone;
  };
  refresh(b, {x_bc, x_ca, x_ad, x_db});
  refresh(c, {x_bc, x_ca});
  if (d != kNone) refresh(d, {x_ad, x_db});
  return true;
}

std::uint32_t HalfEdgeMesh::split(std::uint32_t h, const Eigen::Vector3f& p) {
  const std::uint32_t t = twin_[h];
  const std::uint32_t a = from(h), b = to_[h], c = to_[next(h)];
  const std::uint32_t m = static_cast<std::uint32_t>(positions_.size());
  positions_.push_back(p);
  out_.push_back(kNone);
  const std::uint32_t x_bc = twin_[next(h)], x_ca = twin_[prev(h)];
  auto new_face = [&]() {
    const std::uint32_t f = static_cast<std::uint32_t>(to_.size());
    to_.resize(to_.size() + 3, kNone);
    twin_.resize(twin_.size() + 3, kNone);
    alive_.push_back(1);
    ++live_faces_;
    return f;
  };
  // Face 1 becomes (a, m, c): a->m, m->c, c->a; the new face g1 is (m, b, c): m->b, b->c, c->m.
  const std::uint32_t f1 = 3 * face(h), g1 = new_face();
  set_face(f1, m, c, a);
  set_face(g1, b, c, m);
  twin_[f1] = kNone;
  link(f1 + 1, g1 + 2);
  link(f1 + 2, x_ca);
  link(g1 + 1, x_bc);
  twin_[g1] = kNone;
  std::uint32_t d = kNone;
  if (t != kNone) {
    d = to_[next(t)];
    const std::uint32_t x_ad = twin_[next(t)], x_db = twin_[prev(t)];
    // Face 2 becomes (b, m, d): b->m, m->d, d->b; the new face g2 is (m, a, d): m->a, a->d, d->m.
    const std::uint32_t f2 = 3 * face(t), g2 = new_face();
    set_face(f2, m, d, b);
    set_face(g2, a, d, m);
    link(f2 + 1, g2 + 2);
    link(f2 + 2, x_db);
    link(g2 + 1, x_ad);
    link(f2, g1);  // b->m with m->b
    link(g2, f1);  // m->a with a->m
  }
  out_[m] = f1 + 1;
  out_[a] = f1;
  out_[b] = g1 + 1;
  out_[c] = f1 + 2;
  for (std::uint32_t v : {m, a, b, c}) set_outgoing(v);
  if (d != kNone) {
    out_[d] = 3 * face(t) + 2;
    set_outgoing(d);
  }
  return m;
}

std::string HalfEdgeMesh::check() const {
  for (std::uint32_t h = 0; h < to_.size(); ++h) {
    if (!alive_[face(h)]) continue;
    const std::uint32_t t = twin_[h];
    if (to_[h] == from(h)) return "half-edge " + std::to_string(h) + " is a loop";
    if (t != kNone && !alive_[face(t)])
      return "half-edge " + std::to_string(h) + " twins a removed face";
    if (t == kNone) continue;
    if (twin_[t] != h || to_[t] != from(h) || from(t) != to_[h])
      return "half-edge " + std::to_string(h) + " and its twin disagree";
  }
  std::vector<std::uint32_t> faces_at(out_.size(), 0);
  for (std::uint32_t h = 0; h < to_.size(); ++h)
    if (alive_[face(h)]) ++faces_at[from(h)];
  for (std::uint32_t v = 0; v < out_.size(); ++v) {
    if (out_[v] == kNone) {
      if (faces_at[v] != 0) return "vertex " + std::to_string(v) + " has faces but no outgoing";
      continue;
    }
    if (ring(v).size() != faces_at[v])
      return "vertex " + std::to_string(v) + " is not one fan (non-manifold)";
    if (from(out_[v]) != v || !alive_[face(out_[v])])
      return "outgoing half-edge of vertex " + std::to_string(v);
    for (std::uint32_t h : ring(v))
      if (twin_[h] == kNone && h != out_[v])
        return "vertex " + std::to_string(v) + " has a border half-edge besides its outgoing one";
  }
  return {};
}

TriangleMesh HalfEdgeMesh::to_triangle_mesh() const {
  TriangleMesh mesh;
  std::vector<std::uint32_t> id(positions_.size(), kNone);
  for (std::uint32_t h = 0; h < to_.size(); ++h)
    if (alive_[face(h)]) id[to_[h]] = 0;
  for (std::uint32_t v = 0; v < positions_.size(); ++v) {
    if (id[v] == kNone) continue;
    id[v] = static_cast<std::uint32_t>(mesh.vertices.size());
    mesh.vertices.push_back(positions_[v]);
  }
  for (std::uint32_t f = 0; f < face_count(); ++f)
    if (alive_[f])
      mesh.triangles.push_back(Triangle{id[from(3 * f)], id[from(3 * f + 1)], id[from(3 * f + 2)]});
  return mesh;
}

}  // namespace meshflow
