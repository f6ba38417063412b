// Why this file is long: the remeshing rounds and the local repair share the
// same operator wrappers (split, collapse, swap, relax with their validity
// tests), kept together in one anonymous-namespace class.
//
// Step 5 of the extrusion (seed 002 Fig. 9) as its own entry point; see
// optimise_region.h. Everything works on lists gathered from the region's
// faces (never a scan of the whole model per pass) and the repair works on
// a FIFO queue of edges, so the cost follows the region and the edits.
#include <atelier/systems/mesh/edit.h>
#include <atelier/systems/sketch/optimise_region.h>
#include <atelier/systems/spatial/body_bvh.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <string>
#include <vector>

namespace atelier {

namespace {

Status region_error(ErrorCode c, const std::string& what) {
  return Status(c, "optimise_region: " + what);
}

Vec3d tri_normal(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  return (b - a).cross(c - a);
}

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
        return region_error(ErrorCode::kInvalidArgument, "region face " + std::to_string(f.value) + " is not a triangle");
      in[f.value] = 1;
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
    eo_.check_ring_nodes = false;
    for (std::uint32_t v = 0; v < m_.nodes.slots.capacity(); ++v)
      if (m_.alive(NodeIdx{v}) && m_.nodes.in_face[v].valid()) eo_.check_ring_nodes = true;
    // The region on entry: the projection target of the relaxation.
    // (BodyBvh keeps a view of the points: they are members.)
    std::vector<Vec3d>& pts = ref_pts_;
    std::vector<Triangle>& tris = ref_tris_;
    std::vector<NodeIdx> f;
    for (FaceIdx fi : edits ? region : std::span<const FaceIdx>{}) {
      m_.face_nodes(fi, f);
      const auto b = static_cast<std::uint32_t>(pts.size());
      tris.push_back({b, b + 1, b + 2});
      for (NodeIdx v : f) pts.push_back(m_.position(v));
    }
    can_project_ = edits && !tris.empty() && ref_.build(pts, tris, {}, ExecContext::sequential()).is_ok();
    return {};
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
  bool on_border(NodeIdx v) const {
    bool b = false;
    m_.for_each_outgoing(v, [&](HalfedgeIdx h) { b |= !m_.face(h).valid() || !m_.face(twin(h)).valid(); });
    return b;
  }

  /// The editable edges, in the order of the region's face slots.
  std::vector<EdgeIdx> region_edges() {
    stamp_.resize(m_.edges.slots.capacity(), 0);
    ++tick_;
    std::vector<EdgeIdx> out;
    for (std::uint32_t f = 0; f < m_.faces.slots.capacity(); ++f) {
      if (!is_region(FaceIdx{f})) continue;
      m_.for_each_face_halfedge(FaceIdx{f}, [&](HalfedgeIdx h) {
        const EdgeIdx e = edge_of(h);
        if (stamp_[e.value] == tick_ || !editable(e)) return;
        stamp_[e.value] = tick_;
        out.push_back(e);
      });
    }
    return out;
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
    const Vec3d mid = 0.5 * (m_.position(m_.tail(halfedge_of(e, 0))) + m_.position(m_.tail(halfedge_of(e, 1))));
    auto s = edge_split(m_, m_.handle(e), mid, eo_);
    if (!s) return {};
    ++rep_.splits;
    return s->nodes.at(0).idx;
  }

  /// Moving r to p keeps every face around r (but those holding k) turned
  /// the same way and makes no edge longer than hi.
  bool collapse_ok(NodeIdx r, NodeIdx k, const Vec3d& p) const {
    // r staying where it is (a fixed end of B, or a border end kept) changes
    // none of its edges or faces: its edges outside the region may be far
    // longer than hi and must not veto the collapse.
    if (p == m_.position(r)) return true;
    bool ok = true;
    m_.for_each_outgoing(r, [&](HalfedgeIdx h) {
      if (!ok) return;
      const NodeIdx w = m_.head(h);
      if (w != k && (m_.position(w) - p).norm() > collapse_limit_) ok = false;
      const FaceIdx face = m_.face(h);
      if (!face.valid()) return;
      // Triangle (r, w, u) with u = head(next(h)).
      const NodeIdx u = m_.head(m_.next(h));
      if (w == k || u == k) return;
      const Vec3d n0 = tri_normal(m_.position(r), m_.position(w), m_.position(u));
      const Vec3d n1 = tri_normal(p, m_.position(w), m_.position(u));
      if (!(n0.dot(n1) > 0.2 * n0.norm() * n1.norm())) ok = false;
    });
    return ok;
  }

  /// Collapses e (B's end, or a border end, kept in place); returns the kept
  /// node (invalid when refused). Err only on an internal failure.
  Expected<NodeIdx> collapse(EdgeIdx e) {
    const NodeIdx a = m_.tail(halfedge_of(e, 0)), b = m_.tail(halfedge_of(e, 1));
    if (fixed(a) && fixed(b)) return NodeIdx{};
    NodeIdx keep = a, gone = b;
    if (fixed(b)) keep = b, gone = a;
    Vec3d p = 0.5 * (m_.position(a) + m_.position(b));
    if (fixed(keep)) {
      p = m_.position(keep);
      // edge_collapse keeps the tail of halfedge 2e unless e is on no mesh
      // edge and only the other end is (the temporary one along the chain).
      NodeIdx kept = a;
      if (!m_.edges.mesh_edge[e.value].valid() && on_mesh_edge(a) != on_mesh_edge(b)) kept = on_mesh_edge(a) ? a : b;
      if (kept != keep) return NodeIdx{};
    } else {
      const bool ba = on_border(a), bb = on_border(b);
      const bool border_edge = !m_.face(halfedge_of(e, 0)).valid() || !m_.face(halfedge_of(e, 1)).valid();
      if (ba && !bb) p = m_.position(a);
      if (bb && !ba) p = m_.position(b);
      if (ba && bb && !border_edge) return NodeIdx{};
      if (ba && bb) {  // along the border: a corner keeps its place
        const bool ca = corner(a), cb = corner(b);
        if (ca && cb) return NodeIdx{};
        if (ca) p = m_.position(a);
        if (cb) p = m_.position(b);
      }
    }
    if (!collapse_ok(gone, keep, p) || !collapse_ok(keep, gone, p)) {
      // Last resort, two free inner ends: the midpoint may fold a face or
      // stretch an edge where one of the ends would not (a crease of the
      // swept surface, a pushed fold): try each end's place.
      if (collapse_limit_ <= hi_ || fixed(keep) || on_border(a) || on_border(b)) return NodeIdx{};
      bool found = false;
      for (const NodeIdx at : {a, b}) {
        p = m_.position(at);
        if (collapse_ok(gone, keep, p) && collapse_ok(keep, gone, p)) {
          found = true;
          break;
        }
      }
      if (!found) return NodeIdx{};
    }
    const Vec3d keep_pos = m_.position(keep);
    auto res = edge_collapse(m_, m_.handle(e), p, eo_);
    if (!res) return NodeIdx{};
    const NodeIdx kept = res->kept.at(0).idx;
    if (fixed(keep) && (kept != keep || m_.position(kept) != keep_pos))
      return region_error(ErrorCode::kInternal, "a collapse moved fixed node " + std::to_string(keep.value));
    ++rep_.collapses;
    return kept;
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
    if (m_.next(m_.next(m_.next(h))) != h || m_.next(m_.next(m_.next(t))) != t) return false;
    const NodeIdx a = m_.tail(h), b = m_.tail(t), x = m_.head(m_.next(h)), y = m_.head(m_.next(t));
    const double d = (m_.position(x) - m_.position(y)).norm();
    if (d > max_len || d < min_len) return false;
    const Vec3d n0 = tri_normal(m_.position(a), m_.position(b), m_.position(x)) +
                     tri_normal(m_.position(b), m_.position(a), m_.position(y));
    const Vec3d n1 = tri_normal(m_.position(x), m_.position(y), m_.position(b));
    const Vec3d n2 = tri_normal(m_.position(y), m_.position(x), m_.position(a));
    if (!(n1.dot(n0) > 0 && n2.dot(n0) > 0 && n1.dot(n2) > 0.5 * n1.norm() * n2.norm())) return false;
    if (xy) xy[0] = x, xy[1] = y;
    return true;
  }

  bool swap(EdgeIdx e) {
    if (auto s = edge_swap(m_, m_.handle(e), eo_)) {
      ++rep_.swaps;
      return true;
    }
    return false;
  }

  int valence_gain(EdgeIdx e) const {
    const HalfedgeIdx h = halfedge_of(e, 0), t = halfedge_of(e, 1);
    const NodeIdx a = m_.tail(h), b = m_.tail(t), x = m_.head(m_.next(h)), y = m_.head(m_.next(t));
    auto dev = [&](NodeIdx v, int delta) {
      if (fixed(v)) return 0;
      const int want = on_border(v) ? 4 : 6;
      return std::abs(static_cast<int>(m_.degree(v)) + delta - want);
    };
    return dev(a, 0) + dev(b, 0) + dev(x, 0) + dev(y, 0) - (dev(a, -1) + dev(b, -1) + dev(x, 1) + dev(y, 1));
  }

  /// A border node where the border turns by more than 30 degrees (or with
  /// other than two border edges): its position is kept.
  bool corner(NodeIdx v) const {
    Vec3d nb[2];
    int kb = 0;
    m_.for_each_outgoing(v, [&](HalfedgeIdx h) {
      if (m_.face(h).valid() && m_.face(twin(h)).valid()) return;
      if (kb < 2) nb[kb] = m_.position(m_.head(h));
      ++kb;
    });
    if (kb == 0) return false;
    if (kb != 2) return true;
    const Vec3d p = m_.position(v), d0 = p - nb[0], d1 = nb[1] - p;
    return !(d0.dot(d1) > std::cos(M_PI / 6) * d0.norm() * d1.norm());
  }

  /// Relaxation target of v (not applied). Inner nodes: the centroid of
  /// the neighbours (spring = false) or the mean of the points at distance L
  /// from each neighbour towards v (spring = true: pulls every ring edge
  /// towards L), in the tangent plane; border nodes: the same along the
  /// border (their two border neighbours; corners stay). Then projected
  /// onto the region on entry. False when v stays.
  bool relax_target(NodeIdx v, Vec3d& out, bool spring = false) {
    if (fixed(v) || m_.is_isolated(v)) return false;
    const Vec3d p = m_.position(v);
    Vec3d c = Vec3d::Zero(), n = Vec3d::Zero(), cb = Vec3d::Zero();
    int k = 0, kb = 0;
    bool ok = true;
    m_.for_each_outgoing(v, [&](HalfedgeIdx h) {
      const FaceIdx f = m_.face(h), g = m_.face(twin(h));
      if ((f.valid() && !is_region(f)) || (g.valid() && !is_region(g))) ok = false;
      const Vec3d w = m_.position(m_.head(h));
      Vec3d t = w;
      if (spring) {
        const Vec3d d = p - w;
        const double l = d.norm();
        t = l > 0 ? Vec3d(w + (o_.target / l) * d) : w;
      }
      c += t;
      ++k;
      if (!f.valid() || !g.valid()) cb += t, ++kb;
      if (f.valid()) n += tri_normal(p, w, m_.position(m_.head(m_.next(h))));
    });
    if (!ok || k == 0 || (kb != 0 && kb != 2) || !(n.norm() > 0)) return false;
    if (kb == 2 && corner(v)) return false;
    n.normalize();
    Vec3d q;
    if (kb == 2) {
      q = cb / 2;
    } else {
      const Vec3d d = c / k - p;
      q = p + d - d.dot(n) * n;
    }
    if (can_project_) {
      const ClosestHit hit = ref_.closest_point(q, (q - p).norm() + o_.target);
      if (hit.triangle == kNoTriangle || !hit.point.allFinite()) return false;
      q = hit.point;
    }
    if (!no_flip(v, q, 0.5)) return false;
    out = q;
    return true;
  }

  /// Moving v to q turns no face around it by more than acos(cos_min).
  bool no_flip(NodeIdx v, const Vec3d& q, double cos_min) const {
    bool ok = true;
    const Vec3d p = m_.position(v);
    m_.for_each_outgoing(v, [&](HalfedgeIdx h) {
      if (!ok || !m_.face(h).valid()) return;
      const Vec3d& a = m_.position(m_.head(h));
      const Vec3d& b = m_.position(m_.head(m_.next(h)));
      const Vec3d n0 = tri_normal(p, a, b), n1 = tri_normal(q, a, b);
      ok = n0.dot(n1) > cos_min * n0.norm() * n1.norm();
    });
    return ok;
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
    if (can_project_) {
      const ClosestHit hit = ref_.closest_point(q, (q - p).norm() + o_.target);
      if (hit.triangle == kNoTriangle || !hit.point.allFinite()) return false;
      q = hit.point;
    }
    if (!no_flip(v, q, 0.5) || !(violation(v, q) < violation(v, p) - 1e-12 * o_.target)) return false;
    m_.nodes.position[v.value] = q;
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

  /// Spring move of v, kept only when it lowers v's ring violation (so the
  /// repair cannot cycle through moves). True when v moved.
  bool spring_move(NodeIdx v) {
    Vec3d q;
    if (!m_.alive(v) || !relax_target(v, q, true)) return false;
    const Vec3d p = m_.position(v);
    const double before = violation(v, p);
    for (double t : {1.0, 0.5, 0.25}) {
      const Vec3d r = p + t * (q - p);
      if (t < 1.0 && can_project_) {
        const ClosestHit hit = ref_.closest_point(r, (r - p).norm() + o_.target);
        if (hit.triangle == kNoTriangle || !hit.point.allFinite() || !no_flip(v, hit.point, 0.5)) continue;
        if (violation(v, hit.point) < before - 1e-12 * o_.target) {
          m_.nodes.position[v.value] = hit.point;
          ++rep_.relaxed;
          return true;
        }
        continue;
      }
      if (violation(v, r) < before - 1e-12 * o_.target) {
        m_.nodes.position[v.value] = r;
        ++rep_.relaxed;
        return true;
      }
    }
    return false;
  }

  void relax_all() {
    std::vector<std::pair<NodeIdx, Vec3d>> moves;
    ++tick_;
    node_stamp_.resize(m_.nodes.slots.capacity(), 0);
    for (EdgeIdx e : region_edges())
      for (unsigned s = 0; s < 2; ++s) {
        const NodeIdx v = m_.tail(halfedge_of(e, s));
        if (node_stamp_[v.value] == tick_) continue;
        node_stamp_[v.value] = tick_;
        Vec3d q;
        if (relax_target(v, q)) moves.emplace_back(v, q);
      }
    // Jacobi: targets from the old positions; re-checked against the
    // neighbours' new positions so that no face turns over.
    for (const auto& [v, q] : moves)
      if (no_flip(v, q, 0.2)) m_.nodes.position[v.value] = q, ++rep_.relaxed;
  }

  // ---------------------------------------------------------- step 1
  Status rounds(const ExecContext& ctx) {
    for (int pass = 0; pass < o_.passes; ++pass) {
      // The last round collapses only within hi (nothing splits after it).
      collapse_limit_ = pass + 1 < o_.passes ? std::max(hi_, 2 * lo_) : hi_;
      if (ctx.cancelled()) return region_error(ErrorCode::kCancelled, "cancelled");
      const std::size_t before = rep_.splits + rep_.collapses + rep_.swaps;
      for (EdgeIdx e : region_edges())
        if (editable(e) && length(e) > hi_) (void)split(e);
      for (EdgeIdx e : region_edges())
        if (editable(e) && length(e) < lo_)
          if (auto k = collapse(e); !k) return k.status();
      for (EdgeIdx e : region_edges()) {
        if (!editable(e) || !swap_ok(e, 0, hi_) || valence_gain(e) <= 0) continue;
        (void)swap(e);
      }
      if (o_.relax) relax_all();
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
      if (editable(e) && !in_bounds(length(e))) enqueue(e, q);
    });
  }

  Status repair(const ExecContext& ctx) {
    collapse_limit_ = hi_;
    std::deque<EdgeIdx> q;
    const std::vector<EdgeIdx> all = region_edges();
    for (EdgeIdx e : all)
      if (!in_bounds(length(e))) enqueue(e, q);
    // Per region edge, as documented (not per edge out of bounds at the
    // start: a few bad edges in a large region may need many operations
    // around them before their neighbourhood settles).
    std::size_t budget = static_cast<std::size_t>(std::max(1, o_.repair_budget)) * (all.size() + 16);
    std::size_t ops = 0;
    while (!q.empty() && ops < budget) {
      if ((ops & 1023) == 0 && ctx.cancelled()) return region_error(ErrorCode::kCancelled, "cancelled");
      const EdgeIdx e = q.front();
      q.pop_front();
      queued_[e.value] = 0;
      if (!editable(e)) continue;
      const double l = length(e);
      if (in_bounds(l)) continue;
      ++ops;
      const NodeIdx a = m_.tail(halfedge_of(e, 0)), b = m_.tail(halfedge_of(e, 1));
      NodeIdx xy[2];
      if (swap_ok(e, lo_, hi_, xy) && swap(e)) {
        for (NodeIdx v : {a, b, xy[0], xy[1]}) push_ring(v, q);
        continue;
      }
      // Slightly out (splitting would leave halves below lo, a collapse
      // edges above hi): spring moves of the ends first.
      const bool gentle = l > hi_ ? l < 2 * lo_ : 2 * l > hi_;
      if (gentle && o_.relax && (targeted_move(e) || spring_move(a) || spring_move(b))) {
        for (NodeIdx v : {a, b}) {
          push_ring(v, q);
          m_.for_each_outgoing(v, [&](HalfedgeIdx h) { push_ring(m_.head(h), q); });
        }
        continue;
      }
      if (l > hi_) {
        if (const NodeIdx n = split(e); n.valid()) {
          Vec3d p;
          if (o_.relax && relax_target(n, p)) m_.nodes.position[n.value] = p, ++rep_.relaxed;
          push_ring(n, q);
          m_.for_each_outgoing(n, [&](HalfedgeIdx h) { push_ring(m_.head(h), q); });
          continue;
        }
      } else {
        auto k = collapse(e);
        if (!k) return k.status();
        if (k->valid()) {
          push_ring(*k, q);
          m_.for_each_outgoing(*k, [&](HalfedgeIdx h) { push_ring(m_.head(h), q); });
          continue;
        }
      }
      // No operator applies: spring moves of the ends, then of their
      // neighbours, each kept only when it lowers its ring's violation.
      if (!o_.relax) continue;
      bool moved = false;
      for (NodeIdx v : {a, b}) moved |= spring_move(v);
      if (!moved) {
        std::vector<NodeIdx> ring;
        for (NodeIdx v : {a, b}) m_.for_each_outgoing(v, [&](HalfedgeIdx h) { ring.push_back(m_.head(h)); });
        for (NodeIdx v : ring) moved |= spring_move(v);
      }
      if (!moved && l < lo_) {
        // Last resort: a collapse that may leave edges up to 2 lo, which
        // re-enter the queue and split into halves >= lo.
        collapse_limit_ = std::max(hi_, 2 * lo_);
        auto k = collapse(e);
        collapse_limit_ = hi_;
        if (!k) return k.status();
        if (k->valid()) {
          push_ring(*k, q);
          m_.for_each_outgoing(*k, [&](HalfedgeIdx h) { push_ring(m_.head(h), q); });
        }
      }
      if (moved) {
        for (NodeIdx v : {a, b}) {
          push_ring(v, q);
          m_.for_each_outgoing(v, [&](HalfedgeIdx h) { push_ring(m_.head(h), q); });
        }
      }
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
        worst = std::max(worst, ref_.closest_point(m_.position(v), o_.target).distance);
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
  Model& m_;
  const RegionOptimiseOptions& o_;
  double lo_ = 0, hi_ = 0, collapse_limit_ = 0;
  std::vector<char> outside_, fixed_, queued_;
  std::vector<std::uint32_t> stamp_, node_stamp_;
  std::uint32_t tick_ = 0;
  EditOptions eo_;
  std::vector<Vec3d> ref_pts_;
  std::vector<Triangle> ref_tris_;
  BodyBvh ref_;
  bool can_project_ = false;
};

Expected<RegionOptimiseReport> run(Model& m, std::span<const FaceIdx> region, std::span<const NodeIdx> fixed,
                                   std::span<const HalfedgeIdx> chain, const RegionOptimiseOptions& o,
                                   const ExecContext& ctx) {
  if (!(o.target > 0) || !std::isfinite(o.target))
    return region_error(ErrorCode::kInvalidArgument, "the target length must be positive and finite");
  if (!(o.low > 0 && o.low < 1 && o.high > 1) || !std::isfinite(o.high))
    return region_error(ErrorCode::kInvalidArgument, "the bounds must satisfy 0 < low < 1 < high");
  if (o.passes < 0 || o.repair_budget < 0) return region_error(ErrorCode::kInvalidArgument, "negative passes or budget");
  Optimiser opt(m, o);
  const bool edits = o.passes > 0 || o.repair_budget > 0;
  if (Status s = opt.init(region, fixed, edits); !s) return s;
  opt.rep_.before = opt.stats();
  // The fixed chain held by a temporary mesh edge: edge_collapse keeps ends on it.
  MeshEdgeIdx temp;
  bool free = !chain.empty();
  for (HalfedgeIdx h : chain)
    free = free && h.valid() && m.alive(edge_of(h)) && !m.edges.mesh_edge[edge_of(h).value].valid();
  if (free && edits) temp = m.new_mesh_edge(m.nodes.surface[m.tail(chain[0]).value], chain);
  Status s = opt.rounds(ctx);
  // A greedy repair can stall where every single operation makes some
  // ring worse; a relaxation of the whole region moves it out of that
  // state, and the repair runs again (at most three times more).
  for (int round = 0; s && o.repair_budget > 0 && round < 4; ++round) {
    if (round > 0) {
      if (opt.stats().outside == 0) break;
      if (o.relax) opt.relax_all();
    }
    s = opt.repair(ctx);
  }
  if (temp.valid()) m.delete_mesh_edge(temp);
  if (!s) return s;
  opt.rep_.after = opt.stats();
  opt.rep_.max_deviation = opt.deviation();
  opt.rep_.region_faces = opt.count_region_faces();
  return opt.rep_;
}

}  // namespace

Expected<RegionOptimiseReport> optimise_region(Model& model, std::span<const FaceIdx> region,
                                               std::span<const NodeIdx> fixed, std::span<const HalfedgeIdx> fixed_chain,
                                               const RegionOptimiseOptions& options, const ExecContext& ctx) {
  if (options.passes == 0 && options.repair_budget == 0)  // statistics only: nothing to undo
    return run(model, region, fixed, fixed_chain, options, ctx);
  Model backup = model;  // transactional
  auto r = run(model, region, fixed, fixed_chain, options, ctx);
  if (!r) model = std::move(backup);
  return r;
}

}  // namespace atelier
