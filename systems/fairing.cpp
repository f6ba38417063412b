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

Expected<FairReport> fair_umbrella(std::span<Vec3d> p, const NodeAdjacency& adj, std::span<const std::uint8_t> fixed,
                                   const FairParams& prm, const ExecContext& ctx) {
  const std::size_t n = p.size();
  if (adj.offset.size() != n + 1 || fixed.size() != n) {
    std::ostringstream s;
    s << "fair_umbrella: " << n << " positions, " << fixed.size() << " fixed flags and an adjacency of "
      << (adj.offset.empty() ? 0 : adj.offset.size() - 1) << " nodes do not match";
    return Status(ErrorCode::kMismatch, s.str());
  }
  if (prm.iterations < 0 || prm.substeps < 1) return Status(ErrorCode::kInvalidArgument, "fair_umbrella: bad iteration or sub-step count");
  // The diagonal nu_v (Kobbelt): 1 + 1/n sum_j 1/n_j.
  std::vector<double> inv_nu(n, 0.0);
  std::vector<std::uint32_t> free_nodes;
  for (std::size_t v = 0; v < n; ++v) {
    const std::uint32_t d = adj.degree(v);
    if (fixed[v] || d == 0) continue;
    double s = 0;
    for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) {
      const std::uint32_t dj = adj.degree(adj.neighbor[k]);
      s += dj ? 1.0 / dj : 0.0;
    }
    inv_nu[v] = 1.0 / (1.0 + s / d);
    free_nodes.push_back(static_cast<std::uint32_t>(v));
  }
  const bool collide = static_cast<bool>(prm.signed_distance);
  // Lower bounds of each free node's signed distance (1-Lipschitz bookkeeping).
  std::vector<double> lower(collide ? free_nodes.size() : 0, -std::numeric_limits<double>::infinity());
  std::vector<Vec3d> u, next(free_nodes.size());
  std::vector<double> moved(free_nodes.size());
  std::vector<std::uint32_t> queries(free_nodes.size()), refused(free_nodes.size());
  FairReport rep;
  for (int it = 0; it < prm.iterations; ++it) {
    if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "fair_umbrella cancelled");
    umbrella(p, adj, u, ctx);
    par::for_each_n(ctx, free_nodes.size(), [&](std::size_t i) {
      const std::uint32_t v = free_nodes[i];
      const Vec3d step = -inv_nu[v] * umbrella2_at(v, adj, u);
      const double len = step.norm();
      Vec3d q = p[v] + step;
      if (collide) {
        if (!(lower[i] - len > prm.clearance)) {
          // Near the body: advance in sub-steps from the exact distance of
          // the start, keep the last admissible one.
          Vec3d last = p[v];
          double last_d = prm.signed_distance(p[v]);
          ++queries[i];
          bool cut = false;
          for (int s = 1; s <= prm.substeps; ++s) {
            const Vec3d t = p[v] + step * (static_cast<double>(s) / prm.substeps);
            const double d = prm.signed_distance(t);
            ++queries[i];
            if (d < prm.clearance && d < last_d) {  // entering (or deeper into) the forbidden zone
              cut = true;
              break;
            }
            last = t;
            last_d = d;
          }
          refused[i] += cut;
          q = last;
          lower[i] = last_d;
        } else {
          lower[i] -= len;
        }
      }
      next[i] = q;
      moved[i] = (q - p[v]).norm();
    });
    par::for_each_n(ctx, free_nodes.size(), [&](std::size_t i) { p[free_nodes[i]] = next[i]; });
    rep.iterations = it + 1;
    rep.last_max_move = par::transform_reduce(
        ctx, moved.size(), 0.0, [&](std::size_t i) { return moved[i]; }, [](double a, double b) { return std::max(a, b); });
    if (rep.last_max_move <= prm.tolerance) break;
  }
  for (std::size_t i = 0; i < free_nodes.size(); ++i) {
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
