// The triangulated net of the Booleans and its checks (closed, oriented,
// 2-manifold, no duplicate vertices, no degenerate triangles), the box
// hierarchy and the candidate pairs (seed 004 section 2: "the
// intersections of the edges of a net with meshes of a second net").
#include <atelier/engine/parallel.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <sstream>

#include "boolean_detail.h"

namespace atelier::net_detail {

std::array<double, 6> tri_box(const TriMesh& m, std::uint32_t t) {
  const auto& v = m.tri[t];
  std::array<double, 6> b{};
  for (int k = 0; k < 3; ++k) {
    b[static_cast<std::size_t>(k)] = std::min({m.p[v[0]][k], m.p[v[1]][k], m.p[v[2]][k]});
    b[static_cast<std::size_t>(k + 3)] = std::max({m.p[v[0]][k], m.p[v[1]][k], m.p[v[2]][k]});
  }
  return b;
}

namespace {

bool overlap(const std::array<double, 6>& x, const std::array<double, 6>& y) noexcept {
  return x[0] <= y[3] && y[0] <= x[3] && x[1] <= y[4] && y[1] <= x[4] && x[2] <= y[5] && y[2] <= x[5];
}

void merge_box(std::array<double, 6>& into, const std::array<double, 6>& b) noexcept {
  for (std::size_t k = 0; k < 3; ++k) {
    into[k] = std::min(into[k], b[k]);
    into[k + 3] = std::max(into[k + 3], b[k + 3]);
  }
}

/// Whether two of the listed positions are equal (==, so -0 equals +0):
/// open addressing on their bits, linear in the count. Only a yes needs the
/// lexicographic sort, which then names the same pair as before.
bool has_equal_positions(std::span<const Vec3d> p, std::span<const std::uint32_t> list) {
  std::size_t cap = 16;
  while (cap < 2 * list.size()) cap *= 2;
  std::vector<std::uint32_t> slot(cap, kNil);
  auto bits = [](double x) {
    x += 0.0;  // -0 -> +0: equal doubles hash alike
    std::uint64_t u;
    std::memcpy(&u, &x, sizeof u);
    return u;
  };
  for (std::uint32_t v : list) {
    const Vec3d& x = p[v];
    std::uint64_t h = bits(x.x()) * 0x9e3779b97f4a7c15ull;
    h = (h ^ (h >> 29) ^ bits(x.y())) * 0xbf58476d1ce4e5b9ull;
    h = (h ^ (h >> 31) ^ bits(x.z())) * 0x94d049bb133111ebull;
    for (std::size_t i = (h ^ (h >> 32)) & (cap - 1);; i = (i + 1) & (cap - 1)) {
      if (slot[i] == kNil) {
        slot[i] = v;
        break;
      }
      if (p[slot[i]] == x) return true;
    }
  }
  return false;
}

/// Whether the polygon with corners c (four or more) is exactly planar and
/// strictly convex, decided with exact orient3d against one point q off its
/// plane: every corner on the plane of the first three, every turn
/// (c[i], c[i+1], c[i+2]) and every fan triangle (c[0], c[i], c[i+1]) of
/// the same nonzero sign (the fan condition rules out stars, whose turns
/// all agree). Such a polygon is split as the fan from its first corner,
/// without a new point: the centroid, rounded to doubles, is in general off
/// the plane, and the bent triangles about it can cross a neighbour once
/// the Boolean's new points are rounded (issue 24, round 19;
/// docs/glossary.md, "fan split of planar n-gons").
bool planar_convex(std::span<const Vec3d> p, std::span<const std::uint32_t> c) {
  const std::size_t n = c.size();
  const Vec3d &p0 = p[c[0]], &p1 = p[c[1]], &p2 = p[c[2]];
  int s = 0;
  Vec3d q = p0;
  for (int k = 0; k < 3 && s == 0; ++k) {
    q = p0;
    q[k] += 1.0 + std::abs(q[k]);  // always moves q[k] (no overflow below 1e308)
    s = orient3d(p0, p1, p2, q);
  }
  if (s == 0) return false;  // p0, p1, p2 collinear (or q did not leave the line)
  for (std::size_t i = 3; i < n; ++i)
    if (orient3d(p0, p1, p2, p[c[i]]) != 0) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (orient3d(p[c[i]], p[c[(i + 1) % n]], p[c[(i + 2) % n]], q) != s) return false;
  for (std::size_t i = 2; i + 1 < n; ++i)
    if (orient3d(p0, p[c[i]], p[c[i + 1]], q) != s) return false;
  return true;
}

}  // namespace

void sort_edge_keys(std::span<const std::uint64_t> key, std::size_t n_vertices, std::vector<std::uint32_t>& order) {
  const std::size_t n = key.size();
  std::vector<std::uint32_t> start(n_vertices + 1, 0);
  for (std::uint64_t k : key) ++start[static_cast<std::size_t>(k >> 32) + 1];
  for (std::size_t v = 0; v < n_vertices; ++v) start[v + 1] += start[v];
  order.resize(n);
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::uint32_t i = 0; i < n; ++i) order[fill[static_cast<std::size_t>(key[i] >> 32)]++] = i;
  }
  // Within a vertex: by key, then index (the indices went in increasing).
  auto before = [&](std::uint32_t x, std::uint32_t y) { return key[x] != key[y] ? key[x] < key[y] : x < y; };
  for (std::size_t v = 0; v < n_vertices; ++v) {
    const auto b = order.begin() + start[v], e = order.begin() + start[v + 1];
    if (e - b > 32) {
      std::sort(b, e, before);
      continue;
    }
    for (auto i = b + 1; i < e; ++i)
      for (auto j = i; j != b && before(*j, *(j - 1)); --j) std::iter_swap(j, j - 1);
  }
}

Status build_tri_mesh(const PolygonSoupView& soup, std::string name, TriMesh& out, const ExecContext& ctx, bool open) {
  out = TriMesh{};
  out.name = std::move(name);
  const std::string& nm = out.name;
  const std::size_t nf = soup.face_count();
  if (nf == 0) return fail(ErrorCode::kInvalidArgument, "net ", nm, ": no faces");
  if (soup.face_offsets.empty() || soup.face_offsets[0] != 0 || soup.face_offsets.back() != soup.face_nodes.size())
    return fail(ErrorCode::kInvalidArgument, "net ", nm, ": malformed polygon offsets");
  const std::size_t nv = soup.positions.size();
  if (nv >= kNil / 2) return fail(ErrorCode::kInvalidArgument, "net ", nm, ": too many vertices");
  std::vector<std::uint8_t> used(nv, 0);
  std::vector<std::uint32_t> face_using(nv, kNil);  // a face using each vertex, for messages
  std::size_t extra = 0, tris = 0;
  std::vector<std::uint8_t> fan_split(nf, 0);  // per polygon: split as a fan (planar_convex)
  for (std::size_t f = 0; f < nf; ++f) {
    const std::uint32_t b = soup.face_offsets[f], e = soup.face_offsets[f + 1];
    if (e < b || e - b < 3) return fail(ErrorCode::kDegenerate, "net ", nm, ": face ", f, " has fewer than 3 corners");
    for (std::uint32_t i = b; i < e; ++i) {
      const std::uint32_t v = soup.face_nodes[i];
      if (v >= nv) return fail(ErrorCode::kInvalidArgument, "net ", nm, ": face ", f, " names vertex ", v, " of ", nv);
      if (!is_finite(soup.positions[v]))
        return fail(ErrorCode::kDegenerate, "net ", nm, ": vertex ", v, " of face ", f, " is not finite");
      for (std::uint32_t j = b; j < i; ++j)
        if (soup.face_nodes[j] == v)
          return fail(ErrorCode::kDegenerate, "net ", nm, ": face ", f, " repeats vertex ", v);
      used[v] = 1;
      if (face_using[v] == kNil) face_using[v] = static_cast<std::uint32_t>(f);
    }
  }
  par::for_each_n(ctx, nf, [&](std::size_t f) {
    const std::uint32_t b = soup.face_offsets[f], e = soup.face_offsets[f + 1];
    if (e - b > 3) fan_split[f] = planar_convex(soup.positions, soup.face_nodes.subspan(b, e - b)) ? 1 : 0;
  });
  for (std::size_t f = 0; f < nf; ++f) {
    const std::uint32_t n = soup.face_offsets[f + 1] - soup.face_offsets[f];
    extra += n > 3 && !fan_split[f] ? 1 : 0;
    tris += n == 3 ? 1 : (fan_split[f] ? n - 2 : n);
  }
  out.p.assign(soup.positions.begin(), soup.positions.end());
  out.net_vertices = nv;
  out.p.reserve(nv + extra);
  out.tri.reserve(tris);
  out.face_of.reserve(tris);
  out.face_tri_begin.resize(nf + 1);
  for (std::size_t f = 0; f < nf; ++f) {
    out.face_tri_begin[f] = static_cast<std::uint32_t>(out.tri.size());
    const std::uint32_t b = soup.face_offsets[f], e = soup.face_offsets[f + 1];
    if (e - b == 3) {
      out.tri.push_back({soup.face_nodes[b], soup.face_nodes[b + 1], soup.face_nodes[b + 2]});
      out.face_of.push_back(static_cast<std::uint32_t>(f));
      continue;
    }
    if (fan_split[f]) {
      for (std::uint32_t i = b + 1; i + 1 < e; ++i) {
        out.tri.push_back({soup.face_nodes[b], soup.face_nodes[i], soup.face_nodes[i + 1]});
        out.face_of.push_back(static_cast<std::uint32_t>(f));
      }
      continue;
    }
    // Seed 004 section 2: an n-gon becomes n triangles around its centroid.
    Vec3d c = Vec3d::Zero();
    for (std::uint32_t i = b; i < e; ++i) c += soup.positions[soup.face_nodes[i]];
    c /= static_cast<double>(e - b);
    const auto ci = static_cast<std::uint32_t>(out.p.size());
    out.p.push_back(c);
    used.push_back(1);
    face_using.push_back(static_cast<std::uint32_t>(f));
    for (std::uint32_t i = b; i < e; ++i) {
      const std::uint32_t j = i + 1 < e ? i + 1 : b;
      out.tri.push_back({ci, soup.face_nodes[i], soup.face_nodes[j]});
      out.face_of.push_back(static_cast<std::uint32_t>(f));
    }
  }
  out.face_tri_begin[nf] = static_cast<std::uint32_t>(out.tri.size());
  const std::size_t nt = out.tri.size();

  // Duplicate vertices (exactly equal positions), centroids included.
  std::vector<std::uint32_t> order;
  order.reserve(out.p.size());
  for (std::uint32_t v = 0; v < out.p.size(); ++v)
    if (used[v]) order.push_back(v);
  if (!has_equal_positions(out.p, order)) order.clear();  // nothing to name: skip the sort
  auto lex = [&](std::uint32_t x, std::uint32_t y) {
    const Vec3d &p = out.p[x], &q = out.p[y];
    if (p.x() != q.x()) return p.x() < q.x();
    if (p.y() != q.y()) return p.y() < q.y();
    if (p.z() != q.z()) return p.z() < q.z();
    return x < y;
  };
  par::sort(ctx, order.begin(), order.end(), lex);
  for (std::size_t i = 1; i < order.size(); ++i)
    if (out.p[order[i - 1]] == out.p[order[i]]) {
      const std::uint32_t x = order[i - 1], y = order[i];
      auto what = [&](std::uint32_t v) {
        return (v < nv ? "vertex " + std::to_string(v) : "the centroid") + " of face " + std::to_string(face_using[v]);
      };
      return fail(ErrorCode::kDegenerate, "net ", nm, ": ", what(x), " and ", what(y),
                  " coincide (duplicate vertices)");
    }

  // Degenerate triangles (exactly collinear corners).
  std::vector<std::uint8_t> bad(nt, 0);
  par::for_each_n(ctx, nt, [&](std::size_t t) {
    const auto& v = out.tri[t];
    bad[t] = collinear(out.p[v[0]], out.p[v[1]], out.p[v[2]]) ? 1 : 0;
  });
  for (std::size_t t = 0; t < nt; ++t)
    if (bad[t])
      return fail(ErrorCode::kDegenerate, "net ", nm, ": face ", out.face_of[t],
                  out.tri.size() == nf ? "" : " (or a triangle of its centroid split)",
                  " is degenerate (collinear corners)");

  // Edges: every undirected edge in exactly two triangles, once each way.
  struct Half {
    std::uint64_t key;
    std::uint32_t tri;
    std::uint8_t k;
    bool forward;
  };
  std::vector<Half> half(3 * nt);
  par::for_each_n(ctx, nt, [&](std::size_t t) {
    for (std::uint8_t k = 0; k < 3; ++k) {
      const std::uint32_t u = out.tri[t][k], v = out.tri[t][(k + 1) % 3];
      half[3 * t + k] = {(std::uint64_t{std::min(u, v)} << 32) | std::max(u, v), static_cast<std::uint32_t>(t), k,
                         u < v};
    }
  });
  {
    // By (key, tri, k): halves were made in (tri, k) order.
    std::vector<std::uint64_t> keys(half.size());
    for (std::size_t i = 0; i < half.size(); ++i) keys[i] = half[i].key;
    std::vector<std::uint32_t> order;
    sort_edge_keys(keys, out.p.size(), order);
    std::vector<Half> sorted(half.size());
    for (std::size_t i = 0; i < half.size(); ++i) sorted[i] = half[order[i]];
    half = std::move(sorted);
  }
  out.tri_edge.assign(nt, {kNil, kNil, kNil});
  out.edge.reserve(3 * nt / 2);
  out.edge_tri.reserve(3 * nt / 2);
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j].key == half[i].key) ++j;
    const auto u = static_cast<std::uint32_t>(half[i].key >> 32), v = static_cast<std::uint32_t>(half[i].key);
    if (j - i == 1) {
      if (!open)
        return fail(ErrorCode::kTopology, "net ", nm, " is open: edge (", u, ", ", v, ") of face ",
                    out.face_of[half[i].tri], " has no neighbour");
      const auto e = static_cast<std::uint32_t>(out.edge.size());
      out.edge.push_back({u, v});
      out.edge_tri.push_back({half[i].tri, kNil});
      out.tri_edge[half[i].tri][half[i].k] = e;
      i = j;
      continue;
    }
    if (j - i > 2)
      return fail(ErrorCode::kNonManifold, "net ", nm, " is non-manifold: edge (", u, ", ", v, ") is shared by faces ",
                  out.face_of[half[i].tri], ", ", out.face_of[half[i + 1].tri], " and ", out.face_of[half[i + 2].tri]);
    if (half[i].forward == half[i + 1].forward)
      return fail(ErrorCode::kTopology, "net ", nm, " is inconsistently oriented: faces ", out.face_of[half[i].tri],
                  " and ", out.face_of[half[i + 1].tri], " run edge (", u, ", ", v, ") the same way");
    const auto e = static_cast<std::uint32_t>(out.edge.size());
    out.edge.push_back({u, v});
    out.edge_tri.push_back({half[i].tri, half[i + 1].tri});
    out.tri_edge[half[i].tri][half[i].k] = e;
    out.tri_edge[half[i + 1].tri][half[i + 1].k] = e;
    i = j;
  }

  // Non-manifold vertices: the triangles around a vertex form one fan.
  std::vector<std::uint32_t> degree(out.p.size(), 0), fan(out.p.size(), 0);
  std::vector<std::uint32_t> first(out.p.size(), kNil);
  for (std::uint32_t t = 0; t < nt; ++t)
    for (std::uint32_t v : out.tri[t]) {
      ++degree[v];
      if (first[v] == kNil) first[v] = t;
    }
  auto corner_of = [&](std::uint32_t t, std::uint32_t v) {
    for (std::uint32_t k = 0; k < 3; ++k)
      if (out.tri[t][k] == v) return k;
    return 3u;
  };
  std::vector<std::uint8_t> pinched(out.p.size(), 0);
  par::for_each_n(ctx, out.p.size(), [&](std::size_t vi) {
    const auto v = static_cast<std::uint32_t>(vi);
    if (first[v] == kNil) return;
    std::uint32_t t = first[v], count = 0;
    if (open) return;  // fans around boundary vertices are open: checked by the builder of the result
    do {
      ++count;
      const std::uint32_t k = corner_of(t, v);
      const std::uint32_t e = out.tri_edge[t][k];  // v -> next corner
      t = out.edge_tri[e][0] == t ? out.edge_tri[e][1] : out.edge_tri[e][0];
    } while (t != first[v] && count <= degree[v]);
    pinched[v] = count != degree[v];
  });
  for (std::uint32_t v = 0; v < out.p.size(); ++v)
    if (pinched[v])
      return fail(ErrorCode::kNonManifold, "net ", nm, " is non-manifold at vertex ", v,
                  " (its faces form several fans, e.g. face ", out.face_of[first[v]], ")");

  out.box.resize(nt);
  par::for_each_n(ctx, nt, [&](std::size_t t) { out.box[t] = tri_box(out, static_cast<std::uint32_t>(t)); });
  for (std::uint32_t v = 0; v < out.p.size(); ++v)
    if (used[v]) out.bounds.extend(out.p[v]);
  return {};
}

/// Leaf size of the box hierarchy: 8 triangles (their boxes are tested
/// contiguously, cheaper than the node pairs that smaller leaves make).
constexpr std::uint32_t kLeafSize = 8;

void build_bvh(const TriMesh& m, Bvh& out, const ExecContext& ctx) {
  // Triangles in Morton order of their box centres, then ranges halved: a
  // linear BVH (one parallel sort instead of a median search per level).
  const std::size_t nt = m.tri.size();
  out.nodes.clear();
  out.order.resize(nt);
  if (nt == 0) return;
  Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const double c = 0.5 * (m.box[t][static_cast<std::size_t>(k)] + m.box[t][static_cast<std::size_t>(k + 3)]);
      lo[k] = std::min(lo[k], c);
      hi[k] = std::max(hi[k], c);
    }
  const Vec3d ext = (hi - lo).cwiseMax(Vec3d::Constant(1e-300));
  auto spread = [](std::uint64_t x) {  // 21 bits -> every third of 63
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
  };
  std::vector<std::pair<std::uint64_t, std::uint32_t>> key(nt);
  par::for_each_n(ctx, nt, [&](std::size_t t) {
    std::uint64_t code = 0;
    for (int k = 0; k < 3; ++k) {
      const double c = 0.5 * (m.box[t][static_cast<std::size_t>(k)] + m.box[t][static_cast<std::size_t>(k + 3)]);
      const double u = std::clamp((c - lo[k]) / ext[k], 0.0, 1.0);
      code |= spread(static_cast<std::uint64_t>(u * 2097151.0)) << k;
    }
    key[t] = {code, static_cast<std::uint32_t>(t)};
  });
  par::sort(ctx, key.begin(), key.end(), std::less<>());
  for (std::size_t i = 0; i < nt; ++i) out.order[i] = key[i].second;
  out.nodes.reserve(nt / 2 + 8);
  struct Job {
    std::uint32_t node, first, count;
  };
  out.nodes.push_back({});
  std::vector<Job> stack{{0, 0, static_cast<std::uint32_t>(nt)}};
  while (!stack.empty()) {
    const Job j = stack.back();
    stack.pop_back();
    // Inner nodes keep their range too: the pair traversal splits the node
    // holding more triangles.
    out.nodes[j.node].first = j.first;
    out.nodes[j.node].count = j.count;
    if (j.count <= kLeafSize) continue;
    const std::uint32_t half = j.count / 2;
    const auto left = static_cast<std::uint32_t>(out.nodes.size());
    out.nodes[j.node].left = left;
    out.nodes.push_back({});
    out.nodes.push_back({});
    stack.push_back({left, j.first, half});
    stack.push_back({left + 1, j.first + half, j.count - half});
  }
  // Triangle boxes in leaf order: the pair tests read them contiguously.
  out.box.resize(nt);
  for (std::size_t i = 0; i < nt; ++i) out.box[i] = m.box[out.order[i]];
  // Boxes bottom-up: children always come after their parent.
  for (std::size_t n = out.nodes.size(); n-- > 0;) {
    Bvh::Node& node = out.nodes[n];
    if (node.left == kNil) {
      node.box = out.box[node.first];
      for (std::uint32_t i = node.first + 1; i < node.first + node.count; ++i) merge_box(node.box, out.box[i]);
    } else {
      node.box = out.nodes[node.left].box;
      merge_box(node.box, out.nodes[node.left + 1].box);
    }
  }
}

namespace {

/// Pairs of overlapping triangle boxes by a simultaneous traversal of two
/// hierarchies (one net against itself: self_check_pairs.cpp): node pairs are expanded
/// breadth-first into a frontier of independent tasks, run in parallel, and
/// the pairs are sorted, so the list is the same for any thread count.
// The frontier stops growing at 256 node pairs; one step makes at most
// three of each, so tasks (the frontier plus task 0) stay below this.
constexpr std::size_t kMaxTasks = 1024;

template <class Visit>
void dual_visit(const Bvh& ba, const Bvh& bb, const ExecContext& ctx, std::size_t& tasks, Visit&& visit) {
  tasks = 0;
  if (ba.nodes.empty() || bb.nodes.empty()) return;
  using NodePair = std::array<std::uint32_t, 2>;
  auto leaf = [](const Bvh::Node& n) { return n.left == kNil; };
  // Children to visit for a node pair.
  auto expand = [&](const NodePair& np, auto&& push) {
    const Bvh::Node& x = ba.nodes[np[0]];
    const Bvh::Node& y = bb.nodes[np[1]];
    // Split the node holding more triangles (a leaf never): halves the
    // boxes on both sides alike, so fewer node pairs overlap.
    const bool split_x = !leaf(x) && (leaf(y) || x.count >= y.count);
    if (split_x) {
      push({x.left, np[1]});
      push({x.left + 1, np[1]});
    } else {
      push({np[0], y.left});
      push({np[0], y.left + 1});
    }
  };
  auto leaf_pairs = [&](const NodePair& np, std::size_t task) {
    const Bvh::Node& x = ba.nodes[np[0]];
    const Bvh::Node& y = bb.nodes[np[1]];
    for (std::uint32_t i = x.first; i < x.first + x.count; ++i) {
      const std::array<double, 6> bi = ba.box[i];
      // A triangle whose box misses the other leaf's box meets none of its
      // triangles: one test instead of one per triangle there.
      if (!overlap(bi, y.box)) continue;
      for (std::uint32_t j = y.first; j < y.first + y.count; ++j)
        if (overlap(bi, bb.box[j])) visit(task, ba.order[i], bb.order[j]);
    }
  };
  auto both_leaves = [&](const NodePair& np) { return leaf(ba.nodes[np[0]]) && leaf(bb.nodes[np[1]]); };
  // Breadth-first frontier.
  std::vector<NodePair> frontier{{0, 0}};
  if (!overlap(ba.nodes[0].box, bb.nodes[0].box)) return;
  std::vector<NodePair> direct;  // leaf pairs met while building the frontier: task 0
  while (!frontier.empty() && frontier.size() < 256) {
    std::vector<NodePair> next;
    for (const NodePair& np : frontier) {
      if (both_leaves(np)) {
        direct.push_back(np);
        continue;
      }
      expand(np, [&](const NodePair& c) {
        if (overlap(ba.nodes[c[0]].box, bb.nodes[c[1]].box)) next.push_back(c);
      });
    }
    frontier = std::move(next);
  }
  tasks = frontier.size() + 1;
  for (const NodePair& np : direct) leaf_pairs(np, 0);
  ExecContext c = ctx;
  c.sequential_threshold = 2;
  c.grain = 1;
  par::for_each_n(c, frontier.size(), [&](std::size_t k) {
    std::vector<NodePair> stack{frontier[k]};
    while (!stack.empty()) {
      const NodePair np = stack.back();
      stack.pop_back();
      if (both_leaves(np)) {
        leaf_pairs(np, k + 1);
        continue;
      }
      expand(np, [&](const NodePair& ch) {
        if (overlap(ba.nodes[ch[0]].box, bb.nodes[ch[1]].box)) stack.push_back(ch);
      });
    }
  });
}

}  // namespace

std::vector<std::array<std::uint32_t, 2>> overlapping_pairs(const TriMesh& /*a*/, const Bvh& bvh_a,
                                                            const TriMesh& /*b*/, const Bvh& bvh_b,
                                                            const ExecContext& ctx) {
  // The hierarchies hold the triangle boxes (in leaf order).
  // One list per task (each task writes only its own).
  std::vector<std::vector<std::array<std::uint32_t, 2>>> lists(kMaxTasks);
  std::size_t tasks = 0;
  dual_visit(bvh_a, bvh_b, ctx, tasks, [&](std::size_t task, std::uint32_t i, std::uint32_t j) {
    lists[task].push_back({i, j});
  });
  std::vector<std::array<std::uint32_t, 2>> pairs;
  for (std::size_t k = 0; k < tasks; ++k) pairs.insert(pairs.end(), lists[k].begin(), lists[k].end());
  // Sorted: the same list for any thread count.
  par::sort(ctx, pairs.begin(), pairs.end(), [](const auto& x, const auto& y) { return x < y; });
  return pairs;
}

// first_self_crossing: self_check_pairs.cpp.

}  // namespace atelier::net_detail
