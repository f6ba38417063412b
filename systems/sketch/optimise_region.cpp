// Why this file is long: the remeshing rounds and the local repair share the
// same operator wrappers (split, collapse, swap, relax with their validity
// tests), kept together in one anonymous-namespace class.
//
// Step 5 of the extrusion (seed 002 Fig. 9) as its own entry point; see
// optimise_region.h. The region's edge list is gathered once from its faces
// and then kept from the operators' results (never a scan of the face slots
// per pass), the relaxation projects by a walk from each node's last closest
// triangle (a BVH query only at a fold) and visits only the nodes whose ring
// changed after the first round, and the repair works on a FIFO queue of
// edges, so the cost follows the region and the edits.
//
// extrude_detail::optimise_outside (extrude's settle rounds, beyond seed
// 002) is the same optimisation keeping its places outside a body: split
// points and relaxed nodes that would lie within the clearance are pushed
// out (closest body point + c n), and a relaxed node whose projection
// onto the region lands there keeps its tangential place, pushed out; and
// the repair's last move for a slightly-out edge searches places around an
// end in its tangent plane (search_move).
#include <atelier/systems/mesh/edit.h>
#include <atelier/systems/sketch/optimise_region.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/spatial/collision_body.h>
#include <atelier/systems/spatial/triangle_query.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <string>
#include <vector>

#include "extrude_detail.h"

namespace atelier {

namespace {

Status region_error(ErrorCode c, const std::string& what) {
  return Status(c, "optimise_region: " + what);
}

Vec3d tri_normal(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  return (b - a).cross(c - a);
}

using RingPair = std::array<NodeIdx, 2>;  // see Optimiser::no_flip_ring

/// With a body (optimise_outside): a split's pushed point at most this far
/// from either end, in the edge's length (0.5 at the middle).
constexpr double kPushedSplitReach = 0.6;

class Optimiser {
 public:
  Optimiser(Model& m, const RegionOptimiseOptions& o) : m_(m), o_(o) {
    lo_ = o.low * o.target;
    hi_ = o.high * o.target;
    // A collapse may leave edges up to 2 lo (> hi): the split that follows
    // halves them into edges >= lo, so dense rows can still be thinned.
    collapse_limit_ = std::max(hi_, 2 * lo_);
  }

  Status init(std::span<const FaceIdx> region, std::span<const NodeIdx> fixed, bool edits) {
    std::vector<char> in(m_.faces.slots.capacity(), 0);
    for (FaceIdx f : region) {
      if (!f.valid() || f.value >= in.size() || !m_.alive(f))
        return region_error(ErrorCode::kInvalidArgument, "region face " + std::to_string(f.value) + " is dead");
      if (m_.face_degree(f) != 3)
        return region_error(ErrorCode::kInvalidArgument,
                            "region face " + std::to_string(f.value) + " is not a triangle");
      in[f.value] = 1;
      m_.for_each_face_halfedge(f, [&](HalfedgeIdx h) { fresh_.push_back(edge_of(h)); });
    }
    outside_.assign(in.size(), 0);
    fixed_.assign(m_.nodes.slots.capacity(), 0);
    for (std::uint32_t f = 0; f < in.size(); ++f) {
      if (in[f] || !m_.alive(FaceIdx{f})) continue;
      outside_[f] = 1;
      m_.for_each_face_halfedge(FaceIdx{f}, [&](HalfedgeIdx h) { fixed_[m_.tail(h).value] = 1; });
    }
    for (NodeIdx v : fixed) {
      if (!v.valid() || v.value >= fixed_.size() || !m_.alive(v))
        return region_error(ErrorCode::kInvalidArgument, "fixed node " + std::to_string(v.value) + " is dead");
      fixed_[v.value] = 1;
    }
    // Any corner of a region face on a border (see on_border)? A free
    // corner's edges are all region face sides; a fixed one's ring is walked.
    for (std::size_t r = 0; r < region.size() && !any_border_; ++r)
      m_.for_each_face_halfedge(region[r], [&](HalfedgeIdx h) {
        any_border_ =
            any_border_ || !m_.face(twin(h)).valid() || (fixed_[m_.tail(h).value] && slow_on_border(m_.tail(h)));
      });
    eo_.check_ring_nodes = false;
    for (std::uint32_t v = 0; v < m_.nodes.slots.capacity(); ++v)
      if (m_.alive(NodeIdx{v}) && m_.nodes.in_face[v].valid()) eo_.check_ring_nodes = true;
    // The region on entry: the projection target of the relaxation, its
    // points shared so that a projection can walk from triangle to triangle
    // (BodyBvh keeps a view of the points: they are members).
    // Adjacency from the model's own halfedges: no sort.
    if (!edits) return {};
    std::vector<std::uint32_t> local(m_.nodes.slots.capacity(), kNoTriangle), tri_of(in.size(), kNoTriangle);
    std::vector<HalfedgeIdx> hs;
    for (std::size_t r = 0; r < region.size(); ++r) tri_of[region[r].value] = static_cast<std::uint32_t>(r);
    ref_tris_.resize(region.size());
    ref_across_.resize(region.size());
    for (std::size_t r = 0; r < region.size(); ++r) {
      hs.clear();
      m_.for_each_face_halfedge(region[r], [&](HalfedgeIdx h) { hs.push_back(h); });
      for (int k = 0; k < 3; ++k) {
        const NodeIdx v = m_.tail(hs[k]);
        std::uint32_t& l = local[v.value];
        if (l == kNoTriangle) {
          l = static_cast<std::uint32_t>(ref_pts_.size());
          ref_pts_.push_back(m_.position(v));
        }
        ref_tris_[r][k] = l;
        set_hint(v, static_cast<std::uint32_t>(r));
        const FaceIdx g = m_.face(twin(hs[k]));
        ref_across_[r][k] = g.valid() && g.value < tri_of.size() ? tri_of[g.value] : kNoTriangle;
      }
    }
    ref_ring_offset_.assign(ref_pts_.size() + 1, 0);
    for (const Triangle& t : ref_tris_)
      for (std::uint32_t v : t) ++ref_ring_offset_[v + 1];
    for (std::size_t v = 0; v < ref_pts_.size(); ++v) ref_ring_offset_[v + 1] += ref_ring_offset_[v];
    ref_ring_.resize(ref_ring_offset_.back());
    std::vector<std::uint32_t> fill(ref_ring_offset_.begin(), ref_ring_offset_.end() - 1);
    for (std::uint32_t t = 0; t < ref_tris_.size(); ++t)
      for (std::uint32_t v : ref_tris_[t]) ref_ring_[fill[v]++] = t;
    can_project_ = !ref_tris_.empty();
    // The walk finds the closest point only on a surface without folds: a
    // pair of neighbouring triangles turned by more than 60 degrees makes
    // every projection a BVH query.
    std::size_t folds = 0;  // (the sleeve and dress of the garment tests have some)
    for (std::uint32_t t = 0; t < ref_tris_.size() && folds == 0; ++t) {
      const Vec3d nt = ref_normal(t);
      for (std::uint32_t u : ref_across_[t])
        if (u != kNoTriangle && u > t) {
          const Vec3d nu = ref_normal(u);
          folds += !(nt.dot(nu) > 0.5 * nt.norm() * nu.norm());
        }
    }
    walk_ = folds == 0;
    return {};
  }

  // ------------------------------------------------------- projection
  void set_hint(NodeIdx v, std::uint32_t t) {
    if (v.value >= hint_.size())
      hint_.resize(std::max<std::size_t>(m_.nodes.slots.capacity(), v.value + 1), kNoTriangle);
    hint_[v.value] = t;
  }

  /// Closest point of q on the region on entry, walking from triangle t to
  /// the neighbour (across the edge, or around the corner, that holds the
  /// current closest point) while the distance drops: the moves are short
  /// against the surface's curvature, so the walk ends at the closest
  /// triangle in a few steps instead of a BVH descent (the BVH query stays
  /// the fallback when a walk runs long).
  std::uint32_t walk(const Vec3d& q, std::uint32_t t, Vec3d& out) {
    auto cp = [&](std::uint32_t u) {
      const Triangle& T = ref_tris_[u];
      return closest_point_on_triangle(q, ref_pts_[T[0]], ref_pts_[T[1]], ref_pts_[T[2]]);
    };
    TrianglePoint c = cp(t);
    double d = (c.point - q).squaredNorm();
    for (int step = 0; step < 256; ++step) {
      if (c.feature == TriFeature::kFace) break;
      std::uint32_t best = kNoTriangle;
      TrianglePoint bc;
      double bd = d;
      auto consider = [&](std::uint32_t u) {
        if (u == kNoTriangle || u == t) return;
        const TrianglePoint uc = cp(u);
        const double ud = (uc.point - q).squaredNorm();
        if (ud < bd) bd = ud, best = u, bc = uc;
      };
      const auto fk = static_cast<int>(c.feature);
      if (fk >= static_cast<int>(TriFeature::kEdge01)) {
        consider(ref_across_[t][fk - static_cast<int>(TriFeature::kEdge01)]);
      } else {
        const std::uint32_t v = ref_tris_[t][fk];
        for (std::uint32_t i = ref_ring_offset_[v]; i < ref_ring_offset_[v + 1]; ++i) consider(ref_ring_[i]);
      }
      if (best == kNoTriangle) {
        out = c.point;
        return t;
      }
      t = best, c = bc, d = bd;
      if (step == 255) {  // a long walk: ask the tree
        const ClosestHit hit = tree().closest_point(q);
        out = hit.point;
        return hit.triangle;
      }
    }
    out = c.point;
    return t;
  }

  /// Projects q (a new place of v, |q - p| short) onto the region on
  /// entry, starting from v's hint; tri receives the closest triangle.
  bool project(NodeIdx v, Vec3d& q, std::uint32_t& tri) {
    const Vec3d q0 = q;
    if (!project_region(v, q, tri)) return false;
    if (!body_ || !extrude_detail::within_clearance(body_->query(q), clear_)) return true;
    // The region runs through the body there (a triangle across a limb
    // between pushed nodes): the tangential place itself, pushed out.
    q = q0;
    return push(q);
  }

  bool project_region(NodeIdx v, Vec3d& q, std::uint32_t& tri) {
    tri = v.value < hint_.size() ? hint_[v.value] : kNoTriangle;
    if (tri == kNoTriangle || !walk_) {
      const ClosestHit hit = tree().closest_point(q, o_.target);
      tri = hit.triangle;
      q = hit.point;
    } else {
      const Vec3d q0 = q;
      tri = walk(q, tri, q);
      // Far from the surface where the walk ended (a crease gentler than
      // the fold test's 60 degrees: the walk stops at a local minimum of the
      // distance): the tree, bounded by that distance, finds the global
      // one. On the garment tests' folded regions the walk alone ended up
      // to 3.9 L farther, hence the fold test.
      if (const double dw = (q - q0).norm(); dw > 0.02 * o_.target) {
        const ClosestHit hit = tree().closest_point(q0, dw);
        if (hit.triangle != kNoTriangle && hit.distance < dw) tri = hit.triangle, q = hit.point;
      }
    }
    return tri != kNoTriangle && q.allFinite();
  }

  bool walks() const { return walk_; }

  /// Keep every place c outside `body` (extrude's settle rounds; null: off).
  void keep_outside(const CollisionBody* body, double c) { body_ = body, clear_ = c; }

  /// q moved to the body's closest point + c n when it is closer than c
  /// (the body push of extrude_body.cpp). False on a non-finite answer.
  bool push(Vec3d& q) const {
    if (!body_) return true;
    const BodyDistance d = body_->query(q);
    if (!extrude_detail::within_clearance(d, clear_)) return true;
    const Vec3d r = extrude_detail::pushed_place(d, clear_);
    if (!r.allFinite()) return false;
    q = r;
    return true;
  }

  Vec3d ref_normal(std::uint32_t t) const {
    const Triangle& T = ref_tris_[t];
    return tri_normal(ref_pts_[T[0]], ref_pts_[T[1]], ref_pts_[T[2]]);
  }

  /// The BVH of the region on entry, built on first use (a walk that runs
  /// long, a node without a hint): most calls never need it.
  const BodyBvh& tree() {
    if (!tree_built_) tree_built_ = true, (void)ref_.build(ref_pts_, ref_tris_, {}, ExecContext::sequential());
    return ref_;
  }

  void place(NodeIdx v, const Vec3d& q, std::uint32_t tri) {
    m_.nodes.position[v.value] = q;
    if (tri != kNoTriangle) set_hint(v, tri);
  }

  bool is_region(FaceIdx f) const {
    return f.valid() && m_.alive(f) && !(f.value < outside_.size() && outside_[f.value]);
  }
  bool fixed(NodeIdx v) const { return v.value < fixed_.size() && fixed_[v.value]; }
  bool editable(EdgeIdx e) const {
    if (!m_.alive(e)) return false;
    const FaceIdx a = m_.face(halfedge_of(e, 0)), b = m_.face(halfedge_of(e, 1));
    if (!a.valid() && !b.valid()) return false;
    return (!a.valid() || is_region(a)) && (!b.valid() || is_region(b));
  }
  double length(EdgeIdx e) const {
    return (m_.position(m_.tail(halfedge_of(e, 0))) - m_.position(m_.tail(halfedge_of(e, 1)))).norm();
  }
  bool in_bounds(double l) const { return l >= lo_ && l <= hi_; }
  bool slow_on_border(NodeIdx v) const {
    bool b = false;
    m_.for_each_outgoing(v, [&](HalfedgeIdx h) { b |= !m_.face(h).valid() || !m_.face(twin(h)).valid(); });
    return b;
  }
  /// v has an edge with a face on one side only. Every node asked about is
  /// a corner of a region face; without such a node on entry there is none
  /// ever (no operator opens a border): no walk then (the dome on the cup).
  bool on_border(NodeIdx v) const { return any_border_ && slow_on_border(v); }

  /// The editable edges: the list of the last call less the edges that
  /// died, then those the operators made since (each operator reports the
  /// edges around the node it made or kept), so no pass scans the face
  /// slots. Valid until the next call. An edge of the last list that is
  /// still alive is still editable: the faces outside the region never
  /// change, so an operator only ever puts region faces on an edge, and
  /// a slot an operator reuses holds one of its own (region) edges.
  const std::vector<EdgeIdx>& region_edges() {
    stamp_.resize(m_.edges.slots.capacity(), 0);
    ++tick_;
    scratch_.clear();
    for (EdgeIdx e : edges_) {
      if (stamp_[e.value] == tick_ || !m_.alive(e)) continue;
      stamp_[e.value] = tick_;
      scratch_.push_back(e);
    }
    for (EdgeIdx e : fresh_) {
      if (e.value >= stamp_.size() || stamp_[e.value] == tick_ || !editable(e)) continue;
      stamp_[e.value] = tick_;
      scratch_.push_back(e);
    }
    fresh_.clear();
    edges_.swap(scratch_);
    return edges_;
  }

  /// The edges around v are new (or changed ends): region_edges() takes
  /// them, and v's ring is relaxed in the next round.
  void report_ring(NodeIdx v) {
    mark(v);
    m_.for_each_outgoing(v, [&](HalfedgeIdx h) {
      fresh_.push_back(edge_of(h));
      mark(m_.head(h));
    });
  }

  /// v's ring changed since the last relaxation (see relax_all).
  void mark(NodeIdx v) {
    if (v.value >= dirty_.size()) dirty_.resize(std::max<std::size_t>(m_.nodes.slots.capacity(), v.value + 1), 0);
    if (dirty_[v.value] == epoch_) return;
    dirty_[v.value] = epoch_;
    dirty_list_.push_back(v);
  }

  EdgeLengthStats stats() {
    EdgeLengthStats s;
    s.min = INFINITY;
    double sum = 0;
    for (EdgeIdx e : region_edges()) {
      const double l = length(e);
      ++s.edges;
      sum += l;
      s.min = std::min(s.min, l);
      s.max = std::max(s.max, l);
      s.outside += !in_bounds(l);
    }
    if (s.edges == 0) return EdgeLengthStats{};
    s.mean = sum / static_cast<double>(s.edges);
    s.within = static_cast<double>(s.edges - s.outside) / static_cast<double>(s.edges);
    return s;
  }

  // ---------------------------------------------------------- operators
  /// Splits e at its midpoint; returns the new node (invalid when refused).
  NodeIdx split(EdgeIdx e) {
    const NodeIdx a = m_.tail(halfedge_of(e, 0));
    const Vec3d& pa = m_.position(a);
    const Vec3d& pb = m_.position(m_.tail(halfedge_of(e, 1)));
    Vec3d mid = 0.5 * (pa + pb);
    if (body_) {
      // A split at a midpoint inside the body (an edge across a limb between
      // pushed nodes) pushed out: refused when the pushed point is no longer
      // near the middle, since the halves would not be shorter (splits and
      // collapses then churned there, 3000 of each on a 350-face region).
      const double l = (pa - pb).norm();
      if (!push(mid) || (mid - pa).norm() > kPushedSplitReach * l || (mid - pb).norm() > kPushedSplitReach * l)
        return {};
    }
    NodeIdx n;
    if (plain_ && !m_.edges.mesh_edge[e.value].valid()) {
      n = split_plain(e, mid);
    } else {
      const bool chain = m_.edges.mesh_edge[e.value].valid();
      auto s = edge_split(m_, m_.handle(e), mid, eo_);
      if (!s) return {};
      n = s->nodes.at(0).idx;
      if (chain) constrain(n);
    }
    ++rep_.splits;
    report_ring(n);
    set_hint(n, a.value < hint_.size() ? hint_[a.value] : kNoTriangle);
    return n;
  }

  /// Moving r to p makes no edge of r's ring (but the one to k) longer
  /// than the collapse limit (tested for both ends before the normals: most
  /// refused collapses fail there) and keeps every face around r (but those
  /// holding k) turned the same way. r staying where it is (a fixed end of
  /// B, or a border end kept) changes none of its edges or faces: its edges
  /// outside the region may be far longer than hi and must not veto the
  /// collapse.
  bool collapse_ring_ok(NodeIdx r, NodeIdx k, const Vec3d& p) const {
    if (p == m_.position(r)) return true;
    const double lim = collapse_limit_ * collapse_limit_;
    const Vec3d& pr = m_.position(r);
    bool ok = true;
    m_.for_each_outgoing(r, [&](HalfedgeIdx h) {
      if (!ok) return;
      const NodeIdx w = m_.head(h);
      if (w == k) return;  // (its face holds k too)
      const Vec3d& pw = m_.position(w);
      if ((pw - p).squaredNorm() > lim) {
        ok = false;
        return;
      }
      // Triangle (r, w, u) with u = head(next(h)).
      if (!m_.face(h).valid()) return;
      const NodeIdx u = m_.head(m_.next(h));
      if (u == k) return;
      const Vec3d& pu = m_.position(u);
      const Vec3d n0 = tri_normal(pr, pw, pu), n1 = tri_normal(p, pw, pu);
      ok = n0.dot(n1) > 0.2 * n0.norm() * n1.norm();
    });
    return ok;
  }
  /// Both ends of a collapse of gone into keep at p pass collapse_ring_ok.
  bool collapse_fits(NodeIdx gone, NodeIdx keep, const Vec3d& p) const {
    return collapse_ring_ok(gone, keep, p) && collapse_ring_ok(keep, gone, p);
  }

  /// Collapses e (B's end, or a border end, kept in place); returns the kept
  /// node (invalid when refused). Err only on an internal failure.
  Expected<NodeIdx> collapse(EdgeIdx e) {
    const NodeIdx a = m_.tail(halfedge_of(e, 0)), b = m_.tail(halfedge_of(e, 1));
    if (fixed(a) && fixed(b)) return NodeIdx{};
    NodeIdx keep = a, gone = b;
    if (fixed(b)) keep = b, gone = a;
    Vec3d p = 0.5 * (m_.position(a) + m_.position(b));
    // The region's own collapse (collapse_plain) where the generic
    // operator's bookkeeping has nothing to do: no mesh edge at e or its
    // ends, two triangles on e, no attribute or ring node in the model. It
    // may keep either end.
    const bool plain = plain_ && !m_.edges.mesh_edge[e.value].valid() && !constrained(a) && !constrained(b) &&
                       m_.face(halfedge_of(e, 0)).valid() && m_.face(halfedge_of(e, 1)).valid();
    if (fixed(keep)) {
      p = m_.position(keep);
      // edge_collapse keeps the tail of halfedge 2e unless e is on no mesh
      // edge and only the other end is (the temporary one along the chain).
      NodeIdx kept = a;
      if (!plain && !m_.edges.mesh_edge[e.value].valid() && on_mesh_edge(a) != on_mesh_edge(b))
        kept = on_mesh_edge(a) ? a : b;
      if (!plain && kept != keep) return NodeIdx{};
    } else {
      const bool ba = on_border(a), bb = on_border(b);
      const bool border_edge = !m_.face(halfedge_of(e, 0)).valid() || !m_.face(halfedge_of(e, 1)).valid();
      if (ba && !bb) p = m_.position(a);
      if (bb && !ba) p = m_.position(b);
      if (ba && bb && !border_edge) return NodeIdx{};
      if (ba && bb) {  // along the border: a corner keeps its place
        const double ta = border_turn_cos(a), tb = border_turn_cos(b);
        bool ca = is_corner(ta), cb = is_corner(tb);
        if (ca && cb) {
          // Two corners at the ends of one short border edge (a chamfer of
          // the free end, e.g. the last copy of a B with a short edge between
          // two turns) meet at the edge's midpoint when each turns by less
          // than 60 degrees: the border then turns once, by about their sum,
          // and the free end keeps its outline to within half the edge.
          if (!(is_chamfer(ta) && is_chamfer(tb))) return NodeIdx{};
          ca = cb = false;
        }
        if (ca) p = m_.position(a);
        if (cb) p = m_.position(b);
      }
    }
    if (!collapse_fits(gone, keep, p)) {
      // Last resort, two free inner ends: the midpoint may fold a face or
      // stretch an edge where one of the ends would not (a crease of the
      // swept surface, a pushed fold): try each end's place.
      if (collapse_limit_ <= hi_ || fixed(keep) || on_border(a) || on_border(b)) return NodeIdx{};
      bool found = false;
      for (const NodeIdx at : {a, b}) {
        p = m_.position(at);
        if (collapse_fits(gone, keep, p)) {
          found = true;
          break;
        }
      }
      if (!found) return NodeIdx{};
    }
    const Vec3d keep_pos = m_.position(keep);
    NodeIdx kept = keep;
    if (plain) {
      const HalfedgeIdx h = halfedge_of(e, m_.tail(halfedge_of(e, 0)) == keep ? 0 : 1);
      if (!collapse_plain_ok(h)) return NodeIdx{};
      collapse_plain(h, p);
    } else {
      auto res = edge_collapse(m_, m_.handle(e), p, eo_);
      if (!res) return NodeIdx{};
      kept = res->kept.at(0).idx;
    }
    if (fixed(keep) && (kept != keep || m_.position(kept) != keep_pos))
      return region_error(ErrorCode::kInternal, "a collapse moved fixed node " + std::to_string(keep.value));
    ++rep_.collapses;
    report_ring(kept);
    return kept;
  }

  // ------------------------------------------- the region's own operators
  // Split and collapse of an edge of the all-triangle region away from any
  // mesh edge, in a model without attribute or ring nodes: the same
  // primitives in the same order as edge_split / edge_collapse
  // (systems/mesh/edit.cpp, Table 3) without what they do for joints,
  // chains, polygons and attributes (a lookup of the joint, result vectors,
  // scans of the attribute table, ring walks for mesh edges), which is
  // most of their cost here. The model stays valid after each; optimise_region
  // as a whole stays transactional (its copy of the model).

  /// Node on a mesh edge (the generic operators keep such nodes on it).
  bool constrained(NodeIdx v) const { return v.value < constrained_.size() && constrained_[v.value]; }
  void constrain(NodeIdx v) {
    if (v.value >= constrained_.size())
      constrained_.resize(std::max<std::size_t>(m_.nodes.slots.capacity(), v.value + 1), 0);
    constrained_[v.value] = 1;
  }

  /// After the temporary chain is made: the nodes on mesh edges, and
  /// whether the plain operators may run at all.
  void note_constraints() {
    constrained_.assign(m_.nodes.slots.capacity(), 0);
    for (std::uint32_t me = 0; me < m_.mesh_edges.slots.capacity(); ++me) {
      if (!m_.alive(MeshEdgeIdx{me})) continue;
      for (HalfedgeIdx h : m_.mesh_edges.halfedges.row(me))
        if (m_.alive(h)) constrained_[m_.tail(h).value] = constrained_[m_.head(h).value] = 1;
    }
    plain_ = !eo_.check_ring_nodes && m_.attrib_nodes.slots.empty();
  }

  /// Splits e (no mesh edge; its faces triangles) at p: each triangle on
  /// it becomes two through the new node and the opposite corner, as
  /// split_one + cut_quad in edit.cpp. Returns the new node.
  NodeIdx split_plain(EdgeIdx e, const Vec3d& p) {
    const HalfedgeIdx h = halfedge_of(e, 0), t = halfedge_of(e, 1);  // a -> b, b -> a
    const NodeIdx a = m_.tail(h), b = m_.tail(t);
    const FaceIdx fh = m_.face(h), ft = m_.face(t);
    // The faces' other sides: b -> c -> a and a -> d -> b.
    const HalfedgeIdx bc = fh.valid() ? m_.next(h) : HalfedgeIdx{}, ca = fh.valid() ? m_.next(bc) : HalfedgeIdx{};
    const HalfedgeIdx ad = ft.valid() ? m_.next(t) : HalfedgeIdx{}, db = ft.valid() ? m_.next(ad) : HalfedgeIdx{};
    const SurfaceIdx s = m_.nodes.surface[a.value];
    const NodeIdx v = m_.new_node(s, p);
    m_.nodes.in_face[v.value] = m_.nodes.in_face[a.value];
    // Interpolated at p's parameter along a -> b, as split_edge_raw does.
    const Vec3d ab = m_.position(b) - m_.position(a);
    const double l2 = ab.squaredNorm();
    const double u = l2 > 0 ? std::clamp((p - m_.position(a)).dot(ab) / l2, 0.0, 1.0) : 0.5;
    m_.nodes.uv[v.value] = (1.0 - u) * m_.nodes.uv[a.value] + u * m_.nodes.uv[b.value];
    m_.nodes.position_backup[v.value] =
        (1.0 - u) * m_.nodes.position_backup[a.value] + u * m_.nodes.position_backup[b.value];
    const EdgeIdx g = m_.new_edge(v, b);
    const HalfedgeIdx gs = halfedge_of(g, 0), gt = halfedge_of(g, 1);  // v -> b, b -> v
    m_.edges.flags[g.value] = m_.edges.flags[e.value];
    m_.set_tail(t, v);  // t: v -> a, h: a -> v
    // Each face replaced by its two halves in edit.cpp's order (delete,
    // new edge, two faces), so that the slots are those edge_split takes.
    auto cut = [&](FaceIdx f, const std::array<HalfedgeIdx, 5>& r) {
      const std::uint8_t flags = m_.faces.flags[f.value];
      m_.delete_face(f);
      const EdgeIdx d = m_.new_edge(v, m_.tail(r[4]));
      const HalfedgeIdx c1[3] = {r[0], r[1], halfedge_of(d, 1)}, c2[3] = {halfedge_of(d, 0), r[2], r[3]};
      m_.faces.flags[m_.new_face(s, c1).value] = flags;
      m_.faces.flags[m_.new_face(s, c2).value] = flags;
    };
    if (fh.valid()) cut(fh, {gs, bc, ca, h, ca});
    if (ft.valid()) cut(ft, {t, ad, db, gt, db});
    return v;
  }

  /// edit.cpp's collapse checks for h = keep -> gone, on two triangles and
  /// no mesh edge near: no dangling or folded face, no opposite node left
  /// with valence 2, the two opposite nodes distinct, and the link
  /// condition (every common neighbour of the ends opposite e).
  bool collapse_plain_ok(HalfedgeIdx h) {
    NodeIdx opp[2];
    const HalfedgeIdx sides[2] = {h, twin(h)};
    for (int k = 0; k < 2; ++k) {
      const HalfedgeIdx x1 = m_.next(sides[k]), x2 = m_.next(x1);
      opp[k] = m_.head(x1);
      const FaceIdx g1 = m_.face(twin(x1)), g2 = m_.face(twin(x2));
      if (!g1.valid() && !g2.valid()) return false;
      if (g1.valid() && g1 == g2) return false;
      if (valence_at_most_3(opp[k]) && !on_border(opp[k])) return false;
    }
    if (opp[0] == opp[1]) return false;
    const NodeIdx a = m_.tail(h), b = m_.head(h);
    node_stamp_.resize(std::max(node_stamp_.size(), m_.nodes.slots.capacity()), 0);
    const std::uint32_t mark = ++tick_;
    m_.for_each_outgoing(a, [&](HalfedgeIdx x) { node_stamp_[m_.head(x).value] = mark; });
    bool ok = true;
    m_.for_each_outgoing(b, [&](HalfedgeIdx x) {
      const NodeIdx w = m_.head(x);
      if (w != opp[0] && w != opp[1] && node_stamp_[w.value] == mark) ok = false;
    });
    return ok;
  }

  bool valence_at_most_3(NodeIdx v) const {
    const HalfedgeIdx start = m_.nodes.out[v.value];
    HalfedgeIdx h = start;
    for (int n = 0; n < 3; ++n) {  // d steps back to start: valence d
      h = m_.halfedges.vnext[h.value];
      if (h == start) return true;
    }
    return false;
  }

  /// Collapses h = keep -> gone into keep at p (collapse_one in edit.cpp,
  /// triangles only): each face on e goes with gone's other edge in it,
  /// whose outer face takes keep's edge instead.
  void collapse_plain(HalfedgeIdx h, const Vec3d& p) {
    const NodeIdx a = m_.tail(h), b = m_.head(h);
    for (const HalfedgeIdx x : {h, twin(h)}) {
      const HalfedgeIdx x1 = m_.next(x), x2 = m_.next(x1);
      const HalfedgeIdx rin = m_.tail(x1) == b ? x1 : x2, kin = rin == x1 ? x2 : x1, rout = twin(rin);
      m_.delete_face(m_.face(x));
      (void)edit_detail::hand_over_side(m_, rout, kin);
      m_.edges.flags[edge_of(kin).value] |= m_.edges.flags[edge_of(rin).value];
      m_.delete_edge(edge_of(rin));
    }
    m_.delete_edge(edge_of(h));
    hs_.clear();
    m_.for_each_outgoing(b, [&](HalfedgeIdx x) { hs_.push_back(x); });
    for (HalfedgeIdx x : hs_) m_.set_tail(x, a);
    m_.delete_node(b);
    m_.nodes.position[a.value] = p;
    ++m_.geometry_version;
  }

  bool on_mesh_edge(NodeIdx v) const {
    bool on = false;
    m_.for_each_outgoing(v, [&](HalfedgeIdx h) { on |= m_.edges.mesh_edge[edge_of(h).value].valid(); });
    return on;
  }

  /// The swap of e is valid (two region triangles, no fold) and its new
  /// diagonal has length in [min_len, max_len].
  bool swap_ok(EdgeIdx e, double min_len, double max_len, NodeIdx* xy = nullptr) const {
    const HalfedgeIdx h = halfedge_of(e, 0), t = halfedge_of(e, 1);
    if (!m_.face(h).valid() || !m_.face(t).valid()) return false;
    // (the new diagonal's length first: most edges fail there)
    const NodeIdx a = m_.tail(h), b = m_.tail(t), x = m_.head(m_.next(h)), y = m_.head(m_.next(t));
    const double d = (m_.position(x) - m_.position(y)).norm();
    if (d > max_len || d < min_len) return false;
    if (m_.next(m_.next(m_.next(h))) != h || m_.next(m_.next(m_.next(t))) != t) return false;
    const Vec3d n0 = tri_normal(m_.position(a), m_.position(b), m_.position(x)) +
                     tri_normal(m_.position(b), m_.position(a), m_.position(y));
    const Vec3d n1 = tri_normal(m_.position(x), m_.position(y), m_.position(b));
    const Vec3d n2 = tri_normal(m_.position(y), m_.position(x), m_.position(a));
    if (!(n1.dot(n0) > 0 && n2.dot(n0) > 0 && n1.dot(n2) > 0.5 * n1.norm() * n2.norm())) return false;
    if (xy) xy[0] = x, xy[1] = y;
    return true;
  }

  bool swap(EdgeIdx e) {
    const HalfedgeIdx h = halfedge_of(e, 0), t = halfedge_of(e, 1);
    const NodeIdx ends[4] = {m_.tail(h), m_.tail(t), m_.head(m_.next(h)), m_.head(m_.next(t))};
    if (auto s = edge_swap(m_, m_.handle(e), eo_)) {
      for (NodeIdx v : ends) mark(v);
      ++rep_.swaps;
      return true;
    }
    return false;
  }

  /// How much closer to valence 6 (4 on a border) the swap of e brings its
  /// four nodes. One ring walk per node gives both its degree and whether
  /// it is on a border (the swap pass tests every region edge).
  int valence_gain(EdgeIdx e) const {
    const HalfedgeIdx h = halfedge_of(e, 0), t = halfedge_of(e, 1);
    const NodeIdx a = m_.tail(h), b = m_.tail(t), x = m_.head(m_.next(h)), y = m_.head(m_.next(t));
    auto gain = [&](NodeIdx v, int delta) {
      if (fixed(v)) return 0;
      int degree = 0;
      bool border = false;
      m_.for_each_outgoing(v, [&](HalfedgeIdx g) {
        ++degree;
        border = border || (any_border_ && (!m_.face(g).valid() || !m_.face(twin(g)).valid()));
      });
      const int off = degree - (border ? 4 : 6);
      return std::abs(off) - std::abs(off + delta);
    };
    return gain(a, -1) + gain(b, -1) + gain(x, 1) + gain(y, 1);
  }

  /// A border node where the border turns by more than 30 degrees (or with
  /// other than two border edges): its position is kept.
  bool corner(NodeIdx v) const { return is_corner(border_turn_cos(v)); }
  static bool is_corner(double turn_cos) { return !(turn_cos > std::cos(M_PI / 6)); }
  /// A corner whose border turns by less than 60 degrees (two border edges).
  static bool is_chamfer(double turn_cos) { return turn_cos > 0.5; }
  /// Cosine of the border's turn at v (1 off the border; -2 with other than
  /// two border edges).
  double border_turn_cos(NodeIdx v) const {
    Vec3d nb[2];
    int kb = 0;
    m_.for_each_outgoing(v, [&](HalfedgeIdx h) {
      if (m_.face(h).valid() && m_.face(twin(h)).valid()) return;
      if (kb < 2) nb[kb] = m_.position(m_.head(h));
      ++kb;
    });
    if (kb == 0) return 1;
    if (kb != 2) return -2;
    const Vec3d p = m_.position(v), d0 = p - nb[0], d1 = nb[1] - p;
    const double den = d0.norm() * d1.norm();
    return den > 0 ? d0.dot(d1) / den : -2;
  }

  /// Relaxation target of v (not applied). Inner nodes: the centroid of
  /// the neighbours (spring = false) or the mean of the points at distance L
  /// from each neighbour towards v (spring = true: pulls every ring edge
  /// towards L), in the tangent plane; border nodes: the same along the
  /// border (their two border neighbours; corners stay). Then projected
  /// onto the region on entry. False when v stays.
  bool relax_target(NodeIdx v, Vec3d& out, std::uint32_t& tri, bool spring = false) {
    tri = kNoTriangle;
    if (fixed(v) || m_.is_isolated(v)) return false;
    const Vec3d p = m_.position(v);
    Vec3d c = Vec3d::Zero(), n = Vec3d::Zero(), cb = Vec3d::Zero();
    int k = 0, kb = 0;
    // (v is free: every face on it is a region face, since every node of
    // a face outside the region is fixed and those faces never change)
    ring_pairs_.clear();
    m_.for_each_outgoing(v, [&](HalfedgeIdx h) {
      const FaceIdx f = m_.face(h), g = m_.face(twin(h));
      ring_pairs_.push_back({m_.head(h), f.valid() ? m_.head(m_.next(h)) : NodeIdx{}});
      const Vec3d w = m_.position(ring_pairs_.back()[0]);
      Vec3d t = w;
      if (spring) {
        const Vec3d d = p - w;
        const double l = d.norm();
        t = l > 0 ? Vec3d(w + (o_.target / l) * d) : w;
      }
      c += t;
      ++k;
      if (!f.valid() || !g.valid()) cb += t, ++kb;
      if (f.valid()) n += tri_normal(p, w, m_.position(ring_pairs_.back()[1]));
    });
    if (k == 0 || (kb != 0 && kb != 2) || !(n.norm() > 0)) return false;
    if (kb == 2 && corner(v)) return false;
    n.normalize();
    Vec3d q;
    if (kb == 2) {
      q = cb / 2;
    } else {
      const Vec3d d = c / k - p;
      q = p + d - d.dot(n) * n;
    }
    if (can_project_ && !project(v, q, tri)) return false;
    if (!no_flip_ring(p, q, ring_pairs_, 0.5)) return false;
    out = q;
    return true;
  }

  /// no_flip of a node at p whose ring relax_target recorded: (w, u) for
  /// each outgoing halfedge v -> w in order, u the third corner of its face
  /// (invalid without one). The ring does not change between the targets
  /// and the moves of a relaxation, so the moves walk this list instead of
  /// the halfedge columns again (cold in cache by then on a large region).
  bool no_flip_ring(const Vec3d& p, const Vec3d& q, std::span<const RingPair> ring, double cos_min) const {
    for (const RingPair& wu : ring)
      if (wu[1].valid() && !keeps_turn(p, q, m_.position(wu[0]), m_.position(wu[1]), cos_min)) return false;
    return true;
  }

  /// Moving v to q turns no face around it by more than acos(cos_min).
  bool no_flip(NodeIdx v, const Vec3d& q, double cos_min) const {
    bool ok = true;
    const Vec3d p = m_.position(v);
    m_.for_each_outgoing(v, [&](HalfedgeIdx h) {
      if (!ok || !m_.face(h).valid()) return;
      ok = keeps_turn(p, q, m_.position(m_.head(h)), m_.position(m_.head(m_.next(h))), cos_min);
    });
    return ok;
  }

  /// Triangle (p, a, b) moved to (q, a, b) turns by less than acos(cos_min).
  static bool keeps_turn(const Vec3d& p, const Vec3d& q, const Vec3d& a, const Vec3d& b, double cos_min) {
    const Vec3d n0 = tri_normal(p, a, b), n1 = tri_normal(q, a, b);
    return n0.dot(n1) > cos_min * n0.norm() * n1.norm();
  }

  /// How far v's editable ring edges are outside [lo, hi] with v at q.
  double violation(NodeIdx v, const Vec3d& q) const {
    double s = 0;
    m_.for_each_outgoing(v, [&](HalfedgeIdx h) {
      if (!editable(edge_of(h))) return;
      const double l = (m_.position(m_.head(h)) - q).norm();
      s += std::max(0.0, lo_ - l) + std::max(0.0, l - hi_);
    });
    return s;
  }

  /// Moves v to q projected onto the region if that lowers v's ring
  /// violation and turns no face over. True when v moved.
  bool try_move(NodeIdx v, Vec3d q) {
    const Vec3d p = m_.position(v);
    std::uint32_t tri = kNoTriangle;
    if (can_project_ && !project(v, q, tri)) return false;
    if (!no_flip(v, q, 0.5) || !(violation(v, q) < violation(v, p) - 1e-12 * o_.target)) return false;
    place(v, q, tri);
    ++rep_.relaxed;
    return true;
  }

  /// Moves a free end of e along e (in its tangent plane, or along the
  /// border) so that e's length becomes L, half way, or just inside the
  /// bound; kept only when the end's ring violation drops.
  bool targeted_move(EdgeIdx e) {
    const double l = length(e);
    if (!(l > 0)) return false;
    const double inside = l < lo_ ? lo_ + 0.02 * (o_.target - lo_) : hi_ - 0.02 * (hi_ - o_.target);
    for (unsigned s = 0; s < 2; ++s) {
      const NodeIdx v = m_.tail(halfedge_of(e, s)), w = m_.tail(halfedge_of(e, 1 - s));
      if (fixed(v) || m_.is_isolated(v)) continue;
      bool region_only = true, border = false;
      m_.for_each_outgoing(v, [&](HalfedgeIdx h) {
        const FaceIdx f = m_.face(h), g = m_.face(twin(h));
        if ((f.valid() && !is_region(f)) || (g.valid() && !is_region(g))) region_only = false;
        if (!f.valid() || !g.valid()) border = true;
      });
      if (!region_only || (border && corner(v))) continue;
      if (border && !(!m_.face(halfedge_of(e, 0)).valid() || !m_.face(halfedge_of(e, 1)).valid())) continue;
      const Vec3d p = m_.position(v), dir = (p - m_.position(w)) / l;
      for (double want : {o_.target, 0.5 * (o_.target + inside), inside})
        if (try_move(v, p + (want - l) * dir)) return true;
    }
    return false;
  }

  /// With a body (the settle rounds only): the place in v's tangent plane,
  /// among 36 (12 directions, 0.1, 0.2, 0.3 L), with the least ring
  /// violation, when it is lower than v's now. The edge from B's node on the
  /// dress that no other move fixed: moving along the edge or by springs
  /// stretched another ring edge past hi.
  bool search_move(NodeIdx v) {
    if (!body_ || !m_.alive(v) || fixed(v) || m_.is_isolated(v) || on_border(v)) return false;
    const Vec3d p = m_.position(v);
    Vec3d n = Vec3d::Zero();
    m_.for_each_outgoing(v, [&](HalfedgeIdx h) {
      if (m_.face(h).valid()) n += tri_normal(p, m_.position(m_.head(h)), m_.position(m_.head(m_.next(h))));
    });
    if (!(n.norm() > 0)) return false;
    n.normalize();
    const Vec3d t0 = n.unitOrthogonal(), t1 = n.cross(t0);
    const double before = violation(v, p);
    double best = before - 1e-12 * o_.target;
    Vec3d bq;
    std::uint32_t bt = kNoTriangle;
    bool found = false;
    for (int s = 1; s <= 3; ++s)
      for (int k = 0; k < 12; ++k) {
        const double a = k * (M_PI / 6);
        Vec3d q = p + 0.1 * s * o_.target * (std::cos(a) * t0 + std::sin(a) * t1);
        std::uint32_t tri = kNoTriangle;
        if (can_project_ && !project(v, q, tri)) continue;
        if (!no_flip(v, q, 0.5)) continue;
        if (const double w = violation(v, q); w < best) best = w, bq = q, bt = tri, found = true;
      }
    if (!found) return false;
    place(v, bq, bt);
    ++rep_.relaxed;
    return true;
  }

  /// Spring move of v, kept only when it lowers v's ring violation (so the
  /// repair cannot cycle through moves). True when v moved.
  bool spring_move(NodeIdx v) {
    Vec3d q;
    std::uint32_t qt;
    if (!m_.alive(v) || !relax_target(v, q, qt, true)) return false;
    const Vec3d p = m_.position(v);
    const double before = violation(v, p);
    for (double t : {1.0, 0.5, 0.25}) {
      Vec3d r = p + t * (q - p);
      std::uint32_t rt = qt;
      if (t < 1.0 && can_project_ && (!project(v, r, rt) || !no_flip(v, r, 0.5))) continue;
      if (violation(v, r) < before - 1e-12 * o_.target) {
        place(v, r, rt);
        ++rep_.relaxed;
        return true;
      }
    }
    return false;
  }

  /// Tangential relaxation (Jacobi) of the region's free nodes; with
  /// all = false only of the nodes whose ring changed since the last one
  /// (an edit next to them, or a neighbour moved): the others' targets are
  /// where they already are, so the result is nearly that of a full pass
  /// for the cost of the edited part.
  void relax_all(bool all = true) {
    std::vector<Move>& moves = moves_;
    moves.clear();
    rings_.clear();
    const double settle = 0.02 * o_.target;
    const std::uint32_t want = epoch_++;
    std::vector<NodeIdx> list;
    list.swap(dirty_list_);
    if (all) {
      list.clear();
      ++tick_;
      node_stamp_.resize(m_.nodes.slots.capacity(), 0);
      for (EdgeIdx e : region_edges())
        for (unsigned s = 0; s < 2; ++s) {
          const NodeIdx v = m_.tail(halfedge_of(e, s));
          if (node_stamp_[v.value] == tick_) continue;
          node_stamp_[v.value] = tick_;
          list.push_back(v);
        }
    }
    for (NodeIdx v : list) {
      // (a listed node may have died since it was marked)
      if (!all && (!m_.alive(v) || dirty_[v.value] != want)) continue;
      Vec3d q;
      std::uint32_t tri;
      if (relax_target(v, q, tri)) {
        moves.push_back(
            {v, q, tri, static_cast<std::uint32_t>(rings_.size()), static_cast<std::uint32_t>(ring_pairs_.size())});
        rings_.insert(rings_.end(), ring_pairs_.begin(), ring_pairs_.end());
      }
    }
    // Jacobi: targets from the old positions; re-checked against the
    // neighbours' new positions so that no face turns over.
    for (const Move& mv : moves) {
      const std::span<const RingPair> ring(rings_.data() + mv.ring_at, mv.ring_size);
      if (no_flip_ring(m_.position(mv.v), mv.q, ring, 0.2)) {
        // A move shorter than settle L changes the neighbours' targets by
        // less than that: they need not be visited again for it.
        const bool far = (mv.q - m_.position(mv.v)).squaredNorm() > settle * settle;
        place(mv.v, mv.q, mv.tri), ++rep_.relaxed;
        if (!far) continue;
        mark(mv.v);
        for (const RingPair& wu : ring) mark(wu[0]);
      }
    }
  }

  // ---------------------------------------------------------- step 1
  /// `passes` rounds, the first `wide` of them with collapses that may
  /// leave edges up to 2 lo (dense rows thin out; the next round's splits
  /// halve those edges into edges >= lo). The others collapse within hi:
  /// with wide collapses in every round but the last, split and collapse
  /// undid each other round after round (28k of each per round on the
  /// 100k cup).
  Status rounds(const ExecContext& ctx, int passes, int wide) {
    for (int pass = 0; pass < passes; ++pass) {
      collapse_limit_ = pass < wide && pass + 1 < passes ? std::max(hi_, 2 * lo_) : hi_;
      if (ctx.cancelled()) return region_error(ErrorCode::kCancelled, "cancelled");
      const std::size_t before = rep_.splits + rep_.collapses + rep_.swaps;
      for (EdgeIdx e : region_edges())
        if (m_.alive(e) && length(e) > hi_ && editable(e)) (void)split(e);
      for (EdgeIdx e : region_edges())
        if (m_.alive(e) && length(e) < lo_ && editable(e))
          if (auto k = collapse(e); !k) return k.status();
      // (a swap changes no other edge's editability: region_edges())
      for (EdgeIdx e : region_edges()) {
        if (!swap_ok(e, 0, hi_) || valence_gain(e) <= 0) continue;
        (void)swap(e);
      }
      if (o_.relax) relax_all(pass == 0);
      if (rep_.splits + rep_.collapses + rep_.swaps == before) break;
    }
    return {};
  }

  // ---------------------------------------------------------- step 2
  /// Each edge at most once in the queue (the budget counts operations, not
  /// duplicates of the same edge pushed by each of its neighbours).
  void enqueue(EdgeIdx e, std::deque<EdgeIdx>& q) {
    if (e.value >= queued_.size()) queued_.resize(m_.edges.slots.capacity(), 0);
    if (queued_[e.value]) return;
    queued_[e.value] = 1;
    q.push_back(e);
  }

  void push_ring(NodeIdx v, std::deque<EdgeIdx>& q) {
    if (!m_.alive(v)) return;
    m_.for_each_outgoing(v, [&](HalfedgeIdx h) {
      const EdgeIdx e = edge_of(h);
      if (!in_bounds(length(e)) && editable(e)) enqueue(e, q);
    });
  }

  Status repair(const ExecContext& ctx) {
    collapse_limit_ = hi_;
    std::deque<EdgeIdx> q;
    const std::vector<EdgeIdx> all = region_edges();  // a copy: the loop edits
    for (EdgeIdx e : all)
      if (!in_bounds(length(e))) enqueue(e, q);
    // Per region edge, as documented (not per edge out of bounds at the
    // start: a few bad edges in a large region may need many operations
    // around them before their neighbourhood settles).
    std::size_t budget = static_cast<std::size_t>(std::max(1, o_.repair_budget)) * (all.size() + 16);
    std::size_t ops = 0, changed = 0;
    // An edge no operation could fix waits in `stuck` until the queue has
    // run dry; it comes back when something changed since (the change may
    // have been next to it). After an operation, the out-of-bounds edges
    // within two rings of the nodes it made, moved or kept re-enter the
    // queue (length tested first: most are in bounds).
    std::vector<EdgeIdx> stuck;
    auto near = [&](NodeIdx v) {
      push_ring(v, q);
      m_.for_each_outgoing(v, [&](HalfedgeIdx h) { push_ring(m_.head(h), q); });
    };
    while (ops < budget) {
      if (q.empty()) {
        if (stuck.empty() || changed == 0) break;
        for (EdgeIdx e : stuck)
          if (m_.alive(e) && !in_bounds(length(e)) && editable(e)) enqueue(e, q);
        stuck.clear();
        changed = 0;
        continue;
      }
      if ((ops & 1023) == 0 && ctx.cancelled()) return region_error(ErrorCode::kCancelled, "cancelled");
      const EdgeIdx e = q.front();
      q.pop_front();
      queued_[e.value] = 0;
      if (!editable(e)) continue;
      const double l = length(e);
      if (in_bounds(l)) continue;
      ++ops;
      ++changed;  // undone below when nothing applies
      const NodeIdx a = m_.tail(halfedge_of(e, 0)), b = m_.tail(halfedge_of(e, 1));
      NodeIdx xy[2];
      if (swap_ok(e, lo_, hi_, xy) && swap(e)) {
        for (NodeIdx v : {a, b, xy[0], xy[1]}) push_ring(v, q);
        continue;
      }
      // Slightly out (splitting would leave halves below lo, a collapse
      // edges above hi): moves of the ends first.
      const bool gentle = l > hi_ ? l < 2 * lo_ : 2 * l > hi_;
      if (gentle && o_.relax &&
          (targeted_move(e) || spring_move(a) || spring_move(b) || search_move(a) || search_move(b))) {
        for (NodeIdx v : {a, b}) near(v);
        continue;
      }
      if (l > hi_) {
        if (const NodeIdx n = split(e); n.valid()) {
          Vec3d p;
          std::uint32_t tri;
          if (o_.relax && relax_target(n, p, tri)) place(n, p, tri), ++rep_.relaxed;
          near(n);
          continue;
        }
      } else {
        auto k = collapse(e);
        if (!k) return k.status();
        if (k->valid()) {
          near(*k);
          continue;
        }
      }
      // No operator applies: spring moves of the ends, then of their
      // neighbours, each kept only when it lowers its ring's violation.
      --changed;
      if (!o_.relax) {
        stuck.push_back(e);
        continue;
      }
      std::vector<NodeIdx>& moved = moved_;
      moved.clear();
      for (NodeIdx v : {a, b})
        if (spring_move(v)) moved.push_back(v);
      if (moved.empty()) {
        std::vector<NodeIdx>& ring = ring_;
        ring.clear();
        for (NodeIdx v : {a, b}) m_.for_each_outgoing(v, [&](HalfedgeIdx h) { ring.push_back(m_.head(h)); });
        for (NodeIdx v : ring)
          if (spring_move(v)) moved.push_back(v);
      }
      if (moved.empty() && l < lo_) {
        // Last resort: a collapse that may leave edges up to 2 lo, which
        // re-enter the queue and split into halves >= lo.
        collapse_limit_ = std::max(hi_, 2 * lo_);
        auto k = collapse(e);
        collapse_limit_ = hi_;
        if (!k) return k.status();
        if (k->valid()) {
          ++changed;
          near(*k);
          continue;
        }
      }
      if (moved.empty()) {
        stuck.push_back(e);
        continue;
      }
      ++changed;
      for (NodeIdx v : moved) near(v);
      if (m_.alive(e) && !in_bounds(length(e)) && editable(e)) enqueue(e, q);
    }
    return {};
  }

  double deviation() {
    if (!can_project_) return 0;
    double worst = 0;
    ++tick_;
    node_stamp_.resize(m_.nodes.slots.capacity(), 0);
    for (EdgeIdx e : region_edges())
      for (unsigned s = 0; s < 2; ++s) {
        const NodeIdx v = m_.tail(halfedge_of(e, s));
        if (node_stamp_[v.value] == tick_ || fixed(v)) continue;
        node_stamp_[v.value] = tick_;
        // The walk ends at a local minimum of the distance: an upper bound
        // of the distance to the region on entry.
        Vec3d c = m_.position(v);
        std::uint32_t tri;
        if (!project_region(v, c, tri)) return INFINITY;
        worst = std::max(worst, (c - m_.position(v)).norm());
      }
    return worst;
  }

  std::size_t count_region_faces() const {
    std::size_t n = 0;
    for (std::uint32_t f = 0; f < m_.faces.slots.capacity(); ++f) n += is_region(FaceIdx{f});
    return n;
  }

  RegionOptimiseReport rep_;

 private:
  // relax_all's scratch, kept across rounds: the moves and their rings.
  struct Move {
    NodeIdx v;
    Vec3d q;
    std::uint32_t tri, ring_at, ring_size;
  };
  std::vector<Move> moves_;
  std::vector<RingPair> ring_pairs_, rings_;
  Model& m_;
  const RegionOptimiseOptions& o_;
  double lo_ = 0, hi_ = 0, collapse_limit_ = 0;
  std::vector<char> outside_, fixed_, queued_, constrained_;
  std::vector<HalfedgeIdx> hs_;  // collapse_plain scratch
  bool plain_ = false;
  std::vector<EdgeIdx> edges_, fresh_, scratch_;  // see region_edges()
  std::vector<NodeIdx> moved_, ring_;             // repair scratch
  std::vector<std::uint32_t> dirty_;              // per node: epoch_ of its last change
  std::vector<NodeIdx> dirty_list_;               // the nodes marked in this epoch
  std::uint32_t epoch_ = 1;
  std::vector<std::uint32_t> stamp_, node_stamp_;
  std::uint32_t tick_ = 0;
  EditOptions eo_;
  std::vector<Vec3d> ref_pts_;
  std::vector<Triangle> ref_tris_;
  BodyBvh ref_;
  std::vector<std::array<std::uint32_t, 3>> ref_across_;   // triangle across edge k (corner k -> k + 1)
  std::vector<std::uint32_t> ref_ring_offset_, ref_ring_;  // triangles around each point
  std::vector<std::uint32_t> hint_;                        // per node: a triangle of ref_ at or near its closest point
  bool can_project_ = false, tree_built_ = false, walk_ = false;
  const CollisionBody* body_ = nullptr;
  double clear_ = 0;
  bool any_border_ = false;  // see on_border
};

Expected<RegionOptimiseReport> run(Model& m, std::span<const FaceIdx> region, std::span<const NodeIdx> fixed,
                                   std::span<const HalfedgeIdx> chain, const RegionOptimiseOptions& o,
                                   const ExecContext& ctx, const CollisionBody* body = nullptr, double c = 0) {
  if (!(o.target > 0) || !std::isfinite(o.target))
    return region_error(ErrorCode::kInvalidArgument, "the target length must be positive and finite");
  if (!(o.low > 0 && o.low < 1 && o.high > 1) || !std::isfinite(o.high))
    return region_error(ErrorCode::kInvalidArgument, "the bounds must satisfy 0 < low < 1 < high");
  if (o.passes < 0 || o.repair_budget < 0)
    return region_error(ErrorCode::kInvalidArgument, "negative passes or budget");
  Optimiser opt(m, o);
  opt.keep_outside(body, c);
  const bool edits = o.passes > 0 || o.repair_budget > 0;
  if (Status s = opt.init(region, fixed, edits); !s) return s;
  opt.rep_.before = opt.stats();
  // The fixed chain held by a temporary mesh edge: edge_collapse keeps ends on it.
  MeshEdgeIdx temp;
  bool free = !chain.empty();
  for (HalfedgeIdx h : chain)
    free = free && h.valid() && m.alive(edge_of(h)) && !m.edges.mesh_edge[edge_of(h).value].valid();
  if (free && edits) temp = m.new_mesh_edge(m.nodes.surface[m.tail(chain[0]).value], chain);
  opt.note_constraints();
  // Wide collapses in the first round only on a fold-free region (the
  // churn above); in every round but the last on a folded one, as before
  // (the garment sleeve ended with up to 85 edges out with one).
  Status s = opt.rounds(ctx, o.passes, opt.walks() ? 1 : o.passes - 1);
  // A greedy repair can stall where every single operation makes some
  // ring worse; a relaxation of the whole region moves it out of that
  // state, and the repair runs again (at most three times more).
  // `now` holds the statistics of the region as it is when `fresh` (each
  // is a pass over the region's edges: not taken twice for one state).
  EdgeLengthStats now;
  bool fresh = false;
  auto current = [&]() -> const EdgeLengthStats& {
    if (!fresh) now = opt.stats(), fresh = true;
    return now;
  };
  auto repair = [&] {
    for (int round = 0; s && o.repair_budget > 0 && round < 4; ++round) {
      if (round > 0) {
        if (current().outside == 0) break;
        if (o.relax) opt.relax_all();
      }
      s = opt.repair(ctx);
      fresh = false;
    }
  };
  repair();
  // Edges still out (a row too dense for collapses within hi, seen on the
  // garment tests): one more round with wide collapses, one without, and
  // the repair again. Costs nothing where the first repair succeeded.
  if (s && o.passes > 0 && current().outside > 0) {
    s = opt.rounds(ctx, 2, 1);
    fresh = false;
    repair();
  }
  if (temp.valid()) m.delete_mesh_edge(temp);  // (no length or region changes)
  if (!s) return s;
  opt.rep_.after = current();
  opt.rep_.max_deviation = opt.deviation();
  opt.rep_.region_faces = opt.count_region_faces();
  return opt.rep_;
}

Expected<RegionOptimiseReport> transact(Model& model, std::span<const FaceIdx> region, std::span<const NodeIdx> fixed,
                                        std::span<const HalfedgeIdx> fixed_chain, const RegionOptimiseOptions& options,
                                        const ExecContext& ctx, const CollisionBody* body, double c) {
  if (options.passes == 0 && options.repair_budget == 0)  // statistics only: nothing to undo
    return run(model, region, fixed, fixed_chain, options, ctx);
  // Transactional: the work is done on a copy, which takes the model's
  // place on success. The copy is made into columns reserved for the
  // region's growth (the first round's splits add up to a node per face and
  // three edges and two faces per face before its collapses free slots):
  // no column is reallocated and copied again while it grows.
  const std::size_t grow = region.size();
  Model work;
  work.reserve(model.nodes.slots.capacity() + 2 * grow, model.edges.slots.capacity() + 4 * grow,
               model.faces.slots.capacity() + 3 * grow);
  work = model;
  auto r = run(work, region, fixed, fixed_chain, options, ctx, body, c);
  if (r) model = std::move(work);
  return r;
}

}  // namespace

Expected<RegionOptimiseReport> optimise_region(Model& model, std::span<const FaceIdx> region,
                                               std::span<const NodeIdx> fixed, std::span<const HalfedgeIdx> fixed_chain,
                                               const RegionOptimiseOptions& options, const ExecContext& ctx) {
  return transact(model, region, fixed, fixed_chain, options, ctx, nullptr, 0);
}

Expected<RegionOptimiseReport> extrude_detail::optimise_outside(Model& model, std::span<const FaceIdx> region,
                                                                std::span<const NodeIdx> fixed,
                                                                std::span<const HalfedgeIdx> fixed_chain,
                                                                const RegionOptimiseOptions& options,
                                                                const CollisionBody& body, double c,
                                                                const ExecContext& ctx) {
  return transact(model, region, fixed, fixed_chain, options, ctx, &body, c);
}

}  // namespace atelier
