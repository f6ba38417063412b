// Why this file is long: seed 002's four re-triangulation steps share one
// plan (points, segments, split edges, per-fan triangulations) that must be
// complete before the first write for the operator to be transactional;
// planning and applying read the same private tables.
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <atelier/engine/math.h>
#include <atelier/engine/status_format.h>
#include <atelier/storage/mesh_edge_chain.h>
#include <atelier/systems/mesh/edit.h>
#include <atelier/systems/sketch/retriangulate.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <memory_resource>
#include <unordered_map>

namespace atelier {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, K>;
using Fbi = CGAL::Triangulation_face_base_with_info_2<int, K>;
using Fb = CGAL::Constrained_triangulation_face_base_2<K, Fbi>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
// Crossings are inserted beforehand; a constraint may still pass through a
// collinear point (it is then split there, which the edge check reports).
using Cdt =
    CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::No_constraint_intersection_requiring_constructions_tag>;

enum class LK : std::uint8_t { kNode, kEdge, kDiag, kFan };

/// A canonical surface point: a node, an edge point (u from tail(2e)), a
/// fan-diagonal point (face, d: diagonal c0 - c_d, u from c0), or a point
/// inside a fan triangle (face, fan j, areal coordinates).
struct Loc {
  LK k = LK::kNode;
  std::uint32_t a = 0, b = 0;
  double u = 0;
  Vec3d bary = Vec3d::Zero();
};

struct Pt {
  Loc loc;
  NodeIdx node;  // existing node (kNode) or the new one once applied
  Vec3d pos = Vec3d::Zero();
  SurfaceIdx surface;
};

using FanKey = std::pair<std::uint32_t, std::uint32_t>;  // face, fan

struct Segment {
  std::uint32_t a = 0, b = 0;  // point ids, in curve direction
  FanKey fan;                  // the fan triangle holding it; {kNone, kNone} along a side
  LK side_kind = LK::kNode;    // along a side: kEdge (side_a = edge) or kDiag (face, d)
  std::uint32_t side_a = 0, side_b = 0;
  std::vector<std::pair<double, std::uint32_t>> inner;  // inserted points by parameter from a
};

struct FanPlan {
  FanKey fan;
  NodeIdx n[3];
  std::vector<std::array<std::uint32_t, 3>> tris;  // point ids
  std::vector<std::array<Vec2d, 3>> tri2;          // their corners in the fan's plane frame
  Vec2d c2[3];                                     // the fan's corners in that frame
  bool kept = false;                               // no points: the fan triangle stays as it is
};

struct Plan {
  std::vector<Pt> pts;
  // The plan's map nodes come from one arena, released at once (their
  // mallocs and frees were a tenth of the re-triangulation of a stroke).
  std::pmr::monotonic_buffer_resource arena;
  std::vector<std::uint32_t> node_pt;  // per node slot: its point id, or kNone
  std::pmr::map<std::uint32_t, std::vector<std::pair<double, std::uint32_t>>> edge_pts{&arena};  // edge -> (u, pid)
  std::pmr::map<FanKey, std::vector<std::pair<double, std::uint32_t>>> diag_pts{&arena};  // (face, d) -> (u, pid)
  std::pmr::map<FanKey, std::vector<std::uint32_t>> fan_pts{&arena};                      // (face, fan) -> pids
  std::vector<Segment> segments;
  std::vector<std::vector<std::vector<std::uint32_t>>> curve_seg;  // per curve, per row pair: its segments in order
  std::vector<FaceIdx> faces;                                      // faces to replace
  std::pmr::map<FanKey, FanPlan> fans{&arena};
  // Per face slot, its entry in face_hs (kNone: not read yet): the faces'
  // cycles are read for every point located in them (a hash map here was a
  // tenth of the re-triangulation).
  std::vector<std::uint32_t> face_at;
  std::vector<std::vector<HalfedgeIdx>> face_hs;
  std::size_t crossings = 0;
};

class Planner {
 public:
  Planner(const Model& m, double snap) : m_(m), snap_(snap) {
    P.node_pt.assign(m.nodes.slots.capacity(), kNone);
    P.face_at.assign(m.faces.slots.capacity(), kNone);
  }
  bool chords_without_cdt = true;  // RetriangulateOptions::chords_without_cdt
  std::size_t fans_without_cdt = 0;

  /// The face's halfedges (the span stays valid while faces are added: the
  /// cycles' own buffers never move).
  std::span<const HalfedgeIdx> hs(FaceIdx f) {
    std::uint32_t& at = P.face_at[f.value];
    if (at == kNone) {
      at = static_cast<std::uint32_t>(P.face_hs.size());
      m_.face_halfedges(f, P.face_hs.emplace_back());
    }
    return P.face_hs[at];
  }
  NodeIdx corner(FaceIdx f, std::uint32_t i) { return m_.tail(hs(f)[i]); }
  std::array<NodeIdx, 3> fan_nodes(const FanKey& k) {
    const FaceIdx f{k.first};
    return {corner(f, 0), corner(f, k.second + 1), corner(f, k.second + 2)};
  }

  Loc node_loc(NodeIdx v) const { return {LK::kNode, v.value, 0, 0, Vec3d::Zero()}; }
  Loc edge_loc(EdgeIdx e, double u) const {
    const HalfedgeIdx h0 = halfedge_of(e, 0);
    if (u <= snap_) return node_loc(m_.tail(h0));
    if (u >= 1 - snap_) return node_loc(m_.head(h0));
    return {LK::kEdge, e.value, 0, u, Vec3d::Zero()};
  }
  /// u measured from tail(h).
  Loc halfedge_loc(HalfedgeIdx h, double u) const { return edge_loc(edge_of(h), is_forward(h) ? u : 1 - u); }
  Loc diag_loc(FaceIdx f, std::uint32_t d, double u) {
    if (u <= snap_) return node_loc(corner(f, 0));
    if (u >= 1 - snap_) return node_loc(corner(f, d));
    return {LK::kDiag, f.value, d, u, Vec3d::Zero()};
  }
  Loc fan_loc(FaceIdx f, std::uint32_t j, Vec3d b) {
    b = b.cwiseMax(0.0);
    b /= b.sum();
    for (int i = 0; i < 3; ++i)
      if (b[i] < snap_) b[i] = 0;
    b /= b.sum();
    const auto k = static_cast<std::uint32_t>(hs(f).size());
    const int zeros = (b[0] == 0) + (b[1] == 0) + (b[2] == 0);
    if (zeros >= 2) {
      const std::uint32_t c = b[0] > 0 ? 0 : b[1] > 0 ? j + 1 : j + 2;
      return node_loc(corner(f, c));
    }
    if (b[2] == 0) return j == 0 ? halfedge_loc(hs(f)[0], b[1]) : diag_loc(f, j + 1, b[1]);
    if (b[0] == 0) return halfedge_loc(hs(f)[j + 1], b[2]);
    if (b[1] == 0) return j + 3 == k ? halfedge_loc(hs(f)[k - 1], b[0]) : diag_loc(f, j + 2, b[2]);
    return {LK::kFan, f.value, j, 0, b};
  }
  Expected<Loc> attrib_loc(AttribNodeIdx a) {
    const auto& an = m_.attrib_nodes;
    const std::uint32_t el = an.element[a.value];
    switch (an.kind[a.value]) {
      case AttribNodeKind::kVertex:
        return node_loc(NodeIdx{el});
      case AttribNodeKind::kEdge:
        return halfedge_loc(HalfedgeIdx{el}, std::clamp(an.param[a.value].x(), 0.0, 1.0));
      case AttribNodeKind::kFace: {
        const FaceIdx f{el};
        const std::uint32_t j = an.corner[a.value];
        if (j + 3 > hs(f).size())
          return status_of(ErrorCode::kInvalidArgument, "attribute node ", a.value, " names fan ", j, " of face ",
                           f.value, " beyond its corners");
        return fan_loc(f, j, an.param[a.value]);
      }
    }
    return Status(ErrorCode::kInternal, "unknown attribute node kind");
  }

  Vec3d position(const Loc& l) {
    switch (l.k) {
      case LK::kNode:
        return m_.position(NodeIdx{l.a});
      case LK::kEdge: {
        const HalfedgeIdx h0 = halfedge_of(EdgeIdx{l.a}, 0);
        return (1 - l.u) * m_.position(m_.tail(h0)) + l.u * m_.position(m_.head(h0));
      }
      case LK::kDiag: {
        const FaceIdx f{l.a};
        return (1 - l.u) * m_.position(corner(f, 0)) + l.u * m_.position(corner(f, l.b));
      }
      case LK::kFan: {
        const auto n = fan_nodes({l.a, l.b});
        return l.bary[0] * m_.position(n[0]) + l.bary[1] * m_.position(n[1]) + l.bary[2] * m_.position(n[2]);
      }
    }
    return Vec3d::Zero();
  }
  SurfaceIdx surface(const Loc& l) const {
    switch (l.k) {
      case LK::kNode:
        return m_.nodes.surface[l.a];
      case LK::kEdge:
        return m_.surface_of(EdgeIdx{l.a});
      default:
        return m_.faces.surface[l.a];
    }
  }

  /// The point id of a location, merging with a point already there.
  std::uint32_t add(const Loc& l) {
    auto fresh = [&] {
      const auto id = static_cast<std::uint32_t>(P.pts.size());
      Pt p;
      p.loc = l;
      if (l.k == LK::kNode) p.node = NodeIdx{l.a};
      p.pos = position(l);
      p.surface = surface(l);
      P.pts.push_back(p);
      return id;
    };
    switch (l.k) {
      case LK::kNode: {
        if (const std::uint32_t known = P.node_pt[l.a]; known != kNone) return known;
        const std::uint32_t id = fresh();
        P.node_pt[l.a] = id;
        return id;
      }
      case LK::kEdge:
      case LK::kDiag: {
        auto& list = l.k == LK::kEdge ? P.edge_pts[l.a] : P.diag_pts[{l.a, l.b}];
        for (const auto& [u, id] : list)
          if (std::abs(u - l.u) <= snap_) return id;
        const std::uint32_t id = fresh();
        list.emplace_back(l.u, id);
        return id;
      }
      case LK::kFan: {
        auto& list = P.fan_pts[{l.a, l.b}];
        for (std::uint32_t id : list)
          if ((P.pts[id].loc.bary - l.bary).cwiseAbs().maxCoeff() <= snap_) return id;
        const std::uint32_t id = fresh();
        list.push_back(id);
        return id;
      }
    }
    return kNone;
  }

  /// Fan triangles a point lies in or on.
  std::vector<FanKey> fans_of(std::uint32_t pid) {
    const Loc& l = P.pts[pid].loc;
    std::vector<FanKey> out;
    auto side_fan = [&](HalfedgeIdx h) {
      const FaceIdx f = m_.face(h);
      if (!f.valid()) return;
      const auto& v = hs(f);
      const auto k = static_cast<std::uint32_t>(v.size());
      const auto c = static_cast<std::uint32_t>(std::find(v.begin(), v.end(), h) - v.begin());
      out.push_back({f.value, c == 0 ? 0 : c == k - 1 ? k - 3 : c - 1});
    };
    switch (l.k) {
      case LK::kNode:
        m_.for_each_outgoing(NodeIdx{l.a}, [&](HalfedgeIdx h) {
          const FaceIdx f = m_.face(h);
          if (!f.valid()) return;
          const auto& v = hs(f);
          const auto k = static_cast<std::uint32_t>(v.size());
          const auto c = static_cast<std::uint32_t>(std::find(v.begin(), v.end(), h) - v.begin());
          for (std::uint32_t j = 0; j + 2 < k; ++j)
            if (c == 0 || c == j + 1 || c == j + 2) out.push_back({f.value, j});
        });
        break;
      case LK::kEdge:
        side_fan(halfedge_of(EdgeIdx{l.a}, 0));
        side_fan(halfedge_of(EdgeIdx{l.a}, 1));
        break;
      case LK::kDiag:
        out.push_back({l.a, l.b - 2});
        out.push_back({l.a, l.b - 1});
        break;
      case LK::kFan:
        out.push_back({l.a, l.b});
        break;
    }
    std::sort(out.begin(), out.end());
    return out;
  }

  /// Areal coordinates of a point in a fan triangle it lies in or on.
  Vec3d bary_in(std::uint32_t pid, const FanKey& fk) {
    const Loc& l = P.pts[pid].loc;
    const auto n = fan_nodes(fk);
    Vec3d b = Vec3d::Zero();
    auto at = [&](NodeIdx v) {
      for (int i = 0; i < 3; ++i)
        if (n[i] == v) return i;
      return -1;
    };
    switch (l.k) {
      case LK::kNode:
        b[at(NodeIdx{l.a})] = 1;
        break;
      case LK::kEdge: {
        const HalfedgeIdx h0 = halfedge_of(EdgeIdx{l.a}, 0);
        b[at(m_.tail(h0))] = 1 - l.u;
        b[at(m_.head(h0))] = l.u;
        break;
      }
      case LK::kDiag:
        b[0] = 1 - l.u;
        b[at(corner(FaceIdx{l.a}, l.b))] = l.u;
        break;
      case LK::kFan:
        b = l.bary;
        break;
    }
    return b;
  }

  Plan P;

 private:
  const Model& m_;
  double snap_;
};

/// The curve's segments, split at the fan diagonals of polygon faces when
/// two consecutive points share a face but no fan triangle.
Status add_segment(Planner& pl, std::uint32_t a, std::uint32_t b, std::uint32_t curve, std::vector<std::uint32_t>& ids,
                   const Model& m, int depth = 0) {
  Plan& P = pl.P;
  const auto fa = pl.fans_of(a), fb = pl.fans_of(b);
  std::vector<FanKey> common;
  std::set_intersection(fa.begin(), fa.end(), fb.begin(), fb.end(), std::back_inserter(common));
  if (!common.empty()) {
    // Along a side (both points on one side of a common fan): no
    // constraint; the side's own points in between are filled in once all
    // points are known.
    for (const FanKey& fk : common) {
      const Vec3d ba = pl.bary_in(a, fk), bb = pl.bary_in(b, fk);
      for (int i = 0; i < 3; ++i) {
        if (ba[i] != 0 || bb[i] != 0) continue;
        Segment s;
        s.a = a;
        s.b = b;
        s.fan = {kNone, kNone};
        const FaceIdx f{fk.first};
        const auto& h = pl.hs(f);
        const auto k = static_cast<std::uint32_t>(h.size());
        const std::uint32_t j = fk.second;
        // The side opposite corner i: 2 -> side 0, 0 -> side 1, 1 -> side 2.
        HalfedgeIdx real;
        std::uint32_t d = 0;
        if (i == 2) {
          if (j == 0)
            real = h[0];
          else
            d = j + 1;
        } else if (i == 0) {
          real = h[j + 1];
        } else {
          if (j + 3 == k)
            real = h[k - 1];
          else
            d = j + 2;
        }
        if (real.valid()) {
          s.side_kind = LK::kEdge;
          s.side_a = edge_of(real).value;
        } else {
          s.side_kind = LK::kDiag;
          s.side_a = f.value;
          s.side_b = d;
        }
        ids.push_back(static_cast<std::uint32_t>(P.segments.size()));
        P.segments.push_back(std::move(s));
        return {};
      }
    }
    Segment s;
    s.a = a;
    s.b = b;
    s.fan = common.front();
    ids.push_back(static_cast<std::uint32_t>(P.segments.size()));
    P.segments.push_back(std::move(s));
    return {};
  }
  // A common polygon face: cut the segment at the fan diagonals, in the
  // face's plane (Newell normal).
  std::vector<std::uint32_t> faces;
  for (const auto& x : fa)
    for (const auto& y : fb)
      if (x.first == y.first) faces.push_back(x.first);
  if (faces.empty() || depth > 0)
    return status_of(ErrorCode::kInvalidArgument, "curve ", curve, ": consecutive nodes at (", P.pts[a].pos.transpose(),
                     ") and (", P.pts[b].pos.transpose(), ") share no face");
  const FaceIdx f{faces.front()};
  const auto& h = pl.hs(f);
  const std::size_t k = h.size();
  Vec3d nrm = Vec3d::Zero();
  for (std::size_t i = 0; i < k; ++i) nrm += m.position(m.tail(h[i])).cross(m.position(m.tail(h[(i + 1) % k])));
  if (!(nrm.norm() > 0)) return status_of(ErrorCode::kDegenerate, "face ", f.value, " has no plane");
  nrm.normalize();
  const Vec3d ax = std::abs(nrm.x()) < 0.6 ? Vec3d::UnitX() : Vec3d::UnitY();
  const Vec3d ux = nrm.cross(ax).normalized(), uy = nrm.cross(ux);
  auto to2 = [&](const Vec3d& p) { return Vec2d(p.dot(ux), p.dot(uy)); };
  const Vec2d A = to2(P.pts[a].pos), B = to2(P.pts[b].pos), c0 = to2(m.position(m.tail(h[0])));
  std::vector<std::pair<double, std::uint32_t>> cuts;
  for (std::uint32_t d = 2; d + 2 <= k; ++d) {
    const Vec2d cd = to2(m.position(m.tail(h[d])));
    const Vec2d r = B - A, s = cd - c0;
    const double den = cross2(r, s);
    if (std::abs(den) <= 1e-15 * r.norm() * s.norm()) continue;
    const double t = cross2(c0 - A, s) / den, w = cross2(c0 - A, r) / den;
    if (t <= 0 || t >= 1 || w < 0 || w > 1) continue;
    cuts.emplace_back(t, pl.add(pl.diag_loc(f, d, w)));
  }
  std::sort(cuts.begin(), cuts.end());
  std::uint32_t prev = a;
  cuts.emplace_back(1.0, b);
  for (const auto& [t, q] : cuts) {
    if (q == prev) continue;
    if (Status s = add_segment(pl, prev, q, curve, ids, m, depth + 1); !s) return s;
    prev = q;
  }
  return {};
}

/// Intersections of the segments of one fan triangle, in areal coordinates.
Status cross_segments(Planner& pl, const FanKey& fk, const std::vector<std::uint32_t>& segs, double snap) {
  Plan& P = pl.P;
  auto p2 = [&](std::uint32_t pid) {
    const Vec3d b = pl.bary_in(pid, fk);
    return Vec2d(b[1], b[2]);
  };
  for (std::size_t x = 0; x < segs.size(); ++x)
    for (std::size_t y = x + 1; y < segs.size(); ++y) {
      Segment& s1 = P.segments[segs[x]];
      Segment& s2 = P.segments[segs[y]];
      const Vec2d A = p2(s1.a), B = p2(s1.b), C = p2(s2.a), D = p2(s2.b);
      const Vec2d r = B - A, s = D - C;
      const double den = cross2(r, s);
      const bool share = s1.a == s2.a || s1.a == s2.b || s1.b == s2.a || s1.b == s2.b;
      if (std::abs(den) <= 1e-14 * r.norm() * s.norm()) {
        // Parallel: refuse an overlap of positive length.
        if (std::abs(cross2(C - A, r)) > 1e-12 * r.norm()) continue;
        const double rr = r.squaredNorm();
        const double t0 = (C - A).dot(r) / rr, t1 = (D - A).dot(r) / rr;
        const double lo = std::max(0.0, std::min(t0, t1)), hi = std::min(1.0, std::max(t0, t1));
        if (hi - lo > snap)
          return status_of(ErrorCode::kDegenerate, "curves overlap in face ", fk.first,
                           " (two curve segments run along each other)");
        continue;
      }
      const double t = cross2(C - A, s) / den, w = cross2(C - A, r) / den;
      if (t < -snap || t > 1 + snap || w < -snap || w > 1 + snap) continue;
      const bool t_in = t > snap && t<1 - snap, w_in = w> snap && w < 1 - snap;
      if (t_in && w_in) {
        const Vec3d b = pl.bary_in(s1.a, fk) * (1 - t) + pl.bary_in(s1.b, fk) * t;
        const std::uint32_t q = pl.add(pl.fan_loc(FaceIdx{fk.first}, fk.second, b));
        s1.inner.emplace_back(t, q);
        s2.inner.emplace_back(w, q);
        ++P.crossings;
      } else if (t_in && !share) {
        s1.inner.emplace_back(t, w < 0.5 ? s2.a : s2.b);  // an end of s2 on s1
      } else if (w_in && !share) {
        s2.inner.emplace_back(w, t < 0.5 ? s1.a : s1.b);
      } else if (!share && !t_in && !w_in) {
        const std::uint32_t p = t < 0.5 ? s1.a : s1.b, q = w < 0.5 ? s2.a : s2.b;
        if (p != q)
          return status_of(ErrorCode::kDegenerate, "face ", fk.first, ": curve points at (", P.pts[p].pos.transpose(),
                           ") and (", P.pts[q].pos.transpose(), ") are closer than the snap tolerance");
      }
    }
  return {};
}

/// The constrained Delaunay triangulation of a small fan triangle without
/// CGAL's CDT: the fans the painted curves cross hold at most one stroke
/// point each, and building a CDT (its vertex and face allocations, its
/// maps) for three to six points was most of the re-triangulation.
///
/// The polygon (the fan's corners with the points on its sides, counter-
/// clockwise) and at most one inner point p: with p, the fan from p (every
/// constraint must end at p); without, the polygon is split along the
/// constraints (chords between its points) and each part ear-clipped. Then
/// Lawson's flips (exact empty-circle tests) of every edge that is neither a
/// side nor a constraint until all are locally Delaunay: a constrained
/// triangulation that is locally Delaunay is the CDT (Chew 1989; de Berg et
/// al., Thm. 9.8 for the unconstrained case), so where the CDT is unique (no
/// four cocircular points) these are its triangles. Every triangle is then
/// checked (strictly counter-clockwise by exact orientation, no other point
/// in it or on its sides); anything else (false) goes to CGAL's CDT, which
/// also reports the degenerate cases.
bool direct_cdt(Planner& pl, FanPlan& fp, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& cons,
                const std::vector<std::uint32_t>& inner, const std::array<std::vector<std::uint32_t>, 3>& side,
                const std::uint32_t (&cpt)[3]) {
  constexpr int kMax = 12;  // points; larger fans go to the CDT
  if (inner.size() > 1) return false;
  std::array<std::uint32_t, kMax> id{};
  int n = 0;  // polygon points
  for (int k = 0; k < 3; ++k) {
    if (n + 1 + static_cast<int>(side[k].size()) + static_cast<int>(inner.size()) > kMax) return false;
    id[n++] = cpt[k];
    for (std::uint32_t s : side[k]) id[n++] = s;
  }
  const int np = n + static_cast<int>(inner.size());
  if (!inner.empty()) id[n] = inner[0];
  // The same plane coordinates as the CDT's points.
  std::array<K::Point_2, kMax> q;
  for (int i = 0; i < np; ++i) {
    const Vec3d b = pl.bary_in(id[i], fp.fan);
    const Vec2d v = b[0] * fp.c2[0] + b[1] * fp.c2[1] + b[2] * fp.c2[2];
    q[i] = K::Point_2(v.x(), v.y());
  }
  auto local = [&](std::uint32_t pid) {
    for (int i = 0; i < np; ++i)
      if (id[i] == pid) return i;
    return -1;
  };
  std::array<std::array<bool, kMax>, kMax> fixed{};  // sides and constraints
  for (int i = 0; i < n; ++i) fixed[i][(i + 1) % n] = fixed[(i + 1) % n][i] = true;
  std::array<std::pair<int, int>, kMax> con{};
  int nc = 0;
  for (const auto& [x, y] : cons) {
    const int a = local(x), b = local(y);
    if (a < 0 || b < 0 || a == b || nc == kMax) return false;
    fixed[a][b] = fixed[b][a] = true;
    con[nc++] = {a, b};
  }
  auto orient = [&](int a, int b, int c) { return CGAL::orientation(q[a], q[b], q[c]); };
  using Tri = std::array<int, 3>;
  std::array<Tri, 2 * kMax> t{};
  int nt = 0;
  if (np > n) {
    // The fan from the inner point; every constraint must be one of its spokes.
    for (int c = 0; c < nc; ++c)
      if (con[c].first != n && con[c].second != n) return false;
    for (int i = 0; i < n; ++i) t[nt++] = {n, i, (i + 1) % n};
  } else {
    // Split the polygon along the chords, then clip ears off each part.
    std::array<std::array<int, kMax>, kMax> part{};
    std::array<int, kMax> size{};
    int parts = 1;
    for (int i = 0; i < n; ++i) part[0][i] = i;
    size[0] = n;
    for (int c = 0; c < nc; ++c) {
      int where = -1, ia = -1, ib = -1;
      for (int p = 0; p < parts && where < 0; ++p) {
        ia = ib = -1;
        for (int i = 0; i < size[p]; ++i) {
          if (part[p][i] == con[c].first) ia = i;
          if (part[p][i] == con[c].second) ib = i;
        }
        if (ia >= 0 && ib >= 0) where = p;
      }
      if (where < 0) return false;
      if (ia > ib) std::swap(ia, ib);
      const int m = size[where];
      if (ib - ia < 2 || ia + m - ib < 2) return false;  // a side, not a chord
      std::array<int, kMax> rest{};
      int r = 0;
      for (int i = ib; i != ia; i = (i + 1) % m) rest[r++] = part[where][i];
      rest[r++] = part[where][ia];
      for (int i = ia; i <= ib; ++i) part[parts][i - ia] = part[where][i];
      size[parts++] = ib - ia + 1;
      part[where] = rest;
      size[where] = r;
    }
    for (int p = 0; p < parts; ++p) {
      std::array<int, kMax> v = part[p];
      int m = size[p];
      while (m > 3) {
        int ear = -1;
        for (int i = 0; i < m && ear < 0; ++i) {
          const int a = v[(i + m - 1) % m], b = v[i], c = v[(i + 1) % m];
          if (orient(a, b, c) != CGAL::LEFT_TURN) continue;
          bool empty = true;
          for (int j = 0; j < m && empty; ++j) {
            const int w = v[j];
            if (w == a || w == b || w == c) continue;
            empty = orient(a, b, w) == CGAL::RIGHT_TURN || orient(b, c, w) == CGAL::RIGHT_TURN ||
                    orient(c, a, w) == CGAL::RIGHT_TURN;
          }
          if (empty) ear = i;
        }
        if (ear < 0) return false;
        t[nt++] = {v[(ear + m - 1) % m], v[ear], v[(ear + 1) % m]};
        for (int i = ear; i + 1 < m; ++i) v[i] = v[i + 1];
        --m;
      }
      t[nt++] = {v[0], v[1], v[2]};
    }
  }
  // Lawson's flips: edge a-b of triangle (a, b, c) against (b, a, d).
  for (int flips = 0;; ++flips) {
    bool flipped = false;
    for (int x = 0; x < nt && !flipped; ++x)
      for (int k = 0; k < 3 && !flipped; ++k) {
        const int a = t[x][k], b = t[x][(k + 1) % 3], c = t[x][(k + 2) % 3];
        if (fixed[a][b]) continue;
        for (int y = 0; y < nt; ++y) {
          int l = 0;
          while (l < 3 && !(t[y][l] == b && t[y][(l + 1) % 3] == a)) ++l;
          if (l == 3) continue;
          const int d = t[y][(l + 2) % 3];
          if (CGAL::side_of_oriented_circle(q[a], q[b], q[c], q[d]) != CGAL::ON_POSITIVE_SIDE) break;
          if (orient(a, d, c) != CGAL::LEFT_TURN || orient(d, b, c) != CGAL::LEFT_TURN) return false;
          if (flips == 4 * kMax) return false;
          t[x] = {a, d, c};
          t[y] = {d, b, c};
          flipped = true;
          break;
        }
      }
    if (!flipped) break;
  }
  // Every triangle strictly counter-clockwise with no other point in it or on it.
  if (nt != n - 2 + 2 * (np - n)) return false;
  for (int x = 0; x < nt; ++x) {
    const auto [a, b, c] = t[x];
    if (orient(a, b, c) != CGAL::LEFT_TURN) return false;
    for (int w = 0; w < np; ++w)
      if (w != a && w != b && w != c && orient(a, b, w) != CGAL::RIGHT_TURN && orient(b, c, w) != CGAL::RIGHT_TURN &&
          orient(c, a, w) != CGAL::RIGHT_TURN)
        return false;
  }
  for (int x = 0; x < nt; ++x) {
    std::array<std::uint32_t, 3> r = {id[t[x][0]], id[t[x][1]], id[t[x][2]]};
    std::rotate(r.begin(), std::min_element(r.begin(), r.end()), r.end());
    fp.tris.push_back(r);
  }
  std::sort(fp.tris.begin(), fp.tris.end());
  return true;
}

/// The constrained Delaunay triangulation of one fan triangle.
Status triangulate_fan(Planner& pl, FanPlan& fp, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& cons,
                       const std::vector<std::uint32_t>& inner, const std::array<std::vector<std::uint32_t>, 3>& side,
                       const Model& m) {
  Plan& P = pl.P;
  const Vec3d A = m.position(fp.n[0]), B = m.position(fp.n[1]), C = m.position(fp.n[2]);
  const Vec3d e1 = B - A, e2 = C - A, nrm = e1.cross(e2);
  if (!(nrm.norm() > 0) || !nrm.allFinite())
    return status_of(ErrorCode::kDegenerate, "face ", fp.fan.first, ": fan triangle ", fp.fan.second,
                     " has no area but holds curve points");
  const Vec3d ux = e1.normalized(), uy = nrm.normalized().cross(ux);
  fp.c2[0] = Vec2d::Zero();
  fp.c2[1] = Vec2d(e1.dot(ux), e1.dot(uy));
  fp.c2[2] = Vec2d(e2.dot(ux), e2.dot(uy));
  std::vector<std::uint32_t> boundary;
  const std::uint32_t cpt[3] = {P.node_pt[fp.n[0].value], P.node_pt[fp.n[1].value], P.node_pt[fp.n[2].value]};
  if (pl.chords_without_cdt && direct_cdt(pl, fp, cons, inner, side, cpt)) {
    ++pl.fans_without_cdt;
    return {};
  }
  for (int k = 0; k < 3; ++k) {
    boundary.push_back(cpt[k]);
    boundary.insert(boundary.end(), side[k].begin(), side[k].end());
  }
  std::vector<std::uint32_t> all = boundary;
  all.insert(all.end(), inner.begin(), inner.end());
  Cdt cdt;
  // Small maps per fan: nodes from a buffer on the stack.
  std::array<std::byte, 8192> buf;
  std::pmr::monotonic_buffer_resource local(buf.data(), buf.size());
  std::pmr::map<std::uint32_t, Cdt::Vertex_handle> vh(&local);
  for (std::uint32_t pid : all) {
    const Vec3d b = pl.bary_in(pid, fp.fan);
    const Vec2d q = b[0] * fp.c2[0] + b[1] * fp.c2[1] + b[2] * fp.c2[2];
    const std::size_t before = cdt.number_of_vertices();
    auto v = cdt.insert(K::Point_2(q.x(), q.y()));
    if (cdt.number_of_vertices() == before)
      return status_of(ErrorCode::kDegenerate, "face ", fp.fan.first, ": two curve points fall on one place (",
                       P.pts[pid].pos.transpose(), ")");
    v->info() = pid;
    vh.emplace(pid, v);
  }
  const std::size_t nb = boundary.size();
  std::pmr::map<std::pair<std::uint32_t, std::uint32_t>, bool> is_side(&local);
  try {
    for (std::size_t k = 0; k < nb; ++k) {
      const std::uint32_t x = boundary[k], y = boundary[(k + 1) % nb];
      cdt.insert_constraint(vh.at(x), vh.at(y));
      is_side[{std::min(x, y), std::max(x, y)}] = true;
    }
    for (const auto& [x, y] : cons) cdt.insert_constraint(vh.at(x), vh.at(y));
  } catch (const std::exception&) {
    return status_of(ErrorCode::kDegenerate, "face ", fp.fan.first, ": curve segments cross in fan triangle ",
                     fp.fan.second);
  }
  // Outside = reachable from the infinite face without crossing a side.
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info() = 1;
  std::deque<Cdt::Face_handle> queue{cdt.infinite_face()};
  cdt.infinite_face()->info() = 0;
  while (!queue.empty()) {
    const Cdt::Face_handle f = queue.front();
    queue.pop_front();
    for (int i = 0; i < 3; ++i) {
      const Cdt::Face_handle g = f->neighbor(i);
      if (g->info() == 0) continue;
      const auto va = f->vertex(Cdt::cw(i)), vb = f->vertex(Cdt::ccw(i));
      if (!cdt.is_infinite(va) && !cdt.is_infinite(vb)) {
        const std::uint32_t x = va->info(), y = vb->info();
        if (is_side.count({std::min(x, y), std::max(x, y)})) continue;
      }
      g->info() = 0;
      queue.push_back(g);
    }
  }
  std::pmr::map<std::pair<std::uint32_t, std::uint32_t>, int> edges(&local);
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    if (f->info() != 1) continue;
    std::array<std::uint32_t, 3> t = {f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()};
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    fp.tris.push_back(t);
    for (int k = 0; k < 3; ++k) ++edges[{std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}];
  }
  std::sort(fp.tris.begin(), fp.tris.end());
  const std::size_t expect = nb - 2 + 2 * inner.size();
  if (fp.tris.size() != expect)
    return status_of(ErrorCode::kDegenerate, "face ", fp.fan.first, ": fan triangle ", fp.fan.second, " gives ",
                     fp.tris.size(), " triangles instead of ", expect, " (a curve point lies outside it or on a side)");
  for (const auto& [x, y] : cons)
    if (!edges.count({std::min(x, y), std::max(x, y)}))
      return status_of(ErrorCode::kDegenerate, "face ", fp.fan.first,
                       ": a curve segment passes through another curve point");
  return {};
}

}  // namespace

Expected<RetriangulationResult> retriangulate_curves(Model& m, std::span<const AttribEdge> curves,
                                                     const RetriangulateOptions& opt, const ExecContext& ctx) {
  if (!(opt.snap >= 0 && opt.snap < 0.1))
    return Status(ErrorCode::kInvalidArgument, "retriangulate: snap must be in [0, 0.1)");
  std::vector<AttribEdgeIdx> cur;
  for (const AttribEdge& c : curves) {
    auto r = m.resolve(c);
    if (!r) return r.status();
    cur.push_back(*r);
  }
  for (std::size_t i = 0; i < cur.size(); ++i)
    for (std::size_t j = i + 1; j < cur.size(); ++j)
      if (cur[i] == cur[j])
        return status_of(ErrorCode::kInvalidArgument, "retriangulate: curve ", cur[i].value, " given twice");
  Planner pl(m, opt.snap);
  pl.chords_without_cdt = opt.chords_without_cdt;
  Plan& P = pl.P;
  // 1. Curve points and segments.
  std::vector<std::vector<std::uint32_t>> row_pid(cur.size());
  for (std::size_t c = 0; c < cur.size(); ++c) {
    for (AttribNodeIdx a : m.attrib_edges.nodes.row(cur[c].value)) {
      if (!m.alive(a)) return status_of(ErrorCode::kInvalidArgument, "curve ", cur[c].value, " holds a dead node");
      auto l = pl.attrib_loc(a);
      if (!l) return l.status();
      row_pid[c].push_back(pl.add(*l));
    }
  }
  P.curve_seg.resize(cur.size());
  for (std::size_t c = 0; c < cur.size(); ++c) {
    const auto& r = row_pid[c];
    for (std::size_t k = 0; k + 1 < r.size(); ++k) {
      std::vector<std::uint32_t> ids;
      if (r[k] != r[k + 1])
        if (Status s = add_segment(pl, r[k], r[k + 1], cur[c].value, ids, m); !s) return s;
      P.curve_seg[c].push_back(std::move(ids));
    }
  }
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "retriangulate cancelled");
  // 2. Crossings per fan triangle.
  std::pmr::monotonic_buffer_resource local;  // the maps below, released at once
  std::pmr::map<FanKey, std::vector<std::uint32_t>> fan_segs(&local);
  for (std::uint32_t i = 0; i < P.segments.size(); ++i)
    if (P.segments[i].fan.first != kNone) fan_segs[P.segments[i].fan].push_back(i);
  for (const auto& [fk, segs] : fan_segs)
    if (Status s = cross_segments(pl, fk, segs, opt.snap); !s) return s;
  for (Segment& s : P.segments) {
    std::sort(s.inner.begin(), s.inner.end());
    s.inner.erase(
        std::unique(s.inner.begin(), s.inner.end(), [](const auto& x, const auto& y) { return x.second == y.second; }),
        s.inner.end());
  }
  // 3. Joints: every member's corresponding edge gets the same points.
  {
    std::vector<std::uint32_t> split;
    for (const auto& [e, list] : P.edge_pts) split.push_back(e);
    std::pmr::map<std::uint32_t, bool> done(&local);
    for (std::uint32_t e : split) {
      if (done.count(e)) continue;
      const MeshEdgeIdx me = m.edges.mesh_edge[e];
      if (!me.valid() || !m.mesh_edges.joint[me.value].valid()) continue;
      const auto group = joint_corresponding_halfedges(m, halfedge_of(EdgeIdx{e}, 0));
      std::vector<double> us;  // along halfedge 2e
      for (HalfedgeIdx h : group) {
        auto it = P.edge_pts.find(edge_of(h).value);
        if (it == P.edge_pts.end()) continue;
        for (const auto& [u, id] : it->second) us.push_back(is_forward(h) ? u : 1 - u);
      }
      for (HalfedgeIdx h : group) {
        done[edge_of(h).value] = true;
        for (double u : us) (void)pl.add(pl.edge_loc(edge_of(h), is_forward(h) ? u : 1 - u));
      }
    }
  }
  for (auto& [e, list] : P.edge_pts) std::sort(list.begin(), list.end());
  for (auto& [d, list] : P.diag_pts) std::sort(list.begin(), list.end());
  // Segments along a side pass through the side's points in between.
  for (Segment& sg : P.segments) {
    if (sg.fan.first != kNone) continue;
    const std::vector<std::pair<double, std::uint32_t>>* list = nullptr;
    double ua = 0, ub = 0;
    auto param = [&](std::uint32_t pid) {
      const Loc& l = P.pts[pid].loc;
      if (l.k == LK::kEdge || l.k == LK::kDiag) return l.u;
      if (sg.side_kind == LK::kEdge) return m.tail(halfedge_of(EdgeIdx{sg.side_a}, 0)) == NodeIdx{l.a} ? 0.0 : 1.0;
      return pl.corner(FaceIdx{sg.side_a}, 0) == NodeIdx{l.a} ? 0.0 : 1.0;
    };
    if (sg.side_kind == LK::kEdge) {
      auto it = P.edge_pts.find(sg.side_a);
      if (it != P.edge_pts.end()) list = &it->second;
    } else {
      auto it = P.diag_pts.find({sg.side_a, sg.side_b});
      if (it != P.diag_pts.end()) list = &it->second;
    }
    ua = param(sg.a);
    ub = param(sg.b);
    if (!list || ua == ub) continue;
    for (const auto& [u, id] : *list) {
      const double t = (u - ua) / (ub - ua);
      if (t > 0 && t < 1 && id != sg.a && id != sg.b) sg.inner.emplace_back(t, id);
    }
    std::sort(sg.inner.begin(), sg.inner.end());
  }
  // 4. Faces to replace.
  std::vector<FaceIdx> faces;
  for (const auto& [e, list] : P.edge_pts)
    for (unsigned side = 0; side < 2; ++side)
      if (const FaceIdx f = m.face(halfedge_of(EdgeIdx{e}, side)); f.valid()) faces.push_back(f);
  for (const auto& [d, list] : P.diag_pts) faces.push_back(FaceIdx{d.first});
  for (const auto& [fk, list] : P.fan_pts) faces.push_back(FaceIdx{fk.first});
  for (const Segment& s : P.segments)
    if (s.fan.first != kNone) faces.push_back(FaceIdx{s.fan.first});
  // Segments along a fan diagonal need their face (the diagonal becomes an edge).
  for (const Segment& sg : P.segments)
    if (sg.fan.first == kNone && sg.side_kind == LK::kDiag) faces.push_back(FaceIdx{sg.side_a});
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  P.faces = faces;
  {
    std::vector<std::uint8_t> mark(m.faces.slots.capacity(), 0);
    for (FaceIdx f : faces) mark[f.value] = 1;
    for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v) {
      const FaceIdx f = m.nodes.in_face[v];
      if (f.valid() && m.alive(NodeIdx{v}) && mark[f.value])
        return status_of(ErrorCode::kUnsupported, "retriangulate: face ", f.value, " holds ring node ", v,
                         "; remove it first");
    }
  }
  // Constraint sub-segments per fan.
  std::pmr::map<FanKey, std::vector<std::pair<std::uint32_t, std::uint32_t>>> fan_cons(&local);
  for (const Segment& s : P.segments) {
    if (s.fan.first == kNone) continue;
    std::uint32_t prev = s.a;
    for (const auto& [t, q] : s.inner) {
      fan_cons[s.fan].emplace_back(prev, q);
      prev = q;
    }
    fan_cons[s.fan].emplace_back(prev, s.b);
  }
  // 5. Per fan triangle of every face to replace: its points and its CDT.
  for (FaceIdx f : faces) {
    const auto& h = pl.hs(f);
    const auto k = static_cast<std::uint32_t>(h.size());
    for (std::uint32_t i = 0; i < k; ++i) (void)pl.add(pl.node_loc(m.tail(h[i])));
    for (std::uint32_t j = 0; j + 2 < k; ++j) {
      const FanKey fk{f.value, j};
      FanPlan fp;
      fp.fan = fk;
      const auto n = pl.fan_nodes(fk);
      std::copy(n.begin(), n.end(), fp.n);
      std::array<std::vector<std::uint32_t>, 3> side;
      // Side k runs from corner k to corner k+1.
      auto edge_side = [&](HalfedgeIdx he, std::vector<std::uint32_t>& out) {
        auto it = P.edge_pts.find(edge_of(he).value);
        if (it == P.edge_pts.end()) return;
        for (const auto& [u, id] : it->second) out.push_back(id);
        if (!is_forward(he)) std::reverse(out.begin(), out.end());
      };
      auto diag_side = [&](std::uint32_t d, bool from_c0, std::vector<std::uint32_t>& out) {
        auto it = P.diag_pts.find({f.value, d});
        if (it == P.diag_pts.end()) return;
        for (const auto& [u, id] : it->second) out.push_back(id);
        if (!from_c0) std::reverse(out.begin(), out.end());
      };
      if (j == 0)
        edge_side(h[0], side[0]);
      else
        diag_side(j + 1, true, side[0]);
      edge_side(h[j + 1], side[1]);
      if (j + 3 == k)
        edge_side(h[k - 1], side[2]);
      else
        diag_side(j + 2, false, side[2]);
      std::vector<std::uint32_t> inner;
      if (auto it = P.fan_pts.find(fk); it != P.fan_pts.end()) inner = it->second;
      std::sort(inner.begin(), inner.end());
      const auto cit = fan_cons.find(fk);
      static const std::vector<std::pair<std::uint32_t, std::uint32_t>> none;
      const auto& cons = cit == fan_cons.end() ? none : cit->second;
      if (side[0].empty() && side[1].empty() && side[2].empty() && inner.empty() && cons.empty()) {
        fp.kept = true;
        fp.tris.push_back({P.node_pt[n[0].value], P.node_pt[n[1].value], P.node_pt[n[2].value]});
        const Vec3d e1 = m.position(n[1]) - m.position(n[0]), e2 = m.position(n[2]) - m.position(n[0]);
        const Vec3d nr = e1.cross(e2);
        const Vec3d ux = e1.normalized(), uy = nr.normalized().cross(ux);
        fp.c2[0] = Vec2d::Zero();
        fp.c2[1] = Vec2d(e1.dot(ux), e1.dot(uy));
        fp.c2[2] = Vec2d(e2.dot(ux), e2.dot(uy));
      } else if (Status s = triangulate_fan(pl, fp, cons, inner, side, m); !s) {
        return s;
      }
      // Corners of the new triangles in the fan's frame (for re-attaching
      // face-nodes and probes once the model has changed).
      for (const auto& t : fp.tris) {
        std::array<Vec2d, 3> c;
        for (int x = 0; x < 3; ++x) {
          const Vec3d b = pl.bary_in(t[x], fk);
          c[x] = b[0] * fp.c2[0] + b[1] * fp.c2[1] + b[2] * fp.c2[2];
        }
        fp.tri2.push_back(c);
      }
      P.fans.emplace(fk, std::move(fp));
    }
  }
  // New edges between two old nodes must not exist already (a fan diagonal
  // that is also an edge elsewhere).
  for (const auto& [fk, fp] : P.fans) {
    const auto& h = pl.hs(FaceIdx{fk.first});
    for (const auto& t : fp.tris)
      for (int k = 0; k < 3; ++k) {
        const Pt &a = P.pts[t[k]], &b = P.pts[t[(k + 1) % 3]];
        if (a.loc.k != LK::kNode || b.loc.k != LK::kNode) continue;
        const HalfedgeIdx x = m.find_halfedge(a.node, b.node);
        if (!x.valid()) continue;
        if (std::find(h.begin(), h.end(), x) != h.end() || std::find(h.begin(), h.end(), twin(x)) != h.end()) continue;
        return status_of(ErrorCode::kTopology, "retriangulate: face ", fk.first, ": edge ", a.node.value, "-",
                         b.node.value, " would duplicate an existing edge");
      }
  }
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "retriangulate cancelled");

  // 6. Foreign attribute nodes and probes: where they go.
  std::vector<std::uint8_t> in_curve(m.attrib_nodes.slots.capacity(), 0);
  for (AttribEdgeIdx c : cur)
    for (AttribNodeIdx a : m.attrib_edges.nodes.row(c.value)) in_curve[a.value] = 1;
  std::vector<std::uint8_t> replaced(m.faces.slots.capacity(), 0);
  for (FaceIdx f : faces) replaced[f.value] = 1;
  struct Move {
    AttribNodeIdx a;  // invalid for a probe
    std::size_t probe = 0;
    SurfaceLocation from;
  };
  std::vector<Move> moves;
  auto touched = [&](const SurfaceLocation& l) {
    if (l.kind == AttribNodeKind::kFace) return l.element < replaced.size() && replaced[l.element] != 0;
    if (l.kind == AttribNodeKind::kEdge) return P.edge_pts.count(edge_of(HalfedgeIdx{l.element}).value) != 0;
    return false;
  };
  for (std::uint32_t i = 0; i < m.attrib_nodes.slots.capacity(); ++i) {
    if (!m.alive(AttribNodeIdx{i}) || in_curve[i]) continue;
    const auto& an = m.attrib_nodes;
    const SurfaceLocation l{an.kind[i], an.element[i], an.param[i], an.corner[i]};
    if (touched(l)) moves.push_back({AttribNodeIdx{i}, 0, l});
  }
  for (std::size_t i = 0; i < opt.probes.size(); ++i) {
    const SurfaceLocation& l = opt.probes[i];
    const bool ok =
        l.kind == AttribNodeKind::kVertex ? l.element < m.nodes.slots.capacity() && m.alive(NodeIdx{l.element})
        : l.kind == AttribNodeKind::kEdge ? l.element < 2 * m.edges.slots.capacity() && m.alive(HalfedgeIdx{l.element})
                                          : l.element < m.faces.slots.capacity() && m.alive(FaceIdx{l.element}) &&
                                                l.corner + 3u <= m.face_degree(FaceIdx{l.element});
    if (!ok || !l.param.allFinite())
      return status_of(ErrorCode::kInvalidArgument, "retriangulate: probe ", i, " is not on the model");
    moves.push_back({AttribNodeIdx{}, i, l});
  }
  // Plan each move as (fan, bary) or (edge, u) in pre-apply terms.
  struct Target {
    int kind = 0;  // 0 unchanged, 1 fan triangle of a replaced face, 2 split edge
    FanKey fan;
    Vec3d bary = Vec3d::Zero();
    std::uint32_t edge = 0;
    double u = 0;
  };
  std::vector<Target> targets(moves.size());
  for (std::size_t i = 0; i < moves.size(); ++i) {
    const SurfaceLocation& l = moves[i].from;
    if (l.kind == AttribNodeKind::kFace && replaced[l.element]) {
      Vec3d b = l.param.cwiseMax(0.0);
      b /= std::max(b.sum(), 1e-300);
      targets[i] = {1, {l.element, l.corner}, b, 0, 0};
    } else if (l.kind == AttribNodeKind::kEdge && P.edge_pts.count(edge_of(HalfedgeIdx{l.element}).value)) {
      const HalfedgeIdx h{l.element};
      const double u = std::clamp(l.param.x(), 0.0, 1.0);
      targets[i] = {2, {}, Vec3d::Zero(), edge_of(h).value, is_forward(h) ? u : 1 - u};
    }
  }

  // ---------------------------------------------------------------- apply
  RetriangulationResult out;
  out.crossings = P.crossings;
  out.fans_without_cdt = pl.fans_without_cdt;
  out.faces_removed = faces.size();
  out.edges_split = P.edge_pts.size();
  std::vector<std::uint8_t> face_flags(faces.size());
  std::vector<SurfaceIdx> face_surf(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    face_flags[i] = m.faces.flags[faces[i].value];
    face_surf[i] = m.faces.surface[faces[i].value];
  }
  {
    // One growth of every column instead of one per append (a model fresh
    // from a copy or a reader has no spare capacity).
    std::size_t new_nodes = 0, splits = 0, tris = 0;
    for (const Pt& p : P.pts) new_nodes += !p.node.valid();
    for (const auto& [e, list] : P.edge_pts) splits += list.size();
    for (const auto& [fk, fp] : P.fans) tris += fp.tris.size();
    m.reserve(m.nodes.slots.capacity() + new_nodes, m.edges.slots.capacity() + splits + 3 * tris,
              m.faces.slots.capacity() + tris);
  }
  for (Pt& p : P.pts)
    if (!p.node.valid()) {
      p.node = m.new_node(p.surface, p.pos);
      ++out.nodes_added;
    }
  for (FaceIdx f : faces) m.delete_face(f);
  // Split edges (now faceless on the replaced sides): e keeps its tail and
  // ends at the first point; new edges follow in order.
  std::pmr::map<std::uint32_t, std::vector<NodeIdx>> edge_nodes(&local);  // edge -> nodes from tail(2e) to head(2e)
  for (const auto& [e, list] : P.edge_pts) {
    const EdgeIdx ei{e};
    HalfedgeIdx h = halfedge_of(ei, 0);
    std::vector<NodeIdx> chain{m.tail(h)};
    const NodeIdx last = m.head(h);
    for (const auto& [u, id] : list) {
      const NodeIdx x = P.pts[id].node;
      chain.push_back(x);
      const HalfedgeIdx t = twin(h);
      const NodeIdx b = m.head(h);
      m.set_tail(t, x);
      const EdgeIdx e2 = m.new_edge(x, b);
      const HalfedgeIdx g = halfedge_of(e2, 0);
      m.edges.flags[e2.value] = m.edges.flags[e];
      chain_split_edge(m, h, g);
      h = g;
    }
    chain.push_back(last);
    edge_nodes.emplace(e, std::move(chain));
  }
  // New faces.
  std::pmr::map<FanKey, std::vector<FaceIdx>> fan_faces(&local);
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const FaceIdx f = faces[i];
    const std::uint32_t k = static_cast<std::uint32_t>(pl.hs(f).size());
    for (std::uint32_t j = 0; j + 2 < k; ++j) {
      FanPlan& fp = P.fans.at({f.value, j});
      for (const auto& t : fp.tris) {
        std::array<HalfedgeIdx, 3> cyc;
        for (int c = 0; c < 3; ++c) {
          const NodeIdx a = P.pts[t[c]].node, b = P.pts[t[(c + 1) % 3]].node;
          HalfedgeIdx x = m.find_halfedge(a, b);
          if (!x.valid()) x = halfedge_of(m.new_edge(a, b), 0);
          cyc[c] = x;
        }
        const FaceIdx nf = m.new_face(face_surf[i], cyc);
        m.faces.flags[nf.value] = face_flags[i];
        fan_faces[fp.fan].push_back(nf);
        ++out.faces_added;
      }
    }
  }
  // Moves: foreign attribute nodes and probes.
  auto locate = [&](const Target& t, SurfaceLocation& l, double& margin) {
    if (t.kind == 1) {
      const FanPlan& fp = P.fans.at(t.fan);
      const Vec2d q = t.bary[0] * fp.c2[0] + t.bary[1] * fp.c2[1] + t.bary[2] * fp.c2[2];
      const auto& nf = fan_faces.at(t.fan);
      double best = -INFINITY;
      for (std::size_t x = 0; x < fp.tris.size(); ++x) {
        const auto& c = fp.tri2[x];
        const double area = cross2(c[1] - c[0], c[2] - c[0]);
        if (!(area > 0)) continue;
        const Vec3d w(cross2(c[1] - q, c[2] - q) / area, cross2(c[2] - q, c[0] - q) / area,
                      cross2(c[0] - q, c[1] - q) / area);
        if (w.minCoeff() > best) {
          best = w.minCoeff();
          Vec3d ww = w.cwiseMax(0.0);
          ww /= ww.sum();
          l = {AttribNodeKind::kFace, nf[x].value, ww, 0};
        }
      }
      margin = std::max(0.0, best);
    } else if (t.kind == 2) {
      const auto& chain = edge_nodes.at(t.edge);
      std::vector<double> us{0.0};
      for (const auto& [u, id] : P.edge_pts.at(t.edge)) us.push_back(u);
      us.push_back(1.0);
      std::size_t i = 0;
      while (i + 2 < us.size() && t.u > us[i + 1]) ++i;
      const double len = us[i + 1] - us[i];
      const double lu = len > 0 ? std::clamp((t.u - us[i]) / len, 0.0, 1.0) : 0.0;
      l = {AttribNodeKind::kEdge, m.find_halfedge(chain[i], chain[i + 1]).value, Vec3d(lu, 0, 0), 0};
      margin = 0;
    }
  };
  out.probes.assign(opt.probes.begin(), opt.probes.end());
  out.probe_margin.assign(opt.probes.size(), 0.0);
  for (std::size_t i = 0; i < moves.size(); ++i) {
    SurfaceLocation l = moves[i].from;
    double margin = 0;
    if (targets[i].kind == 0) {
      if (l.kind == AttribNodeKind::kFace) margin = l.param.minCoeff();
    } else {
      locate(targets[i], l, margin);
    }
    if (moves[i].a.valid()) {
      auto& an = m.attrib_nodes;
      an.kind[moves[i].a.value] = l.kind;
      an.element[moves[i].a.value] = l.element;
      an.param[moves[i].a.value] = l.param;
      an.corner[moves[i].a.value] = l.corner;
    } else {
      out.probes[moves[i].probe] = l;
      out.probe_margin[moves[i].probe] = margin;
    }
  }
  // The curves: nodes become ATTRIB_NODEs on mesh nodes, inserted points
  // become new attribute nodes in the rows.
  out.chains.resize(cur.size());
  out.nodes.resize(cur.size());
  for (std::size_t c = 0; c < cur.size(); ++c) {
    const auto row = m.attrib_edges.nodes.row(cur[c].value);
    const std::vector<AttribNodeIdx> old(row.begin(), row.end());
    const SurfaceIdx s = m.attrib_edges.surface[cur[c].value];
    std::vector<AttribNodeIdx> now;
    std::vector<NodeIdx> nodes;
    auto put = [&](AttribNodeIdx a, std::uint32_t pid) {
      auto& an = m.attrib_nodes;
      const NodeIdx v = P.pts[pid].node;
      an.kind[a.value] = AttribNodeKind::kVertex;
      an.element[a.value] = v.value;
      an.param[a.value] = Vec3d::Zero();
      an.corner[a.value] = 0;
      an.position[a.value] = m.position(v);
      an.surface[a.value] = m.nodes.surface[v.value];
      now.push_back(a);
      if (nodes.empty() || nodes.back() != v) nodes.push_back(v);
    };
    for (std::size_t k = 0; k < old.size(); ++k) {
      put(old[k], row_pid[c][k]);
      if (k + 1 == old.size()) break;
      const auto& segs = P.curve_seg[c][k];
      for (std::size_t x = 0; x < segs.size(); ++x) {
        const Segment& sg = P.segments[segs[x]];
        std::vector<std::uint32_t> add;
        for (const auto& [t, q] : sg.inner) add.push_back(q);
        if (x + 1 < segs.size()) add.push_back(sg.b);  // a polygon diagonal point between pieces
        for (std::uint32_t q : add) {
          const AttribNodeIdx a = m.new_attrib_node(s, AttribNodeKind::kVertex, P.pts[q].node.value, Vec3d::Zero(),
                                                    m.position(P.pts[q].node));
          put(a, q);
        }
      }
    }
    m.attrib_edges.nodes.assign(cur[c].value, now);
    for (AttribNodeIdx a : now) m.attrib_nodes.owner[a.value] = cur[c];
    for (std::size_t k = 0; k + 1 < nodes.size(); ++k) {
      const HalfedgeIdx h = m.find_halfedge(nodes[k], nodes[k + 1]);
      out.chains[c].push_back(h);
    }
    out.nodes[c] = std::move(nodes);
  }
  return out;
}

}  // namespace atelier
