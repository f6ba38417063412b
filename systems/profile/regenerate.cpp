// Profile regeneration (systems/profile/regenerate.h): regenerate() runs the
// stages of seed 001 section 4 / seed 000 section 4.2 in order, each a
// member of Regeneration, the state they share.
//
// Why this file is long: the stages share one state (the model being
// refined, each edge's curve, the nodes' distance bounds) and read best next
// to the outline that runs them; split over files they would need that
// state in a header of its own.
#include <atelier/systems/profile/regenerate.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include <atelier/engine/parallel.h>
#include <atelier/storage/mesh_edge_chain.h>
#include <atelier/systems/mesh/subdivide.h>
#include <atelier/systems/smooth/fairing.h>

namespace atelier {

// ------------------------------------------------------------------ helpers

namespace {

enum Role : std::uint8_t { kFree = 0, kFeature = 1, kProfile = 2, kChain = 3, kOld = 4 };

/// A curve per edge, oriented along the edge's even halfedge, and the index
/// of the template profile it descends from (for the quality check).
struct EdgeCurves {
  std::vector<std::int32_t> curve;  // per edge: index into `curves`, -1 none
  std::vector<ProfileCurve> curves;
  std::vector<std::int32_t> root;  // per curve: template profile index
  void set(EdgeIdx e, ProfileCurve c, std::int32_t r) {
    if (curve.size() <= e.value) curve.resize(e.value + 1, -1);
    curve[e.value] = static_cast<std::int32_t>(curves.size());
    curves.push_back(std::move(c));
    root.push_back(r);
  }
  [[nodiscard]] const ProfileCurve* of(EdgeIdx e) const {
    return e.value < curve.size() && curve[e.value] >= 0 ? &curves[static_cast<std::size_t>(curve[e.value])] : nullptr;
  }
};

/// The oriented curve of halfedge h (reversed for odd halfedges).
ProfileCurve along(const ProfileCurve& even_curve, HalfedgeIdx h) {
  return (h.value & 1u) ? even_curve.reversed() : even_curve;
}

bool is_chain_edge(const Model& m, EdgeIdx e) {
  if (m.is_boundary(e)) return true;
  const MeshEdgeIdx me = m.edges.mesh_edge[e.value];
  return me.valid() && m.mesh_edges.joint[me.value].valid();
}

/// The other end of the single chain edge at v besides e; none when v has
/// zero or several (a corner or junction).
std::optional<NodeIdx> chain_neighbour(const Model& m, NodeIdx v, EdgeIdx e) {
  std::optional<NodeIdx> found;
  int count = 0;
  m.for_each_outgoing(v, [&](HalfedgeIdx h) {
    if (edge_of(h) == e || !is_chain_edge(m, edge_of(h))) return;
    ++count;
    found = m.head(h);
  });
  if (count != 1) return std::nullopt;
  return found;
}

/// Interpolatory 4-point rule (Dyn, Levin, Gregory), the curve analogue of
/// the variational scheme: a missing neighbour is extrapolated linearly.
Vec3d four_point(const Vec3d& a, const Vec3d& b, const std::optional<Vec3d>& a_prev,
                 const std::optional<Vec3d>& b_next) {
  const Vec3d ap = a_prev ? *a_prev : Vec3d(2.0 * a - b);
  const Vec3d bn = b_next ? *b_next : Vec3d(2.0 * b - a);
  return (9.0 / 16.0) * (a + b) - (1.0 / 16.0) * (ap + bn);
}

}  // namespace

Expected<std::vector<RegenResult>> regenerate_on_body(std::span<const ProfileTemplate> templates,
                                                      const ReferenceBody& reference,
                                                      std::span<const Vec3d> body_positions, const Box3d& roi,
                                                      const RegenParams& params, const ColliderParams& collider,
                                                      const ExecContext& ctx) {
  ColliderPool pool;
  return regenerate_on_body(templates, reference, body_positions, roi, params, collider, ctx, pool);
}

Expected<std::vector<RegenResult>> regenerate_on_body(std::span<const ProfileTemplate> templates,
                                                      const ReferenceBody& reference,
                                                      std::span<const Vec3d> body_positions, const Box3d& roi,
                                                      const RegenParams& params, const ColliderParams& collider,
                                                      const ExecContext& ctx, ColliderPool& pool) {
  std::unique_ptr<BodyCollider> col = pool.acquire();
  // A pooled collider built on this reference's topology with the same
  // settings is refitted; anything else is built afresh.
  Status s = col->reusable_for(reference.model, reference.skin, roi, collider)
                 ? col->update(body_positions, ctx)
                 : col->build(reference.model, reference.skin, body_positions, roi, collider, ctx);
  if (!s) return s;  // a failed collider is dropped, not pooled
  std::vector<RegenResult> out;
  out.reserve(templates.size());
  for (const ProfileTemplate& t : templates) {
    auto r = regenerate(t, reference, body_positions, col.get(), params, ctx);
    if (!r) {
      pool.release(std::move(col));
      return Status(r.status().code(), t.name + ": " + r.status().message());
    }
    out.push_back(std::move(*r));
  }
  pool.release(std::move(col));
  return out;
}

double joint_crack(const Model& m) noexcept {
  double worst = 0;
  for (std::uint32_t j = 0; j < m.joints.slots.capacity(); ++j) {
    if (!m.alive(JointIdx{j})) continue;
    auto members = m.joints.members.row(j);
    if (members.size() < 2) continue;
    const std::size_t len = m.mesh_edges.halfedges.size(members[0].mesh_edge.value);
    for (std::size_t t = 0; t < len; ++t) {
      const HalfedgeIdx h0 = joint_member_halfedge(m, members[0], t);
      for (std::size_t k = 1; k < members.size(); ++k) {
        if (m.mesh_edges.halfedges.size(members[k].mesh_edge.value) != len) return INFINITY;
        const HalfedgeIdx hk = joint_member_halfedge(m, members[k], t);
        worst = std::max(worst, (m.position(m.tail(hk)) - m.position(m.tail(h0))).norm());
        worst = std::max(worst, (m.position(m.head(hk)) - m.position(m.head(h0))).norm());
      }
    }
  }
  return worst;
}

// ------------------------------------------------------------------ regenerate

namespace {

constexpr double kUnknown = -std::numeric_limits<double>::infinity();

/// A level's new nodes as computed before the split (seed 000 section 4.2),
/// per edge of the coarse model: the midpoint's position and role and, on a
/// profile edge, the curve's two halves along the edge's even halfedge.
struct EdgeSplit {
  std::vector<Vec3d> mid;
  std::vector<std::uint8_t> role;
  std::vector<std::pair<ProfileCurve, ProfileCurve>> halves;
  std::vector<std::uint8_t> has_halves;
  std::vector<std::uint8_t> done;  // set by the joint pass: the edge is computed
  explicit EdgeSplit(std::uint32_t edges)
      : mid(edges), role(edges, kFree), halves(edges), has_halves(edges, 0), done(edges, 0) {}
};

/// The coarse nodes each new node of a level descends from, taken before the
/// split: an edge's two ends (its midpoint's parents) and the corners of the
/// faces of degree > 3 (their centre's parents; a triangle gets no centre).
struct Parents {
  std::vector<std::array<NodeIdx, 2>> ends;  // per edge
  std::vector<std::uint32_t> corner_off{0};  // per face: its range in `corners`
  std::vector<NodeIdx> corners;
};

/// The state shared by the stages of one regeneration: the model being
/// built (out.model), each edge's profile curve, the nodes' distance bounds
/// and the fairing's set-up. regenerate() runs the stages in the paper's
/// order; each says what it reads and writes.
class Regeneration {
 public:
  Regeneration(const ProfileTemplate& t, const ReferenceBody& reference, std::span<const Vec3d> body_positions,
               const BodyCollider* collider, const RegenParams& params, const ExecContext& ctx, double clearance,
               std::chrono::steady_clock::time_point t0)
      : t_(t),
        reference_(reference),
        body_(body_positions),
        collider_(collider),
        params_(params),
        ctx_(ctx),
        clearance_(clearance),
        collide_(params.collision && collider != nullptr),
        t0_(t0),
        last_(t0) {}
  Regeneration(const Regeneration&) = delete;
  Regeneration& operator=(const Regeneration&) = delete;

  [[nodiscard]] bool collide() const noexcept { return collide_; }
  [[nodiscard]] RegenResult take() { return std::move(out_); }

  /// Step 1a (seed 001 section 4): the template's model with its nodes
  /// decoded on the body. Reads the template's encodings and the body;
  /// writes the model (positions; attribute nodes and edges deleted), p0_
  /// (the decoded positions) and the feature roles.
  Status relocate_feature_nodes() {
    Model& m = out_.model;
    m = t_.model;
    n0_ = m.nodes.slots.capacity();
    p0_.assign(n0_, Vec3d::Zero());
    if (Status s = decode_nodes(t_.encodings, reference_, body_, p0_); !s)
      return Status(s.code(), "regenerate '" + t_.name + "': " + s.message());
    for (std::size_t v = 0; v < n0_; ++v)
      if (m.alive(NodeIdx{static_cast<std::uint32_t>(v)})) m.nodes.position[v] = p0_[v];
    // Attached profile points are template data: the curves replace them.
    for (std::uint32_t a = 0; a < m.attrib_edges.slots.capacity(); ++a)
      if (m.alive(AttribEdgeIdx{a})) m.delete_attrib_edge(AttribEdgeIdx{a});
    for (std::uint32_t a = 0; a < m.attrib_nodes.slots.capacity(); ++a)
      if (m.alive(AttribNodeIdx{a})) m.delete_attrib_node(AttribNodeIdx{a});
    (void)m.compact();  // node, edge and face tables have no tombstones: their indices stay
    out_.role.assign(n0_, kFeature);
    return {};
  }

  /// Step 1b: the profiles decoded on the relocated ends (seed 001 eq. (7),
  /// seed 000 eq. (3)), one curve per profile edge; profiles follow joints,
  /// so every member's corresponding edge gets the curve. Reads p0_ and the
  /// joints; writes ec_.
  void rebuild_profiles() {
    const Model& m = out_.model;
    ec_.curve.assign(m.edges.slots.capacity(), -1);
    const std::vector<ProfileCurve> decoded = t_.decode_profiles(p0_);  // eqs. (7) and (3)
    for (std::size_t i = 0; i < decoded.size(); ++i) {
      const HalfedgeIdx h = t_.profiles[i].halfedge;
      ec_.set(edge_of(h), along(decoded[i], h), static_cast<std::int32_t>(i));
    }
    for (std::uint32_t j = 0; j < m.joints.slots.capacity(); ++j) {
      if (!m.alive(JointIdx{j})) continue;
      auto members = m.joints.members.row(j);
      const std::size_t len = m.mesh_edges.halfedges.size(members[0].mesh_edge.value);
      for (std::size_t s = 0; s < len; ++s) {
        std::optional<std::pair<ProfileCurve, std::int32_t>> c;  // along the joint direction
        for (const JointMember& mem : members) {
          const HalfedgeIdx h = joint_member_halfedge(m, mem, s);
          if (const ProfileCurve* pc = ec_.of(edge_of(h)); pc && !c)
            c.emplace(along(*pc, h), ec_.root[static_cast<std::size_t>(ec_.curve[edge_of(h).value])]);
        }
        if (!c) continue;
        for (const JointMember& mem : members) {
          const HalfedgeIdx h = joint_member_halfedge(m, mem, s);
          if (!ec_.of(edge_of(h))) ec_.set(edge_of(h), along(c->first, h), c->second);  // along() reverses odd h back
        }
      }
    }
  }

  /// The fairing's settings, with the collider's signed distance when the
  /// collision is on. Writes fp_.
  void set_up_fairing() {
    fp_.iterations = params_.fair_iterations;
    fp_.substeps = params_.substeps;
    fp_.clearance = clearance_;
    fp_.tolerance = params_.fair_tolerance;
    if (collide_) {
      const BodyCollider* collider = collider_;
      fp_.signed_distance = [collider](const Vec3d& p) { return collider->signed_distance(p); };
    }
  }

  /// Pushes the decoded nodes that are inside the body out to the clearance
  /// (a node encoded closer than the clearance but outside stays). Reads
  /// the model; writes lb_ (the exact distances), positions, quality.pushed.
  void push_out_decoded_nodes() {
    const Model& m = out_.model;
    lb_.assign(n0_, kUnknown);
    if (!collide_) return;
    std::vector<std::uint8_t> in(n0_, 0);
    par::for_each_n(ctx_, n0_, [&](std::size_t v) {
      if (!m.alive(NodeIdx{static_cast<std::uint32_t>(v)})) return;
      lb_[v] = collider_->exact(m.nodes.position[v]).distance;
      in[v] = lb_[v] < 0;
    });
    for (std::size_t v = 0; v < n0_; ++v)
      if (in[v]) out_.quality.pushed += push_out(v, v + 1, clearance_);
  }

  /// Step 2, one level of the modified variational subdivision (seed 000
  /// section 4.2): the new nodes' positions, the 1-to-4 split, the push-out
  /// of the new nodes and the fairing. Reads and writes the model, ec_, lb_,
  /// the roles and the quality's counters and timings.
  Status refine_level() {
    EdgeSplit split = new_node_positions();
    const Parents parents = parents_of_new_nodes();
    out_.quality.split_ms += lap();
    auto map = subdivide_uniform(out_.model, ctx_);
    if (!map) return map.status();
    if (map->compacted) return Status(ErrorCode::kInternal, "regenerate: unexpected compaction");
    place_new_nodes(*map, split);
    if (collide_) carry_bounds(*map, parents);
    // New nodes go out to 1.5x the clearance: the slack lets the fairing's
    // Lipschitz test skip most of their distance queries.
    out_.quality.split_ms += lap();
    const std::size_t n = out_.model.nodes.slots.capacity();
    if (collide_) out_.quality.pushed += push_out(map->old_nodes, n, 1.5 * clearance_);
    out_.quality.push_ms += lap();
    if (Status s = fair_new_nodes(*map); !s) return s;
    out_.quality.fair_ms += lap();
    return {};
  }

  /// The exact signed distance of every node that may be near the body
  /// (bound below 3x the clearance) and of every feature node; the others
  /// keep their bound, which already shows them outside. Infinity without a
  /// collider. Reads the model and lb_ (resized to the nodes).
  [[nodiscard]] std::vector<double> final_distances() {
    const Model& m = out_.model;
    const std::size_t n = m.nodes.slots.capacity();
    std::vector<double> d(n, INFINITY);
    if (collider_) {
      lb_.resize(n, kUnknown);
      const double near = 3.0 * clearance_;
      par::for_each_n(ctx_, n, [&](std::size_t v) {
        if (!m.alive(NodeIdx{static_cast<std::uint32_t>(v)})) return;
        d[v] = (collide_ && lb_[v] >= near && v >= n0_) ? lb_[v] : collider_->exact(m.nodes.position[v]).distance;
      });
    }
    return d;
  }

  /// A node pushed out of one part of the body can land in another where
  /// two parts nearly touch (the thighs at the crotch): pushes again with a
  /// shrinking target until nothing is inside. Reads and writes positions
  /// and `d` (kept exact for the moved nodes), quality.pushed.
  void push_until_outside(std::vector<double>& d) {
    const std::size_t n = d.size();
    for (int round = 0; round < 8; ++round) {
      std::vector<std::uint32_t> in;
      for (std::size_t v = 0; v < n; ++v)
        if (d[v] < 0) in.push_back(static_cast<std::uint32_t>(v));
      if (in.empty()) break;
      const double target = std::max(clearance_ * std::ldexp(1.0, -round), 1e-6);
      for (std::uint32_t v : in) out_.quality.pushed += push_out(v, v + 1, target);
      for (std::uint32_t v : in) d[v] = collider_->exact(out_.model.nodes.position[v]).distance;
    }
  }

  /// Step 3: penetration and the feature nodes' clearance against the
  /// encoded one (from `d`), the refined profile nodes against the curves
  /// decoded at the top level, the umbrella norm of the last level's free
  /// nodes, the joints' cracks, the timings. Writes out_.quality.
  void measure_quality(std::span<const double> d) {
    const Model& m = out_.model;
    RegenQuality& q = out_.quality;
    q.nodes = m.nodes.slots.size();
    q.faces = m.faces.slots.size();
    if (collider_) {
      q.min_distance = INFINITY;
      for (std::size_t v = 0; v < d.size(); ++v) {
        if (!m.alive(NodeIdx{static_cast<std::uint32_t>(v)})) continue;
        q.min_distance = std::min(q.min_distance, d[v]);
        if (d[v] < 0) {
          ++q.inside;
          q.max_depth = std::max(q.max_depth, -d[v]);
        }
        if (v < n0_ && v < t_.encoded_clearance.size())
          q.node_clearance_error = std::max(q.node_clearance_error, std::abs(d[v] - t_.encoded_clearance[v]));
      }
    }
    const std::vector<ProfileCurve> roots = t_.decode_profiles(p0_);
    for (std::uint32_t e = 0; e < ec_.curve.size(); ++e) {
      if (ec_.curve[e] < 0) continue;
      const ProfileCurve& c = roots[static_cast<std::size_t>(ec_.root[static_cast<std::size_t>(ec_.curve[e])])];
      const HalfedgeIdx h = halfedge_of(EdgeIdx{e}, 0);
      q.profile_error =
          std::max({q.profile_error, c.distance(m.position(m.tail(h))), c.distance(m.position(m.head(h)))});
    }
    if (!fixed_.empty()) q.umbrella = umbrella2_norm(m.nodes.position, adj_, fixed_, ctx_);
    q.crack = joint_crack(m);
    q.quality_ms += lap();
    q.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count();
  }

 private:
  /// Milliseconds since the previous lap (the first since t0).
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - last_).count();
    last_ = now;
    return ms;
  }

  /// Moves the nodes [first, last) that are inside or closer than `target`
  /// along the body normal at their closest point (seed 000 Fig. 16) and
  /// returns how many moved. A pure function of the position, so joint nodes
  /// in the same place land in the same place. Reads and writes positions
  /// and lb_[v] (a lower bound of node v's signed distance to the body,
  /// -inf when unknown; a node whose bound clears the target needs no query).
  std::size_t push_out(std::size_t first, std::size_t last, double target) {
    Model& m = out_.model;
    std::vector<std::uint8_t> moved(last - first, 0);
    par::for_each_n(ctx_, last - first, [&](std::size_t i) {
      const std::size_t v = first + i;
      if (!m.alive(NodeIdx{static_cast<std::uint32_t>(v)}) || lb_[v] >= target) return;
      const Vec3d& p = m.nodes.position[v];
      // The grid (when there is one) clears far nodes cheaply; otherwise one
      // exact query decides and gives the push-out target.
      if (collider_->has_grid()) {
        const double g = collider_->signed_distance(p);
        if (g >= target) return;
      }
      const SignedHit hit = collider_->exact(p);
      if (hit.distance >= target) {
        lb_[v] = hit.distance;
        return;
      }
      m.nodes.position[v] = hit.closest.point + target * hit.normal;
      lb_[v] = kUnknown;
      moved[i] = 1;
    });
    std::size_t n = 0;
    for (auto x : moved) n += x;
    return n;
  }

  /// Where each edge's new node goes: C(1/2) of the edge's profile, with the
  /// curve halved; on a boundary or joint chain without a profile the
  /// 4-point rule along the chain (or the midpoint without smooth_chains);
  /// elsewhere the midpoint. Joint edges first: one computation per joint
  /// position, copied to all members, so corresponding new nodes are
  /// bit-identical. Reads the model and ec_.
  [[nodiscard]] EdgeSplit new_node_positions() const {
    const Model& m = out_.model;
    const std::uint32_t E = static_cast<std::uint32_t>(m.edges.slots.capacity());
    EdgeSplit sp(E);
    for (std::uint32_t j = 0; j < m.joints.slots.capacity(); ++j) {
      if (!m.alive(JointIdx{j})) continue;
      auto members = m.joints.members.row(j);
      const std::size_t len = m.mesh_edges.halfedges.size(members[0].mesh_edge.value);
      const NodeIdx first = m.tail(joint_member_halfedge(m, members[0], 0));
      const NodeIdx lastn = m.head(joint_member_halfedge(m, members[0], len - 1));
      const bool closed = first == lastn;
      for (std::size_t s = 0; s < len; ++s) {
        const HalfedgeIdx h0 = joint_member_halfedge(m, members[0], s);
        Vec3d pm;
        std::uint8_t role = kChain;
        std::optional<std::pair<ProfileCurve, ProfileCurve>> hv;
        if (const ProfileCurve* pc = ec_.of(edge_of(h0))) {
          const ProfileCurve c = along(*pc, h0);
          pm = c.eval(0.5);
          hv = c.split_half();
          role = kProfile;
        } else if (params_.smooth_chains) {
          std::optional<Vec3d> ap, bn;
          if (s > 0 || closed) ap = m.position(m.tail(joint_member_halfedge(m, members[0], s > 0 ? s - 1 : len - 1)));
          if (s + 1 < len || closed) bn = m.position(m.head(joint_member_halfedge(m, members[0], s + 1 < len ? s + 1 : 0)));
          pm = four_point(m.position(m.tail(h0)), m.position(m.head(h0)), ap, bn);
        } else {
          pm = 0.5 * (m.position(m.tail(h0)) + m.position(m.head(h0)));
        }
        for (const JointMember& mem : members) {
          const HalfedgeIdx h = joint_member_halfedge(m, mem, s);
          const EdgeIdx e = edge_of(h);
          sp.mid[e.value] = pm;
          sp.role[e.value] = role;
          sp.done[e.value] = 1;
          if (hv) {  // halves along the even halfedge of e
            sp.halves[e.value] = (h.value & 1u) ? std::pair{hv->second.reversed(), hv->first.reversed()} : *hv;
            sp.has_halves[e.value] = 1;
          }
        }
      }
    }
    par::for_each_n(ctx_, E, [&](std::size_t ei) {
      const EdgeIdx e{static_cast<std::uint32_t>(ei)};
      if (sp.done[ei] || !m.alive(e)) return;
      const HalfedgeIdx h = halfedge_of(e, 0);
      const NodeIdx a = m.tail(h), b = m.head(h);
      if (const ProfileCurve* pc = ec_.of(e)) {
        sp.mid[ei] = pc->eval(0.5);  // C(1/2), seed 000 section 4.2
        sp.halves[ei] = pc->split_half();
        sp.has_halves[ei] = 1;
        sp.role[ei] = kProfile;
      } else if (m.is_boundary(e) && params_.smooth_chains) {
        std::optional<Vec3d> ap, bn;
        if (auto x = chain_neighbour(m, a, e)) ap = m.position(*x);
        if (auto x = chain_neighbour(m, b, e)) bn = m.position(*x);
        sp.mid[ei] = four_point(m.position(a), m.position(b), ap, bn);
        sp.role[ei] = kChain;
      } else {
        sp.mid[ei] = 0.5 * (m.position(a) + m.position(b));
        sp.role[ei] = m.is_boundary(e) ? kChain : kFree;
      }
    });
    return sp;
  }

  /// The parents of the new nodes, read off the coarse model.
  [[nodiscard]] Parents parents_of_new_nodes() const {
    const Model& m = out_.model;
    const std::uint32_t E = static_cast<std::uint32_t>(m.edges.slots.capacity());
    Parents p;
    p.ends.resize(E);
    for (std::uint32_t e = 0; e < E; ++e)
      if (m.alive(EdgeIdx{e})) p.ends[e] = {m.tail(halfedge_of(EdgeIdx{e}, 0)), m.head(halfedge_of(EdgeIdx{e}, 0))};
    const std::uint32_t F = static_cast<std::uint32_t>(m.faces.slots.capacity());
    std::vector<NodeIdx> ring;
    for (std::uint32_t f = 0; f < F; ++f) {
      if (m.alive(FaceIdx{f}) && m.face_degree(FaceIdx{f}) > 3) {
        m.face_nodes(FaceIdx{f}, ring);
        p.corners.insert(p.corners.end(), ring.begin(), ring.end());
      }
      p.corner_off.push_back(static_cast<std::uint32_t>(p.corners.size()));
    }
    return p;
  }

  /// After the split: each edge's new node goes where `split` put it, with
  /// its role; a profile edge's two halves carry the curve's halves (and its
  /// root). Old nodes without a role become kOld. Writes positions, roles, ec_.
  void place_new_nodes(const SubdivisionMap& map, EdgeSplit& split) {
    Model& m = out_.model;
    const std::uint32_t E = static_cast<std::uint32_t>(split.mid.size());
    const std::size_t n = m.nodes.slots.capacity();
    out_.role.resize(n, kFree);
    for (std::size_t v = 0; v < map.old_nodes; ++v)
      if (out_.role[v] == kFree) out_.role[v] = kOld;
    EdgeCurves next;
    next.curve.assign(m.edges.slots.capacity(), -1);
    for (std::uint32_t e = 0; e < E; ++e) {
      if (!m.alive(EdgeIdx{e})) continue;
      const NodeIdx mv = map.edge_midpoint[e];
      m.nodes.position[mv.value] = split.mid[e];
      out_.role[mv.value] = split.role[e];
      if (split.has_halves[e]) {
        const std::int32_t r = ec_.root[static_cast<std::size_t>(ec_.curve[e])];
        // first_half(2e) = 2e runs tail -> midpoint; second_half(2e) is even
        // and runs midpoint -> head.
        next.set(EdgeIdx{e}, std::move(split.halves[e].first), r);
        next.set(edge_of(map.second_half(halfedge_of(EdgeIdx{e}, 0))), std::move(split.halves[e].second), r);
      }
    }
    ec_ = std::move(next);
    lb_.resize(n, kUnknown);
  }

  /// A signed distance is 1-Lipschitz, so a new node's bound is its
  /// parent's minus their distance (the best over its parents). Writes lb_.
  void carry_bounds(const SubdivisionMap& map, const Parents& parents) {
    const Model& m = out_.model;
    auto from = [&](NodeIdx v, NodeIdx parent) {
      lb_[v.value] = std::max(lb_[v.value], lb_[parent.value] - (m.position(v) - m.position(parent)).norm());
    };
    const std::uint32_t E = static_cast<std::uint32_t>(parents.ends.size());
    for (std::uint32_t e = 0; e < E; ++e) {
      if (!m.alive(EdgeIdx{e})) continue;
      from(map.edge_midpoint[e], parents.ends[e][0]);
      from(map.edge_midpoint[e], parents.ends[e][1]);
    }
    const std::uint32_t F = static_cast<std::uint32_t>(parents.corner_off.size() - 1);
    for (std::uint32_t f = 0; f < F; ++f) {
      const NodeIdx c = map.face_centre[f];
      if (!c.valid()) continue;
      for (std::uint32_t k = parents.corner_off[f]; k < parents.corner_off[f + 1]; ++k) from(c, parents.corners[k]);
    }
  }

  /// Kobbelt's umbrella fairing of the new free nodes, with old, profile,
  /// boundary and joint nodes fixed, collision-checked against lb_ when the
  /// collision is on (systems/smooth/fairing.h). Writes positions, fixed_,
  /// adj_, lb_ and the quality's fairing counters.
  Status fair_new_nodes(const SubdivisionMap& map) {
    Model& m = out_.model;
    const std::size_t n = m.nodes.slots.capacity();
    fixed_.assign(n, 1);
    for (std::size_t v = map.old_nodes; v < n; ++v) fixed_[v] = out_.role[v] == kFree ? 0 : 1;
    adj_ = build_adjacency(m, {}, ctx_);
    if (collide_) fp_.distance_bounds = lb_;
    auto fr = fair_umbrella(m.nodes.position, adj_, fixed_, fp_, ctx_);
    if (!fr) return fr.status();
    out_.quality.refused_moves += fr->refused_moves;
    out_.quality.fair_queries += fr->distance_queries;
    return {};
  }

  // Inputs.
  const ProfileTemplate& t_;
  const ReferenceBody& reference_;
  std::span<const Vec3d> body_;
  const BodyCollider* collider_;
  const RegenParams& params_;
  const ExecContext& ctx_;
  const double clearance_;
  const bool collide_;
  const std::chrono::steady_clock::time_point t0_;
  std::chrono::steady_clock::time_point last_;

  // State.
  RegenResult out_;                  // the model being built, its roles and quality
  std::size_t n0_ = 0;               // the template's node count (the feature nodes)
  std::vector<Vec3d> p0_;            // the feature nodes decoded on the body
  EdgeCurves ec_;                    // each edge's profile curve
  std::vector<double> lb_;           // per node: lower bound of its signed distance (kUnknown: none)
  std::vector<std::uint8_t> fixed_;  // the last level's fairing: fixed nodes
  NodeAdjacency adj_;                // and adjacency (for the umbrella norm)
  FairParams fp_;
};

}  // namespace

Expected<RegenResult> regenerate(const ProfileTemplate& t, const ReferenceBody& reference,
                                 std::span<const Vec3d> body_positions, const BodyCollider* collider,
                                 const RegenParams& params, const ExecContext& ctx) {
  const auto t0 = std::chrono::steady_clock::now();
  const int levels = params.levels >= 0 ? params.levels : t.levels;
  const double clearance = params.clearance >= 0 ? params.clearance : t.clearance;
  if (params.collision && !collider)
    return Status(ErrorCode::kInvalidArgument, "regenerate '" + t.name + "': collision requested without a collider");
  if (levels > kMaxTemplateLevels)
    return Status(ErrorCode::kInvalidArgument,
                  "regenerate: more than " + std::to_string(kMaxTemplateLevels) + " levels requested");
  if (body_positions.size() < reference.model.nodes.slots.capacity())
    return Status(ErrorCode::kMismatch, "regenerate '" + t.name + "': the body has " +
                                            std::to_string(body_positions.size()) + " node positions, the reference " +
                                            std::to_string(reference.model.nodes.slots.capacity()));
  Regeneration r(t, reference, body_positions, collider, params, ctx, clearance, t0);

  // 1. Relocate the feature nodes and rebuild the profiles (seed 001 section
  //    4, eqs. (7) and (3)); a decoded node inside the body is pushed out.
  if (Status s = r.relocate_feature_nodes(); !s) return s;
  r.rebuild_profiles();
  r.set_up_fairing();
  r.push_out_decoded_nodes();

  // 2. Modified variational subdivision (seed 000 section 4.2), per level:
  //    split (profile and chain nodes placed), push-out, fairing.
  for (int level = 0; level < levels; ++level) {
    if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "regenerate cancelled");
    if (Status s = r.refine_level(); !s) return s;
  }

  // Push-out again until no node is inside (nodes pushed out of one part of
  // the body into another); the distances are kept for the quality.
  std::vector<double> d = r.final_distances();
  if (r.collide()) r.push_until_outside(d);

  // 3. Quality.
  r.measure_quality(d);
  return r.take();
}

}  // namespace atelier
