// Step 5 of the extrusion (seed 002 Fig. 9, the paper's reference [1]):
// short edges and small triangles of the swept region removed with the
// existing edit operators, towards the mean edge length L of B, then a
// tangential relaxation of the region's inner nodes projected back onto the
// swept surface (its triangles before the optimisation, an Embree BVH) so
// the surface stays where the sweep put it. The passes run over edges and
// nodes in index order, so the result is one fixed sequence of operators
// (independent of threads).
#include <atelier/systems/mesh/edit.h>
#include <atelier/systems/spatial/body_bvh.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "extrude_detail.h"

namespace atelier::extrude_detail {

namespace {

constexpr double kLow = 4.0 / 5.0, kHigh = 4.0 / 3.0;

double length(const Model& m, EdgeIdx e) {
  return (m.position(m.tail(halfedge_of(e, 0))) - m.position(m.tail(halfedge_of(e, 1)))).norm();
}

bool on_boundary(const Model& m, NodeIdx v) {
  bool b = false;
  m.for_each_outgoing(v, [&](HalfedgeIdx h) { b |= !m.face(h).valid() || !m.face(twin(h)).valid(); });
  return b;
}

Vec3d tri_normal(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  return (b - a).cross(c - a);
}

/// Moving r to p keeps every face around r (but those holding k) turned the
/// same way and makes no edge longer than `hi`.
bool collapse_ok(const Model& m, NodeIdx r, NodeIdx k, const Vec3d& p, double hi) {
  bool ok = true;
  std::vector<NodeIdx> f;
  m.for_each_outgoing(r, [&](HalfedgeIdx h) {
    if (!ok) return;
    const NodeIdx w = m.head(h);
    if (w != k && (m.position(w) - p).norm() > hi) ok = false;
    const FaceIdx face = m.face(h);
    if (!face.valid()) return;
    m.face_nodes(face, f);
    if (f.size() != 3 || std::find(f.begin(), f.end(), k) != f.end()) return;
    Vec3d q[3];
    for (int i = 0; i < 3; ++i) q[i] = f[i] == r ? p : m.position(f[i]);
    const Vec3d n0 = tri_normal(m.position(f[0]), m.position(f[1]), m.position(f[2]));
    const Vec3d n1 = tri_normal(q[0], q[1], q[2]);
    if (!(n0.dot(n1) > 0.1 * n0.norm() * n1.norm())) ok = false;
  });
  return ok;
}

/// Every face around v is new (v is inside the region, not on B or a border).
bool inner(const Model& m, const Region& r, NodeIdx v) {
  if (r.fixed(v)) return false;
  bool ok = true;
  m.for_each_outgoing(v, [&](HalfedgeIdx h) { ok = ok && r.is_new(m, m.face(h)) && r.is_new(m, m.face(twin(h))); });
  return ok;
}

/// Moves every inner node towards the centroid of its neighbours within
/// its tangent plane, then onto the swept surface; a move that would turn
/// a face over is skipped.
void relax(Model& m, const Region& r, const BodyBvh& swept) {
  std::vector<std::pair<NodeIdx, Vec3d>> moves;
  std::vector<NodeIdx> f;
  for (std::uint32_t i = 0; i < m.nodes.slots.capacity(); ++i) {
    const NodeIdx v{i};
    if (!m.alive(v) || m.is_isolated(v) || !inner(m, r, v)) continue;
    Vec3d c = Vec3d::Zero(), n = Vec3d::Zero();
    int k = 0;
    m.for_each_outgoing(v, [&](HalfedgeIdx h) {
      c += m.position(m.head(h));
      ++k;
      m.face_nodes(m.face(h), f);
      if (f.size() == 3) n += tri_normal(m.position(f[0]), m.position(f[1]), m.position(f[2]));
    });
    if (k == 0 || !(n.norm() > 0)) continue;
    n.normalize();
    const Vec3d p = m.position(v), d = c / k - p;
    const ClosestHit hit = swept.closest_point(p + d - d.dot(n) * n);
    if (hit.triangle != kNoTriangle && hit.point.allFinite()) moves.emplace_back(v, hit.point);
  }
  for (const auto& [v, q] : moves) {
    bool ok = true;
    m.for_each_outgoing(v, [&](HalfedgeIdx h) {
      m.face_nodes(m.face(h), f);
      if (f.size() != 3) return;
      Vec3d a[3];
      for (int i = 0; i < 3; ++i) a[i] = f[i] == v ? q : m.position(f[i]);
      const Vec3d n0 = tri_normal(m.position(f[0]), m.position(f[1]), m.position(f[2])),
                  n1 = tri_normal(a[0], a[1], a[2]);
      ok = ok && n0.dot(n1) > 0.5 * n0.norm() * n1.norm();
    });
    if (ok) m.nodes.position[v.value] = q;
  }
}

std::vector<EdgeIdx> editable_edges(const Model& m, const Region& r) {
  std::vector<EdgeIdx> out;
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e)
    if (m.alive(EdgeIdx{e}) && r.editable(m, EdgeIdx{e})) out.push_back(EdgeIdx{e});
  return out;
}

}  // namespace

bool Region::editable(const Model& m, EdgeIdx e) const noexcept {
  const FaceIdx a = m.face(halfedge_of(e, 0)), b = m.face(halfedge_of(e, 1));
  if (!a.valid() && !b.valid()) return false;
  return (!a.valid() || is_new(m, a)) && (!b.valid() || is_new(m, b));
}

EdgeLengthStats region_stats(const Model& m, const Region& r, double target) {
  EdgeLengthStats s;
  s.min = INFINITY;
  std::size_t in = 0;
  double sum = 0;
  for (EdgeIdx e : editable_edges(m, r)) {
    const double l = length(m, e);
    ++s.edges;
    sum += l;
    s.min = std::min(s.min, l);
    s.max = std::max(s.max, l);
    in += l >= kLow * target && l <= kHigh * target;
  }
  if (s.edges == 0) return EdgeLengthStats{};
  s.mean = sum / static_cast<double>(s.edges);
  s.within = static_cast<double>(in) / static_cast<double>(s.edges);
  return s;
}

Expected<OptimiseCounts> optimise_region(Model& m, const Region& r, std::span<const HalfedgeIdx> base_chain,
                                         double target, int passes, const ExecContext& ctx) {
  OptimiseCounts c;
  const double lo = kLow * target, hi = kHigh * target;
  EditOptions eo;
  eo.check_ring_nodes = false;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v}) && m.nodes.in_face[v].valid()) eo.check_ring_nodes = true;
  // B as a constraint: edge_collapse keeps the end lying on a mesh edge.
  MeshEdgeIdx temp;
  bool free = !base_chain.empty();
  for (HalfedgeIdx h : base_chain) free = free && h.valid() && !m.edges.mesh_edge[edge_of(h).value].valid();
  if (free) temp = m.new_mesh_edge(m.nodes.surface[m.tail(base_chain[0]).value], base_chain);
  // The swept surface as it is before the optimisation (relaxation target).
  std::vector<Vec3d> pts;
  std::vector<Triangle> tris;
  {
    std::vector<NodeIdx> f;
    for (std::uint32_t i = 0; i < m.faces.slots.capacity(); ++i) {
      if (!r.is_new(m, FaceIdx{i})) continue;
      m.face_nodes(FaceIdx{i}, f);
      for (std::size_t k = 1; k + 1 < f.size(); ++k) {
        tris.push_back({static_cast<std::uint32_t>(pts.size()), static_cast<std::uint32_t>(pts.size() + 1),
                        static_cast<std::uint32_t>(pts.size() + 2)});
        pts.push_back(m.position(f[0]));
        pts.push_back(m.position(f[k]));
        pts.push_back(m.position(f[k + 1]));
      }
    }
  }
  BodyBvh swept;
  const bool can_relax = !tris.empty() && swept.build(pts, tris, {}, ExecContext::sequential()).is_ok();

  for (int pass = 0; pass < passes; ++pass) {
    if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "extrude: cancelled");
    const std::size_t before = c.splits + c.collapses + c.swaps;
    // Long edges: split at the midpoint (on the swept triangulation).
    for (EdgeIdx e : editable_edges(m, r)) {
      if (!m.alive(e) || !r.editable(m, e) || !(length(m, e) > hi)) continue;
      const Vec3d mid = 0.5 * (m.position(m.tail(halfedge_of(e, 0))) + m.position(m.tail(halfedge_of(e, 1))));
      if (auto s = edge_split(m, m.handle(e), mid, eo)) ++c.splits;
    }
    // Short edges: collapse, B's end (or a boundary end) kept in place.
    for (EdgeIdx e : editable_edges(m, r)) {
      if (!m.alive(e) || !r.editable(m, e) || !(length(m, e) < lo)) continue;
      const NodeIdx a = m.tail(halfedge_of(e, 0)), b = m.tail(halfedge_of(e, 1));
      if (r.fixed(a) && r.fixed(b)) continue;
      NodeIdx keep = a, gone = b;
      if (r.fixed(b)) keep = b, gone = a;
      Vec3d p = 0.5 * (m.position(a) + m.position(b));
      if (r.fixed(keep)) {
        p = m.position(keep);
      } else {
        const bool ba = on_boundary(m, a), bb = on_boundary(m, b);
        if (ba && !bb) p = m.position(a);
        if (bb && !ba) p = m.position(b);
      }
      if (!collapse_ok(m, gone, keep, p, hi) || !collapse_ok(m, keep, gone, p, hi)) continue;
      const Vec3d keep_pos = m.position(keep);
      auto res = edge_collapse(m, m.handle(e), p, eo);
      if (!res) continue;
      const NodeIdx kept = res->kept.at(0).idx;
      if (r.fixed(keep) && (kept != keep || m.position(kept) != keep_pos))
        return Status(ErrorCode::kInternal, "extrude: a collapse moved base node " + std::to_string(keep.value));
      ++c.collapses;
    }
    // Swaps towards valence 6 (4 on the boundary); B's nodes do not count.
    for (EdgeIdx e : editable_edges(m, r)) {
      if (!m.alive(e) || !r.editable(m, e)) continue;
      const HalfedgeIdx h = halfedge_of(e, 0), t = halfedge_of(e, 1);
      if (!m.face(h).valid() || !m.face(t).valid()) continue;
      if (m.face_degree(m.face(h)) != 3 || m.face_degree(m.face(t)) != 3) continue;
      const NodeIdx a = m.tail(h), b = m.tail(t), x = m.head(m.next(h)), y = m.head(m.next(t));
      auto dev = [&](NodeIdx v, int delta) {
        if (r.fixed(v)) return 0;
        const int want = on_boundary(m, v) ? 4 : 6;
        return std::abs(static_cast<int>(m.degree(v)) + delta - want);
      };
      const int now = dev(a, 0) + dev(b, 0) + dev(x, 0) + dev(y, 0);
      const int then = dev(a, -1) + dev(b, -1) + dev(x, 1) + dev(y, 1);
      if (then >= now) continue;
      const Vec3d n0 = tri_normal(m.position(a), m.position(b), m.position(x)) +
                       tri_normal(m.position(b), m.position(a), m.position(y));
      const Vec3d n1 = tri_normal(m.position(x), m.position(y), m.position(b));
      const Vec3d n2 = tri_normal(m.position(y), m.position(x), m.position(a));
      if (!(n1.dot(n0) > 0 && n2.dot(n0) > 0 && n1.dot(n2) > 0.5 * n1.norm() * n2.norm())) continue;
      if ((m.position(x) - m.position(y)).norm() > hi) continue;
      if (auto s = edge_swap(m, m.handle(e), eo)) ++c.swaps;
    }
    if (can_relax) relax(m, r, swept);
    if (c.splits + c.collapses + c.swaps == before) break;
  }
  if (temp.valid()) m.delete_mesh_edge(temp);
  return c;
}

}  // namespace atelier::extrude_detail
