#include "systems/fairing.h"

#include <algorithm>
#include <atomic>
#include <sstream>

#include "engine/parallel.h"

namespace atelier {

NodeAdjacency build_adjacency(const Model& m, SurfaceIdx only, const ExecContext& ctx) {
  NodeAdjacency a;
  const std::size_t n = m.nodes.slots.capacity();
  a.offset.assign(n + 1, 0);
  a.topology_version = m.topology_version;
  auto use = [&](std::size_t v) {
    return m.alive(NodeIdx{static_cast<std::uint32_t>(v)}) && (!only.valid() || m.nodes.surface[v] == only);
  };
  par::for_each_n(ctx, n, [&](std::size_t v) {
    if (use(v)) a.offset[v + 1] = static_cast<std::uint32_t>(m.degree(NodeIdx{static_cast<std::uint32_t>(v)}));
  });
  for (std::size_t v = 0; v < n; ++v) a.offset[v + 1] += a.offset[v];
  a.neighbor.resize(a.offset[n]);
  par::for_each_n(ctx, n, [&](std::size_t v) {
    if (!use(v)) return;
    std::uint32_t k = a.offset[v];
    m.for_each_outgoing(NodeIdx{static_cast<std::uint32_t>(v)}, [&](HalfedgeIdx h) { a.neighbor[k++] = m.head(h).value; });
  });
  return a;
}

namespace {

// U(p) for every node with neighbours (others: zero).
void umbrella(std::span<const Vec3d> p, const NodeAdjacency& adj, std::vector<Vec3d>& u, const ExecContext& ctx) {
  const std::size_t n = p.size();
  u.resize(n);
  par::for_each_n(ctx, n, [&](std::size_t v) {
    const std::uint32_t b = adj.offset[v], e = adj.offset[v + 1];
    if (b == e) {
      u[v] = Vec3d::Zero();
      return;
    }
    Vec3d s = Vec3d::Zero();
    for (std::uint32_t k = b; k < e; ++k) s += p[adj.neighbor[k]];
    u[v] = s / static_cast<double>(e - b) - p[v];
  });
}

Vec3d umbrella2_at(std::size_t v, const NodeAdjacency& adj, const std::vector<Vec3d>& u) {
  const std::uint32_t b = adj.offset[v], e = adj.offset[v + 1];
  Vec3d s = Vec3d::Zero();
  for (std::uint32_t k = b; k < e; ++k) s += u[adj.neighbor[k]];
  return s / static_cast<double>(e - b) - u[v];
}

}  // namespace

double umbrella2_norm(std::span<const Vec3d> p, const NodeAdjacency& adj, std::span<const std::uint8_t> fixed,
                      const ExecContext& ctx) {
  std::vector<Vec3d> u;
  umbrella(p, adj, u, ctx);
  return par::transform_reduce(
      ctx, p.size(), 0.0,
      [&](std::size_t v) { return fixed[v] || adj.degree(v) == 0 ? 0.0 : umbrella2_at(v, adj, u).norm(); },
      [](double a, double b) { return std::max(a, b); });
}

Expected<FairPlan> make_fair_plan(const NodeAdjacency& adj, std::span<const std::uint8_t> fixed, const FairParams& prm,
                                  const ExecContext& ctx) {
  const std::size_t n = fixed.size();
  if (adj.offset.size() != n + 1) {
    std::ostringstream s;
    s << "fair_umbrella: " << n << " fixed flags and an adjacency of "
      << (adj.offset.empty() ? 0 : adj.offset.size() - 1) << " nodes do not match";
    return Status(ErrorCode::kMismatch, s.str());
  }
  if (!(prm.relaxation > 0.0 && prm.relaxation <= 1.0))
    return Status(ErrorCode::kInvalidArgument, "fair_umbrella: relaxation must be in (0, 1]");
  FairPlan plan;
  plan.nodes = n;
  plan.adjacency_version = adj.topology_version;
  plan.relaxation = prm.relaxation;
  // 1/n per node and the diagonal 1/nu_v (Kobbelt): nu = 1 + 1/n sum_j 1/n_j.
  plan.inv_deg.assign(n, 0.0);
  plan.inv_nu.assign(n, 0.0);
  par::for_each_n(ctx, n, [&](std::size_t v) {
    if (adj.degree(v)) plan.inv_deg[v] = 1.0 / adj.degree(v);
  });
  par::for_each_n(ctx, n, [&](std::size_t v) {
    if (fixed[v] || adj.degree(v) == 0) return;
    double s = 0;
    for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) s += plan.inv_deg[adj.neighbor[k]];
    plan.inv_nu[v] = prm.relaxation / (1.0 + s * plan.inv_deg[v]);
  });
  for (std::size_t v = 0; v < n; ++v)
    if (!fixed[v] && adj.degree(v)) plan.free_nodes.push_back(static_cast<std::uint32_t>(v));
  // Nodes that feed U2 of a free node: the free nodes and their neighbours.
  std::vector<std::uint8_t> need_u(n, 0);
  for (std::uint32_t v : plan.free_nodes) {
    need_u[v] = 1;
    for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) need_u[adj.neighbor[k]] = 1;
  }
  for (std::size_t v = 0; v < n; ++v)
    if (need_u[v] && adj.degree(v)) plan.u_nodes.push_back(static_cast<std::uint32_t>(v));
  return plan;
}

Expected<FairReport> fair_umbrella(std::span<Vec3d> p, const NodeAdjacency& adj, std::span<const std::uint8_t> fixed,
                                   const FairParams& prm, const ExecContext& ctx) {
  if (fixed.size() != p.size()) {
    std::ostringstream s;
    s << "fair_umbrella: " << p.size() << " positions, " << fixed.size() << " fixed flags and an adjacency of "
      << (adj.offset.empty() ? 0 : adj.offset.size() - 1) << " nodes do not match";
    return Status(ErrorCode::kMismatch, s.str());
  }
  auto plan = make_fair_plan(adj, fixed, prm, ctx);
  if (!plan) return plan.status();
  return fair_umbrella(p, adj, *plan, prm, ctx);
}

Expected<FairReport> fair_umbrella(std::span<Vec3d> p, const NodeAdjacency& adj, const FairPlan& plan,
                                   const FairParams& prm, const ExecContext& ctx) {
  const std::size_t n = p.size();
  if (plan.nodes != n || adj.offset.size() != n + 1 || plan.adjacency_version != adj.topology_version) {
    std::ostringstream s;
    s << "fair_umbrella: " << n << " positions, a plan for " << plan.nodes << " nodes and an adjacency of "
      << (adj.offset.empty() ? 0 : adj.offset.size() - 1) << " nodes do not match";
    return Status(ErrorCode::kMismatch, s.str());
  }
  if (prm.iterations < 0 || prm.substeps < 1)
    return Status(ErrorCode::kInvalidArgument, "fair_umbrella: bad iteration or sub-step count");
  if (prm.relaxation != plan.relaxation)
    return Status(ErrorCode::kInvalidArgument, "fair_umbrella: the plan was made with another relaxation");
  const std::vector<double>& inv_deg = plan.inv_deg;
  const std::vector<double>& inv_nu = plan.inv_nu;
  const std::vector<std::uint32_t>& free_nodes = plan.free_nodes;
  const std::vector<std::uint32_t>& u_nodes = plan.u_nodes;

  const bool collide = static_cast<bool>(prm.signed_distance);
  std::vector<double> lower(collide ? free_nodes.size() : 0, -std::numeric_limits<double>::infinity());
  const bool bounds_io = collide && !prm.distance_bounds.empty();
  if (bounds_io && prm.distance_bounds.size() < n)
    return Status(ErrorCode::kMismatch, "fair_umbrella: distance_bounds has " +
                                            std::to_string(prm.distance_bounds.size()) + " entries for " +
                                            std::to_string(n) + " nodes");
  if (bounds_io)
    for (std::size_t i = 0; i < free_nodes.size(); ++i) lower[i] = prm.distance_bounds[free_nodes[i]];
  std::vector<std::uint32_t> queries(collide ? free_nodes.size() : 0), refused(collide ? free_nodes.size() : 0);
  // exact[i]: lower[i] is the exact distance at the node's current position.
  std::vector<std::uint8_t> exact(collide ? free_nodes.size() : 0, 0);
  std::vector<Vec3d> u(n, Vec3d::Zero());
  // Double buffer: fixed nodes hold the same value in both, free nodes are
  // rewritten every iteration, so no copy pass is needed.
  std::vector<Vec3d> other(p.begin(), p.end());
  Vec3d* cur = p.data();
  Vec3d* nxt = other.data();
  const std::uint32_t* off = adj.offset.data();
  const std::uint32_t* nb = adj.neighbor.data();
  constexpr std::size_t kBlock = 2048;
  std::vector<double> block_max((free_nodes.size() + kBlock - 1) / kBlock);
  FairReport rep;
  ExecContext bctx = ctx;
  bctx.grain = 1;
  bctx.sequential_threshold = std::max<std::size_t>(1, ctx.sequential_threshold / kBlock);
  for (int it = 0; it < prm.iterations; ++it) {
    if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "fair_umbrella cancelled");
    par::for_each_block(ctx, u_nodes.size(), [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        const std::uint32_t v = u_nodes[i];
        Vec3d s = Vec3d::Zero();
        for (std::uint32_t k = off[v]; k < off[v + 1]; ++k) s += cur[nb[k]];
        u[v] = s * inv_deg[v] - cur[v];
      }
    });
    par::for_each_n(bctx, block_max.size(), [&](std::size_t blk) {
      double mx = 0;
      const std::size_t end = std::min(free_nodes.size(), (blk + 1) * kBlock);
      for (std::size_t i = blk * kBlock; i < end; ++i) {
        const std::uint32_t v = free_nodes[i];
        Vec3d s = Vec3d::Zero();
        for (std::uint32_t k = off[v]; k < off[v + 1]; ++k) s += u[nb[k]];
        const Vec3d step = -inv_nu[v] * (s * inv_deg[v] - u[v]);
        Vec3d q = cur[v] + step;
        if (collide) {
          const double len = step.norm();
          if (!(lower[i] - len > prm.clearance)) {
            // Near the body. The end point first: when the move neither
            // enters nor deepens the forbidden zone and cannot tunnel (every
            // point of the segment is within len/2 of an end, and both ends
            // are at least that far out), it is taken whole with one query.
            const double d_start = exact[i] ? lower[i] : prm.signed_distance(cur[v]);
            queries[i] += exact[i] ? 1 : 2;
            const double d_end = prm.signed_distance(q);
            if ((d_end >= prm.clearance || d_end >= d_start) && std::min(d_start, d_end) - 0.5 * len >= 0.0) {
              lower[i] = d_end;
              exact[i] = 1;
              mx = std::max(mx, (q - cur[v]).squaredNorm());
              nxt[v] = q;
              continue;
            }
            // Otherwise advance in sub-steps from the start and keep the last
            // admissible one.
            Vec3d last = cur[v];
            double last_d = d_start;
            bool cut = false;
            for (int k = 1; k <= prm.substeps; ++k) {
              const Vec3d t = cur[v] + step * (static_cast<double>(k) / prm.substeps);
              const double d = prm.signed_distance(t);
              ++queries[i];
              if (d < prm.clearance && d < last_d) {  // entering, or going deeper into, the forbidden zone
                cut = true;
                break;
              }
              last = t;
              last_d = d;
            }
            refused[i] += cut;
            q = last;
            lower[i] = last_d;
            exact[i] = 1;
          } else {
            lower[i] -= len;
            exact[i] = 0;
          }
        }
        mx = std::max(mx, (q - cur[v]).squaredNorm());
        nxt[v] = q;
      }
      block_max[blk] = mx;
    });
    std::swap(cur, nxt);
    rep.iterations = it + 1;
    double mx = 0;
    for (double b : block_max) mx = std::max(mx, b);  // max is exact in any order
    rep.last_max_move = std::sqrt(mx);
    if (rep.last_max_move <= prm.tolerance) break;
  }
  if (cur != p.data())
    par::for_each_n(ctx, free_nodes.size(), [&](std::size_t i) { p[free_nodes[i]] = cur[free_nodes[i]]; });
  if (bounds_io)
    for (std::size_t i = 0; i < free_nodes.size(); ++i) prm.distance_bounds[free_nodes[i]] = lower[i];
  for (std::size_t i = 0; i < queries.size(); ++i) {
    rep.distance_queries += queries[i];
    rep.refused_moves += refused[i];
  }
  return rep;
}

Expected<FairReport> fair_umbrella(Model& m, std::span<const std::uint8_t> fixed, const FairParams& prm,
                                   const ExecContext& ctx) {
  const NodeAdjacency adj = build_adjacency(m, SurfaceIdx{}, ctx);
  auto r = fair_umbrella(std::span<Vec3d>(m.nodes.position), adj, fixed, prm, ctx);
  ++m.geometry_version;
  return r;
}

}  // namespace atelier
