#include <atelier/systems/profile/regenerate.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include <atelier/engine/parallel.h>
#include <atelier/systems/smooth/fairing.h>
#include <atelier/systems/mesh/subdivide.h>

namespace atelier {

// ------------------------------------------------------------------ helpers

namespace {

enum Role : std::uint8_t { kFree = 0, kFeature = 1, kProfile = 2, kChain = 3, kOld = 4 };

/// The halfedge of joint member `mem` from its node t to node t + 1 (in the
/// joint's direction).
HalfedgeIdx member_halfedge(const Model& m, const JointMember& mem, std::size_t t) {
  auto chain = m.mesh_edges.halfedges.row(mem.mesh_edge.value);
  const std::size_t len = chain.size();
  return mem.positive ? chain[t] : twin(chain[len - 1 - t]);
}

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
Vec3d four_point(const Vec3d& a, const Vec3d& b, const std::optional<Vec3d>& a_prev, const std::optional<Vec3d>& b_next) {
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
      const HalfedgeIdx h0 = member_halfedge(m, members[0], t);
      for (std::size_t k = 1; k < members.size(); ++k) {
        if (m.mesh_edges.halfedges.size(members[k].mesh_edge.value) != len) return INFINITY;
        const HalfedgeIdx hk = member_halfedge(m, members[k], t);
        worst = std::max(worst, (m.position(m.tail(hk)) - m.position(m.tail(h0))).norm());
        worst = std::max(worst, (m.position(m.head(hk)) - m.position(m.head(h0))).norm());
      }
    }
  }
  return worst;
}

// ------------------------------------------------------------------ regenerate

Expected<RegenResult> regenerate(const ProfileTemplate& t, const ReferenceBody& reference,
                                 std::span<const Vec3d> body_positions, const BodyCollider* collider,
                                 const RegenParams& params, const ExecContext& ctx) {
  const auto t0 = std::chrono::steady_clock::now();
  auto lap = [last = t0]() mutable {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - last).count();
    last = now;
    return ms;
  };
  const int levels = params.levels >= 0 ? params.levels : t.levels;
  const double clearance = params.clearance >= 0 ? params.clearance : t.clearance;
  const bool collide = params.collision && collider != nullptr;
  if (params.collision && !collider)
    return Status(ErrorCode::kInvalidArgument, "regenerate '" + t.name + "': collision requested without a collider");
  if (levels > kMaxTemplateLevels)
    return Status(ErrorCode::kInvalidArgument,
                  "regenerate: more than " + std::to_string(kMaxTemplateLevels) + " levels requested");
  if (body_positions.size() < reference.model.nodes.slots.capacity())
    return Status(ErrorCode::kMismatch, "regenerate '" + t.name + "': the body has " +
                                            std::to_string(body_positions.size()) + " node positions, the reference " +
                                            std::to_string(reference.model.nodes.slots.capacity()));

  // 1. Relocate the feature nodes and rebuild the profiles.
  RegenResult out;
  Model& m = out.model;
  m = t.model;
  const std::size_t n0 = m.nodes.slots.capacity();
  std::vector<Vec3d> p0(n0, Vec3d::Zero());
  if (Status s = decode_nodes(t.encodings, reference, body_positions, p0); !s)
    return Status(s.code(), "regenerate '" + t.name + "': " + s.message());
  for (std::size_t v = 0; v < n0; ++v)
    if (m.alive(NodeIdx{static_cast<std::uint32_t>(v)})) m.nodes.position[v] = p0[v];
  // Attached profile points are template data: the curves replace them.
  for (std::uint32_t a = 0; a < m.attrib_edges.slots.capacity(); ++a)
    if (m.alive(AttribEdgeIdx{a})) m.delete_attrib_edge(AttribEdgeIdx{a});
  for (std::uint32_t a = 0; a < m.attrib_nodes.slots.capacity(); ++a)
    if (m.alive(AttribNodeIdx{a})) m.delete_attrib_node(AttribNodeIdx{a});
  (void)m.compact();  // node, edge and face tables have no tombstones: their indices stay

  EdgeCurves ec;
  ec.curve.assign(m.edges.slots.capacity(), -1);
  {
    const std::vector<ProfileCurve> decoded = t.decode_profiles(p0);  // eqs. (7) and (3)
    for (std::size_t i = 0; i < decoded.size(); ++i) {
      const HalfedgeIdx h = t.profiles[i].halfedge;
      ec.set(edge_of(h), along(decoded[i], h), static_cast<std::int32_t>(i));
    }
    // Profiles follow joints: every member's corresponding edge gets the curve.
    for (std::uint32_t j = 0; j < m.joints.slots.capacity(); ++j) {
      if (!m.alive(JointIdx{j})) continue;
      auto members = m.joints.members.row(j);
      const std::size_t len = m.mesh_edges.halfedges.size(members[0].mesh_edge.value);
      for (std::size_t s = 0; s < len; ++s) {
        std::optional<std::pair<ProfileCurve, std::int32_t>> c;  // along the joint direction
        for (const JointMember& mem : members) {
          const HalfedgeIdx h = member_halfedge(m, mem, s);
          if (const ProfileCurve* pc = ec.of(edge_of(h)); pc && !c)
            c.emplace(along(*pc, h), ec.root[static_cast<std::size_t>(ec.curve[edge_of(h).value])]);
        }
        if (!c) continue;
        for (const JointMember& mem : members) {
          const HalfedgeIdx h = member_halfedge(m, mem, s);
          if (!ec.of(edge_of(h))) ec.set(edge_of(h), along(c->first, h), c->second);  // along() reverses odd h back
        }
      }
    }
  }

  out.role.assign(n0, kFeature);
  std::vector<std::uint8_t> fixed;
  NodeAdjacency adj;
  FairParams fp;
  fp.iterations = params.fair_iterations;
  fp.substeps = params.substeps;
  fp.clearance = clearance;
  fp.tolerance = params.fair_tolerance;
  if (collide) fp.signed_distance = [collider](const Vec3d& p) { return collider->signed_distance(p); };

  // lb[v]: a lower bound of node v's signed distance to the body (-inf when
  // unknown). A signed distance is 1-Lipschitz, so bounds carry over to new
  // nodes (from their parents) and through moves (minus the move's length),
  // and a node whose bound clears the target needs no body query.
  constexpr double kUnknown = -std::numeric_limits<double>::infinity();
  std::vector<double> lb(n0, kUnknown);
  auto push_out = [&](std::size_t first, std::size_t last, double target) -> std::size_t {
    // A node inside or too close moves along the body normal at its closest
    // point (seed 000 Fig. 16). A pure function of the position, so joint
    // nodes in the same place land in the same place.
    std::vector<std::uint8_t> moved(last - first, 0);
    par::for_each_n(ctx, last - first, [&](std::size_t i) {
      const std::size_t v = first + i;
      if (!m.alive(NodeIdx{static_cast<std::uint32_t>(v)}) || lb[v] >= target) return;
      const Vec3d& p = m.nodes.position[v];
      // The grid (when there is one) clears far nodes cheaply; otherwise one
      // exact query decides and gives the push-out target.
      if (collider->has_grid()) {
        const double g = collider->signed_distance(p);
        if (g >= target) return;
      }
      const SignedHit hit = collider->exact(p);
      if (hit.distance >= target) {
        lb[v] = hit.distance;
        return;
      }
      m.nodes.position[v] = hit.closest.point + target * hit.normal;
      lb[v] = kUnknown;
      moved[i] = 1;
    });
    std::size_t n = 0;
    for (auto x : moved) n += x;
    return n;
  };

  if (collide) {  // decoded nodes only when inside (a node encoded closer than the clearance stays)
    std::vector<std::uint8_t> in(n0, 0);
    par::for_each_n(ctx, n0, [&](std::size_t v) {
      if (!m.alive(NodeIdx{static_cast<std::uint32_t>(v)})) return;
      lb[v] = collider->exact(m.nodes.position[v]).distance;
      in[v] = lb[v] < 0;
    });
    for (std::size_t v = 0; v < n0; ++v)
      if (in[v]) out.quality.pushed += push_out(v, v + 1, clearance);
  }

  // 2. Modified variational subdivision.
  for (int level = 0; level < levels; ++level) {
    if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "regenerate cancelled");
    const std::uint32_t E = static_cast<std::uint32_t>(m.edges.slots.capacity());
    std::vector<Vec3d> mid(E);
    std::vector<std::uint8_t> mid_role(E, kFree);
    std::vector<std::pair<ProfileCurve, ProfileCurve>> halves(E);
    std::vector<std::uint8_t> has_halves(E, 0);
    // Joint edges first: one computation per joint position, copied to all
    // members, so corresponding new nodes are bit-identical.
    std::vector<std::uint8_t> done(E, 0);
    for (std::uint32_t j = 0; j < m.joints.slots.capacity(); ++j) {
      if (!m.alive(JointIdx{j})) continue;
      auto members = m.joints.members.row(j);
      const std::size_t len = m.mesh_edges.halfedges.size(members[0].mesh_edge.value);
      const NodeIdx first = m.tail(member_halfedge(m, members[0], 0));
      const NodeIdx lastn = m.head(member_halfedge(m, members[0], len - 1));
      const bool closed = first == lastn;
      for (std::size_t s = 0; s < len; ++s) {
        const HalfedgeIdx h0 = member_halfedge(m, members[0], s);
        Vec3d pm;
        std::uint8_t role = kChain;
        std::optional<std::pair<ProfileCurve, ProfileCurve>> hv;
        if (const ProfileCurve* pc = ec.of(edge_of(h0))) {
          const ProfileCurve c = along(*pc, h0);
          pm = c.eval(0.5);
          hv = c.split_half();
          role = kProfile;
        } else if (params.smooth_chains) {
          std::optional<Vec3d> ap, bn;
          if (s > 0 || closed) ap = m.position(m.tail(member_halfedge(m, members[0], s > 0 ? s - 1 : len - 1)));
          if (s + 1 < len || closed) bn = m.position(m.head(member_halfedge(m, members[0], s + 1 < len ? s + 1 : 0)));
          pm = four_point(m.position(m.tail(h0)), m.position(m.head(h0)), ap, bn);
        } else {
          pm = 0.5 * (m.position(m.tail(h0)) + m.position(m.head(h0)));
        }
        for (const JointMember& mem : members) {
          const HalfedgeIdx h = member_halfedge(m, mem, s);
          const EdgeIdx e = edge_of(h);
          mid[e.value] = pm;
          mid_role[e.value] = role;
          done[e.value] = 1;
          if (hv) {  // halves along the even halfedge of e
            halves[e.value] = (h.value & 1u) ? std::pair{hv->second.reversed(), hv->first.reversed()} : *hv;
            has_halves[e.value] = 1;
          }
        }
      }
    }
    par::for_each_n(ctx, E, [&](std::size_t ei) {
      const EdgeIdx e{static_cast<std::uint32_t>(ei)};
      if (done[ei] || !m.alive(e)) return;
      const HalfedgeIdx h = halfedge_of(e, 0);
      const NodeIdx a = m.tail(h), b = m.head(h);
      if (const ProfileCurve* pc = ec.of(e)) {
        mid[ei] = pc->eval(0.5);  // C(1/2), seed 000 section 4.2
        halves[ei] = pc->split_half();
        has_halves[ei] = 1;
        mid_role[ei] = kProfile;
      } else if (m.is_boundary(e) && params.smooth_chains) {
        std::optional<Vec3d> ap, bn;
        if (auto x = chain_neighbour(m, a, e)) ap = m.position(*x);
        if (auto x = chain_neighbour(m, b, e)) bn = m.position(*x);
        mid[ei] = four_point(m.position(a), m.position(b), ap, bn);
        mid_role[ei] = kChain;
      } else {
        mid[ei] = 0.5 * (m.position(a) + m.position(b));
        mid_role[ei] = m.is_boundary(e) ? kChain : kFree;
      }
    });

    // Parents of the new nodes, for their distance bounds.
    std::vector<std::array<NodeIdx, 2>> ends(E);
    for (std::uint32_t e = 0; e < E; ++e)
      if (m.alive(EdgeIdx{e})) ends[e] = {m.tail(halfedge_of(EdgeIdx{e}, 0)), m.head(halfedge_of(EdgeIdx{e}, 0))};
    const std::uint32_t F = static_cast<std::uint32_t>(m.faces.slots.capacity());
    std::vector<std::uint32_t> corner_off{0};
    std::vector<NodeIdx> corners;
    std::vector<NodeIdx> ring;
    for (std::uint32_t f = 0; f < F; ++f) {
      if (m.alive(FaceIdx{f}) && m.face_degree(FaceIdx{f}) > 3) {
        m.face_nodes(FaceIdx{f}, ring);
        corners.insert(corners.end(), ring.begin(), ring.end());
      }
      corner_off.push_back(static_cast<std::uint32_t>(corners.size()));
    }
    out.quality.split_ms += lap();
    auto map = subdivide_uniform(m, ctx);
    if (!map) return map.status();
    if (map->compacted) return Status(ErrorCode::kInternal, "regenerate: unexpected compaction");
    const std::size_t n = m.nodes.slots.capacity();
    out.role.resize(n, kFree);
    for (std::size_t v = 0; v < map->old_nodes; ++v)
      if (out.role[v] == kFree) out.role[v] = kOld;
    EdgeCurves next;
    next.curve.assign(m.edges.slots.capacity(), -1);
    for (std::uint32_t e = 0; e < E; ++e) {
      if (!m.alive(EdgeIdx{e})) continue;
      const NodeIdx mv = map->edge_midpoint[e];
      m.nodes.position[mv.value] = mid[e];
      out.role[mv.value] = mid_role[e];
      if (has_halves[e]) {
        const std::int32_t r = ec.root[static_cast<std::size_t>(ec.curve[e])];
        // first_half(2e) = 2e runs tail -> midpoint; second_half(2e) is even
        // and runs midpoint -> head.
        next.set(EdgeIdx{e}, std::move(halves[e].first), r);
        next.set(edge_of(map->second_half(halfedge_of(EdgeIdx{e}, 0))), std::move(halves[e].second), r);
      }
    }
    ec = std::move(next);
    lb.resize(n, kUnknown);
    if (collide) {
      auto from = [&](NodeIdx v, NodeIdx parent) {
        lb[v.value] = std::max(lb[v.value], lb[parent.value] - (m.position(v) - m.position(parent)).norm());
      };
      for (std::uint32_t e = 0; e < E; ++e) {
        if (!m.alive(EdgeIdx{e})) continue;
        from(map->edge_midpoint[e], ends[e][0]);
        from(map->edge_midpoint[e], ends[e][1]);
      }
      for (std::uint32_t f = 0; f < F; ++f) {
        const NodeIdx c = map->face_centre[f];
        if (!c.valid()) continue;
        for (std::uint32_t k = corner_off[f]; k < corner_off[f + 1]; ++k) from(c, corners[k]);
      }
    }

    // New nodes go out to 1.5x the clearance: the slack lets the fairing's
    // Lipschitz test skip most of their distance queries.
    out.quality.split_ms += lap();
    if (collide) out.quality.pushed += push_out(map->old_nodes, n, 1.5 * clearance);
    out.quality.push_ms += lap();

    fixed.assign(n, 1);
    for (std::size_t v = map->old_nodes; v < n; ++v) fixed[v] = out.role[v] == kFree ? 0 : 1;
    adj = build_adjacency(m, {}, ctx);
    if (collide) fp.distance_bounds = lb;
    auto fr = fair_umbrella(m.nodes.position, adj, fixed, fp, ctx);
    if (!fr) return fr.status();
    out.quality.refused_moves += fr->refused_moves;
    out.quality.fair_queries += fr->distance_queries;
    out.quality.fair_ms += lap();
  }

  // A node pushed out of one part of the body can land in another where two
  // parts nearly touch (the thighs at the crotch): push again with a
  // shrinking target until nothing is inside.
  // The exact distance of every node that may be near the body (bound below
  // 3x the clearance) and of every feature node; the others keep their
  // bound, which already shows them outside. Kept up to date through the
  // re-push rounds; the quality measures report it.
  const std::size_t n = m.nodes.slots.capacity();
  std::vector<double> d(n, INFINITY);
  if (collider) {
    lb.resize(n, kUnknown);
    const double near = 3.0 * clearance;
    par::for_each_n(ctx, n, [&](std::size_t v) {
      if (!m.alive(NodeIdx{static_cast<std::uint32_t>(v)})) return;
      d[v] = (collide && lb[v] >= near && v >= n0) ? lb[v] : collider->exact(m.nodes.position[v]).distance;
    });
  }
  if (collide) {
    for (int round = 0; round < 8; ++round) {
      std::vector<std::uint32_t> in;
      for (std::size_t v = 0; v < n; ++v)
        if (d[v] < 0) in.push_back(static_cast<std::uint32_t>(v));
      if (in.empty()) break;
      const double target = std::max(clearance * std::ldexp(1.0, -round), 1e-6);
      for (std::uint32_t v : in) out.quality.pushed += push_out(v, v + 1, target);
      for (std::uint32_t v : in) d[v] = collider->exact(m.nodes.position[v]).distance;
    }
  }

  // 3. Quality.
  RegenQuality& q = out.quality;
  q.nodes = m.nodes.slots.size();
  q.faces = m.faces.slots.size();
  if (collider) {
    q.min_distance = INFINITY;
    for (std::size_t v = 0; v < n; ++v) {
      if (!m.alive(NodeIdx{static_cast<std::uint32_t>(v)})) continue;
      q.min_distance = std::min(q.min_distance, d[v]);
      if (d[v] < 0) {
        ++q.inside;
        q.max_depth = std::max(q.max_depth, -d[v]);
      }
      if (v < n0 && v < t.encoded_clearance.size())
        q.node_clearance_error = std::max(q.node_clearance_error, std::abs(d[v] - t.encoded_clearance[v]));
    }
  }
  {
    // Refined profile nodes against the curves decoded at the top level.
    const std::vector<ProfileCurve> roots = t.decode_profiles(p0);
    for (std::uint32_t e = 0; e < ec.curve.size(); ++e) {
      if (ec.curve[e] < 0) continue;
      const ProfileCurve& c = roots[static_cast<std::size_t>(ec.root[static_cast<std::size_t>(ec.curve[e])])];
      const HalfedgeIdx h = halfedge_of(EdgeIdx{e}, 0);
      q.profile_error = std::max({q.profile_error, c.distance(m.position(m.tail(h))), c.distance(m.position(m.head(h)))});
    }
  }
  if (!fixed.empty()) q.umbrella = umbrella2_norm(m.nodes.position, adj, fixed, ctx);
  q.crack = joint_crack(m);
  q.quality_ms += lap();
  q.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace atelier
