// The triangulated net of the Booleans and its checks (closed, oriented,
// 2-manifold, no duplicate vertices, no degenerate triangles), the box
// hierarchy and the candidate pairs (seed 004 section 2: "the
// intersections of the edges of a net with meshes of a second net").
#include "boolean_detail.h"

#include <algorithm>
#include <numeric>
#include <sstream>

#include <atelier/engine/parallel.h>

namespace atelier::net_detail {

namespace {

template <class... A>
Status fail(ErrorCode c, const A&... parts) {
  std::ostringstream s;
  (s << ... << parts);
  return {c, s.str()};
}

std::array<double, 6> tri_box(const TriMesh& m, std::uint32_t t) {
  const auto& v = m.tri[t];
  std::array<double, 6> b{};
  for (int k = 0; k < 3; ++k) {
    b[static_cast<std::size_t>(k)] = std::min({m.p[v[0]][k], m.p[v[1]][k], m.p[v[2]][k]});
    b[static_cast<std::size_t>(k + 3)] = std::max({m.p[v[0]][k], m.p[v[1]][k], m.p[v[2]][k]});
  }
  return b;
}

bool overlap(const std::array<double, 6>& x, const std::array<double, 6>& y) noexcept {
  return x[0] <= y[3] && y[0] <= x[3] && x[1] <= y[4] && y[1] <= x[4] && x[2] <= y[5] && y[2] <= x[5];
}

void merge_box(std::array<double, 6>& into, const std::array<double, 6>& b) noexcept {
  for (std::size_t k = 0; k < 3; ++k) {
    into[k] = std::min(into[k], b[k]);
    into[k + 3] = std::max(into[k + 3], b[k + 3]);
  }
}

}  // namespace

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
    if (e - b > 3) ++extra;
    tris += e - b > 3 ? e - b : 1;
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
      return fail(ErrorCode::kDegenerate, "net ", nm, ": ", what(x), " and ", what(y), " coincide (duplicate vertices)");
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
                  out.tri.size() == nf ? "" : " (or a triangle of its centroid split)", " is degenerate (collinear corners)");

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
      half[3 * t + k] = {(std::uint64_t{std::min(u, v)} << 32) | std::max(u, v), static_cast<std::uint32_t>(t), k, u < v};
    }
  });
  par::sort(ctx, half.begin(), half.end(), [](const Half& x, const Half& y) {
    return x.key != y.key ? x.key < y.key : (x.tri != y.tri ? x.tri < y.tri : x.k < y.k);
  });
  out.tri_edge.assign(nt, {kNil, kNil, kNil});
  out.edge.reserve(3 * nt / 2);
  out.edge_tri.reserve(3 * nt / 2);
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j].key == half[i].key) ++j;
    const auto u = static_cast<std::uint32_t>(half[i].key >> 32), v = static_cast<std::uint32_t>(half[i].key);
    if (j - i == 1) {
      if (!open)
        return fail(ErrorCode::kTopology, "net ", nm, " is open: edge (", u, ", ", v, ") of face ", out.face_of[half[i].tri],
                    " has no neighbour");
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
      return fail(ErrorCode::kTopology, "net ", nm, " is inconsistently oriented: faces ", out.face_of[half[i].tri], " and ",
                  out.face_of[half[i + 1].tri], " run edge (", u, ", ", v, ") the same way");
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
      return fail(ErrorCode::kNonManifold, "net ", nm, " is non-manifold at vertex ", v, " (its faces form several fans, e.g. face ",
                  out.face_of[first[v]], ")");

  out.box.resize(nt);
  par::for_each_n(ctx, nt, [&](std::size_t t) { out.box[t] = tri_box(out, static_cast<std::uint32_t>(t)); });
  for (std::uint32_t v = 0; v < out.p.size(); ++v)
    if (used[v]) out.bounds.extend(out.p[v]);
  return {};
}

void build_bvh(const TriMesh& m, Bvh& out, const ExecContext& ctx) {
  (void)ctx;
  const std::size_t nt = m.tri.size();
  out.nodes.clear();
  out.order.resize(nt);
  std::iota(out.order.begin(), out.order.end(), 0u);
  if (nt == 0) return;
  std::vector<Vec3d> centre(nt);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) centre[t][k] = 0.5 * (m.box[t][static_cast<std::size_t>(k)] + m.box[t][static_cast<std::size_t>(k + 3)]);
  out.nodes.reserve(2 * nt / 2 + 1);
  struct Job {
    std::uint32_t node, first, count;
  };
  out.nodes.push_back({});
  std::vector<Job> stack{{0, 0, static_cast<std::uint32_t>(nt)}};
  while (!stack.empty()) {
    const Job j = stack.back();
    stack.pop_back();
    std::array<double, 6> box = m.box[out.order[j.first]];
    Vec3d lo = centre[out.order[j.first]], hi = lo;
    for (std::uint32_t i = j.first; i < j.first + j.count; ++i) {
      merge_box(box, m.box[out.order[i]]);
      lo = lo.cwiseMin(centre[out.order[i]]);
      hi = hi.cwiseMax(centre[out.order[i]]);
    }
    out.nodes[j.node].box = box;
    if (j.count <= 4) {
      out.nodes[j.node].first = j.first;
      out.nodes[j.node].count = j.count;
      continue;
    }
    int axis = 0;
    (hi - lo).maxCoeff(&axis);
    const std::uint32_t half = j.count / 2;
    auto b = out.order.begin() + j.first;
    std::nth_element(b, b + half, b + j.count, [&](std::uint32_t x, std::uint32_t y) {
      return centre[x][axis] != centre[y][axis] ? centre[x][axis] < centre[y][axis] : x < y;
    });
    const auto left = static_cast<std::uint32_t>(out.nodes.size());
    out.nodes[j.node].left = left;
    out.nodes.push_back({});
    out.nodes.push_back({});
    stack.push_back({left, j.first, half});
    stack.push_back({left + 1, j.first + half, j.count - half});
  }
}

namespace {

template <class Emit>
void query(const Bvh& bvh, const std::array<double, 6>& box, std::vector<std::uint32_t>& stack, Emit&& emit) {
  stack.clear();
  stack.push_back(0);
  while (!stack.empty()) {
    const Bvh::Node& n = bvh.nodes[stack.back()];
    stack.pop_back();
    if (!overlap(n.box, box)) continue;
    if (n.left != kNil) {
      stack.push_back(n.left);
      stack.push_back(n.left + 1);
      continue;
    }
    for (std::uint32_t i = n.first; i < n.first + n.count; ++i) emit(bvh.order[i]);
  }
}

template <class Filter>
std::vector<std::array<std::uint32_t, 2>> collect(const TriMesh& a, const TriMesh& b, const Bvh& bvh,
                                                  const ExecContext& ctx, Filter&& keep) {
  std::vector<std::array<std::uint32_t, 2>> pairs;
  if (bvh.nodes.empty()) return pairs;
  const std::size_t nt = a.tri.size();
  // Blocks of fixed size, results concatenated in block order: the list is
  // the same for any thread count (and sorted: blocks are in index order).
  constexpr std::size_t kBlock = 2048;
  const std::size_t blocks = (nt + kBlock - 1) / kBlock;
  std::vector<std::vector<std::array<std::uint32_t, 2>>> part(blocks);
  std::array<double, 6> bb{b.bounds.lo.x(), b.bounds.lo.y(), b.bounds.lo.z(),
                           b.bounds.hi.x(), b.bounds.hi.y(), b.bounds.hi.z()};
  ExecContext c = ctx;
  c.sequential_threshold = std::max<std::size_t>(1, ctx.sequential_threshold / kBlock);
  c.grain = 1;
  par::for_each_n(c, blocks, [&](std::size_t blk) {
    std::vector<std::uint32_t> stack;
    std::vector<std::uint32_t> hits;
    auto& out = part[blk];
    const std::size_t end = std::min(nt, (blk + 1) * kBlock);
    for (std::size_t i = blk * kBlock; i < end; ++i) {
      if (!overlap(a.box[i], bb)) continue;
      hits.clear();
      query(bvh, a.box[i], stack, [&](std::uint32_t j) {
        if (keep(static_cast<std::uint32_t>(i), j)) hits.push_back(j);
      });
      std::sort(hits.begin(), hits.end());
      for (std::uint32_t j : hits) out.push_back({static_cast<std::uint32_t>(i), j});
    }
  });
  std::size_t total = 0;
  for (const auto& p : part) total += p.size();
  pairs.reserve(total);
  for (const auto& p : part) pairs.insert(pairs.end(), p.begin(), p.end());
  return pairs;
}

}  // namespace

std::vector<std::array<std::uint32_t, 2>> overlapping_pairs(const TriMesh& a, const Bvh& bvh_b, const TriMesh& b,
                                                            const ExecContext& ctx) {
  return collect(a, b, bvh_b, ctx, [](std::uint32_t, std::uint32_t) { return true; });
}

std::vector<std::array<std::uint32_t, 2>> self_pairs(const TriMesh& m, const Bvh& bvh, const ExecContext& ctx) {
  return collect(m, m, bvh, ctx, [](std::uint32_t i, std::uint32_t j) { return i < j; });
}

}  // namespace atelier::net_detail
