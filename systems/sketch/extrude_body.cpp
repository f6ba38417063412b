// The extrusion kept outside a body (issue 21, beyond seed 002, whose
// section 6 lists collision as future work): the body push itself
// (push_out) and the passes around it that keep the extruded part within
// the edge bounds of step 5.
//
//  - Before the optimisation, the push moves the swept nodes that lie in the
//    body onto it (closest point + clearance): neighbouring nodes pushed to
//    different sides of a limb, or pushed next to nodes that were not, fold
//    the swept surface (neighbouring triangles turned by more than 60
//    degrees), and the optimisation, which keeps to that surface, cannot
//    make edges within bounds across a fold. smooth_pushed relaxes the
//    pushed nodes and their neighbours (umbrella steps, each followed by the
//    push) so that the surface the optimisation keeps to is a smooth one
//    outside the body.
//  - Even with every node outside, a triangle between pushed nodes can run
//    through the body (its nodes moved apart by the push, or to either side
//    of a crease): the optimisation, which projects onto that surface, then
//    puts nodes inside, and the last push moved them up to 2 L and
//    stretched their edges out of bounds (the sleeve's 1.35-1.9 L edges).
//    refine_outside splits every new edge whose midpoint is in the body at
//    that midpoint pushed out, a few rounds, so that the surface the
//    optimisation keeps to runs outside the body. On by default with a body.
//  - After the optimisation, the last push moves nodes again without
//    remeshing. settle re-optimises only the faces around the edges that
//    are then outside the bounds (B fixed, after refine_outside) and pushes
//    again, a few times. That optimisation keeps its places outside the
//    body (optimise_outside, optimise_region.cpp): where a limb runs
//    through the sleeve's first copies, triangles between pushed nodes
//    cross the limb (nodes on its opposite sides), the plain optimisation
//    relaxed nodes onto them and split their edges at midpoints inside
//    the limb, and the push took those nodes out again by up to 2 L: the
//    same 20-30 edges left the bounds after every round.
#include <atelier/systems/mesh/edit.h>
#include <atelier/systems/mesh/fan_triangulation.h>
#include <atelier/systems/sketch/extrude.h>
#include <atelier/systems/sketch/optimise_region.h>

#include <algorithm>
#include <vector>

#include "extrude_detail.h"

namespace atelier::extrude_detail {

namespace {

/// The settle rounds' repair budget (operations per region edge; the
/// optimisation's default is 8): where a limb runs across the region the
/// repair's splits and collapses churn until the budget is spent (4000 on a
/// 300-face region, 10 s, the count no better than with 2); the next round
/// goes on from a region around the edges still out.
constexpr int kSettleRepairBudget = 2;

bool is_new(const std::vector<char>& old, NodeIdx v) {
  return !(v.value < old.size() && old[v.value]);
}

/// `mark` grown by `rings` rings of new nodes (over edges).
void grow(const Model& m, const std::vector<char>& old, std::vector<char>& mark, int rings) {
  std::vector<NodeIdx> front;
  for (std::uint32_t v = 0; v < mark.size(); ++v)
    if (mark[v]) front.push_back(NodeIdx{v});
  for (int r = 0; r < rings; ++r) {
    std::vector<NodeIdx> next;
    for (NodeIdx v : front)
      m.for_each_outgoing(v, [&](HalfedgeIdx h) {
        const NodeIdx w = m.head(h);
        if (is_new(old, w) && !mark[w.value]) mark[w.value] = 1, next.push_back(w);
      });
    front = std::move(next);
  }
}

/// From p inside the body along the unit direction dir until c outside it:
/// sphere tracing (a step of the distance to the body never crosses its
/// surface), at most `reach` far. False when it does not get out.
bool march_out(const CollisionBody& body, const Vec3d& p, const Vec3d& dir, double c, double reach, Vec3d& out) {
  double t = 0;
  for (int k = 0; k < 64 && t <= reach; ++k) {
    const BodyDistance d = body.query(p + t * dir);
    if (d.triangle == kNoTriangle) return false;
    if (d.distance >= c) {
      out = p + t * dir;
      return out.allFinite();
    }
    t += d.distance < 0 ? std::max(-d.distance, 0.25 * c) : c - d.distance + 1e-3 * c;
  }
  return false;
}

}  // namespace

/// The push of the collision pass (systems/garment/collision_pass.h step 3)
/// on the new nodes: closer than c (or inside) -> closest body point + c n.
/// With the copies' axes (the first push of a ring B's sweep), a node inside
/// the body whose closest point lies towards its copy's axis (a limb or the
/// shoulder through the sleeve's wall: the closest point would take the
/// wall inwards, to the far side of the limb from its neighbours) goes out
/// away from the axis instead, through the body to c beyond it, when that
/// is within the copy's radius.
void push_out(Model& m, const std::vector<char>& old, const CollisionBody& body, double c, int rounds,
              std::vector<char>& pushed, const CopyAxes* axes) {
  const std::vector<NodeIdx> nodes = new_nodes(m, old);
  for (int r = 0; r < rounds; ++r) {
    bool any = false;
    for (NodeIdx v : nodes) {
      const Vec3d p = m.position(v);
      const BodyDistance d = body.query(p);
      if (!within_clearance(d, c)) continue;
      Vec3d q = pushed_place(d, c);
      if (axes && d.distance < 0 && v.value < axes->normal.size() && axes->normal[v.value] != Vec3d::Zero()) {
        const Vec3d n = axes->normal[v.value];
        Vec3d radial = p - axes->centre[v.value];
        radial -= radial.dot(n) * n;
        const double rn = radial.norm();
        Vec3d out;
        if (rn > 0 && (q - p).dot(radial) < 0 && march_out(body, p, radial / rn, c, rn, out)) q = out;
      }
      if (!q.allFinite()) continue;
      m.nodes.position[v.value] = q;
      if (v.value >= pushed.size()) pushed.resize(v.value + 1, 0);
      pushed[v.value] = 1;
      any = true;
    }
    if (!any) break;
  }
}

EdgeLengthStats new_edge_stats(const Model& m, const std::vector<char>& old, double L, double low, double high) {
  EdgeLengthStats st;
  st.min = INFINITY;
  double sum = 0;
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) {
    if (!m.alive(EdgeIdx{e})) continue;
    const NodeIdx a = m.tail(halfedge_of(EdgeIdx{e}, 0)), b = m.tail(halfedge_of(EdgeIdx{e}, 1));
    if (!is_new(old, a) && !is_new(old, b)) continue;
    const double l = (m.position(a) - m.position(b)).norm();
    ++st.edges;
    sum += l;
    st.min = std::min(st.min, l);
    st.max = std::max(st.max, l);
    st.outside += l < low * L || l > high * L;
  }
  if (st.edges == 0) st.min = 0;
  st.mean = st.edges ? sum / static_cast<double>(st.edges) : 0;
  st.within = st.edges ? 1.0 - static_cast<double>(st.outside) / static_cast<double>(st.edges) : 1;
  return st;
}

void smooth_pushed(Model& m, const std::vector<char>& old, const std::vector<char>& pushed, const CollisionBody& body,
                   double c, int push_rounds, int rounds) {
  if (rounds <= 0) return;
  std::vector<char> mark(m.nodes.slots.capacity(), 0);
  bool any = false;
  for (std::uint32_t v = 0; v < pushed.size() && v < mark.size(); ++v)
    if (pushed[v] && m.alive(NodeIdx{v})) mark[v] = 1, any = true;
  if (!any) return;
  // The pushed nodes and two rings around them: the fold runs where pushed
  // nodes meet unpushed ones.
  grow(m, old, mark, 2);
  std::vector<NodeIdx> nodes;
  for (std::uint32_t v = 0; v < mark.size(); ++v)
    if (mark[v]) nodes.push_back(NodeIdx{v});
  std::vector<Vec3d> next(nodes.size());
  std::vector<char> again;
  for (int r = 0; r < rounds; ++r) {
    // Jacobi umbrella step (half way to the neighbours' mean): the order of
    // the nodes does not matter, so neither do threads.
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      Vec3d sum = Vec3d::Zero();
      int k = 0;
      m.for_each_outgoing(nodes[i], [&](HalfedgeIdx h) { sum += m.position(m.head(h)), ++k; });
      const Vec3d p = m.position(nodes[i]);
      next[i] = k ? 0.5 * p + 0.5 * sum / k : p;
    }
    for (std::size_t i = 0; i < nodes.size(); ++i) m.nodes.position[nodes[i].value] = next[i];
    push_out(m, old, body, c, push_rounds, again);
  }
}

Expected<std::size_t> refine_outside(Model& m, const std::vector<char>& old, const CollisionBody& body, double c,
                                     double min_length, int rounds, std::vector<char>& pushed) {
  EditOptions eo;
  eo.check_ring_nodes = false;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity() && !eo.check_ring_nodes; ++v)
    eo.check_ring_nodes = m.alive(NodeIdx{v}) && m.nodes.in_face[v].valid();
  std::size_t splits = 0;
  // Each dipping edge with the body's answer at its midpoint: a split
  // leaves the other listed edges alive with the same ends, so each is
  // split once, at the point found when it was listed.
  std::vector<std::pair<EdgeIdx, BodyDistance>> dipping;
  for (int r = 0; r < rounds; ++r) {
    dipping.clear();
    for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) {
      if (!m.alive(EdgeIdx{e})) continue;
      const NodeIdx a = m.tail(halfedge_of(EdgeIdx{e}, 0)), b = m.tail(halfedge_of(EdgeIdx{e}, 1));
      if (!is_new(old, a) && !is_new(old, b)) continue;
      const Vec3d pa = m.position(a), pb = m.position(b);
      if (!((pa - pb).norm() >= min_length)) continue;
      const BodyDistance d = body.query(0.5 * (pa + pb));
      if (d.distance < 0) dipping.emplace_back(EdgeIdx{e}, d);
    }
    if (dipping.empty()) break;
    for (const auto& [e, d] : dipping) {
      const Vec3d q = pushed_place(d, c);
      if (d.triangle == kNoTriangle || !q.allFinite()) continue;
      auto sp = edge_split(m, m.handle(e), q, eo);
      if (!sp) return sp.status();
      const NodeIdx v = sp->nodes.at(0).idx;
      if (v.value >= pushed.size()) pushed.resize(v.value + 1, 0);
      pushed[v.value] = 1;
      ++splits;
    }
  }
  return splits;
}

Expected<std::size_t> settle(Model& m, const std::vector<char>& old, const std::vector<char>& old_face,
                             std::span<const NodeIdx> B, std::span<const HalfedgeIdx> chain,
                             const RegionOptimiseOptions& oo, const CollisionBody& body, double c, int push_rounds,
                             int rounds, double refine_shortest, int refine_rounds, std::vector<char>& pushed,
                             const ExecContext& ctx) {
  const double lo = oo.low * oo.target, hi = oo.high * oo.target;
  RegionOptimiseOptions settle_oo = oo;
  settle_oo.repair_budget = std::min(oo.repair_budget, kSettleRepairBudget);
  std::size_t ops = 0;
  for (int r = 0; r < rounds; ++r) {
    // The surface this round's optimisation keeps to, outside the body
    // between the nodes too (see refine_outside): without it, the nodes it
    // places on triangles through the body go back out with the push, and
    // the same edges leave the bounds round after round.
    auto splits = refine_outside(m, old, body, c, refine_shortest * oo.target, refine_rounds, pushed);
    if (!splits) return splits.status();
    std::vector<char> mark(m.nodes.slots.capacity(), 0);
    bool any = false;
    for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) {
      if (!m.alive(EdgeIdx{e})) continue;
      const NodeIdx a = m.tail(halfedge_of(EdgeIdx{e}, 0)), b = m.tail(halfedge_of(EdgeIdx{e}, 1));
      if (!is_new(old, a) && !is_new(old, b)) continue;
      const double l = (m.position(a) - m.position(b)).norm();
      if (l >= lo && l <= hi) continue;
      any = true;
      if (is_new(old, a)) mark[a.value] = 1;
      if (is_new(old, b)) mark[b.value] = 1;
    }
    if (!any) break;
    // Two rings more, so that the edge's ends are free (nodes of faces
    // outside the region are fixed) and the region's rim is not an edge
    // out of bounds.
    grow(m, old, mark, 2);
    std::vector<FaceIdx> region;
    std::vector<NodeIdx> fn;
    for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f) {
      if (!m.alive(FaceIdx{f}) || (f < old_face.size() && old_face[f])) continue;
      m.face_nodes(FaceIdx{f}, fn);
      if (std::any_of(fn.begin(), fn.end(), [&](NodeIdx v) { return mark[v.value] != 0; }))
        region.push_back(FaceIdx{f});
    }
    // Every place this optimisation makes is kept outside the body
    // (optimise_outside): it would otherwise relax nodes onto triangles
    // that run across a limb between pushed nodes, the push would take them
    // out again by up to 2 L, and the same edges would leave the bounds
    // round after round.
    auto oc = optimise_outside(m, region, B, chain, settle_oo, body, c, ctx);
    if (!oc) return oc.status();
    ops += oc->splits + oc->collapses + oc->swaps;
    push_out(m, old, body, c, push_rounds, pushed);
  }
  return ops;
}

}  // namespace atelier::extrude_detail

namespace atelier {

Status collision_body_of(const Model& body, CollisionBody& out) {
  auto refused = [](const Status& s) { return Status(ErrorCode::kInvalidArgument, s.message()); };
  auto tris = fan_triangulate(body);
  if (!tris) return refused(tris.status());
  if (tris->triangles.empty()) return Status(ErrorCode::kInvalidArgument, "the body has no faces");
  auto topo = CollisionTopology::build(tris->triangles, static_cast<std::uint32_t>(body.nodes.slots.capacity()));
  if (!topo) return refused(topo.status());
  CollisionBody built;
  if (Status s = built.build(*topo, body.nodes.position); !s) return refused(s);
  out = std::move(built);
  return {};
}

}  // namespace atelier
