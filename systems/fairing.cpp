#include "systems/fairing.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
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

namespace {

/// Largest |i - j| over the rings of the free nodes of a numbering.
std::uint32_t ring_bandwidth(const NodeAdjacency& adj, std::span<const std::uint8_t> is_free,
                             std::span<const std::uint32_t> number) {
  std::uint32_t b = 0;
  for (std::size_t v = 0; v < is_free.size(); ++v) {
    if (!is_free[v]) continue;
    for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) {
      const std::uint32_t a = number[v], c = number[adj.neighbor[k]];
      b = std::max(b, a > c ? a - c : c - a);
    }
  }
  return b;
}

}  // namespace

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
  if (adj.neighbor.size() >= std::numeric_limits<std::uint32_t>::max() || n >= std::numeric_limits<std::uint32_t>::max())
    return Status(ErrorCode::kInvalidArgument, "fair_umbrella: adjacency too large for 32-bit indices");
  FairPlan plan;
  plan.nodes = n;
  plan.adjacency_version = adj.topology_version;
  plan.relaxation = prm.relaxation;
  // Roles: 2 needs U (free, or a neighbour of a free node), 1 feeds such a
  // U (position only), 0 untouched. Sequential: rings share nodes.
  std::vector<std::uint8_t> is_free(n, 0), role(n, 0);
  par::for_each_n(ctx, n, [&](std::size_t v) { is_free[v] = !fixed[v] && adj.degree(v); });
  for (std::size_t v = 0; v < n; ++v)
    if (is_free[v]) {
      role[v] = 2;
      for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) role[adj.neighbor[k]] = 2;
    }
  for (std::size_t v = 0; v < n; ++v)
    if (role[v] == 2)
      for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k)
        role[adj.neighbor[k]] = std::max<std::uint8_t>(role[adj.neighbor[k]], 1);

  // Active order: slot order, or Cuthill-McKee (breadth first from a node of
  // least valence, neighbours by increasing valence, each component in turn)
  // when that narrows the band: subdivided meshes append their new nodes, so
  // slot order can be far from local.
  std::vector<std::uint32_t> slot_order, number(n, 0);
  for (std::size_t v = 0; v < n; ++v)
    if (role[v] == 2) {
      number[v] = static_cast<std::uint32_t>(slot_order.size());
      slot_order.push_back(static_cast<std::uint32_t>(v));
    }
  std::uint32_t band = ring_bandwidth(adj, is_free, number);
  if (band > 64) {
    std::vector<std::uint32_t> cm, by_degree = slot_order;
    cm.reserve(slot_order.size());
    std::vector<std::uint8_t> seen(n, 0);
    std::stable_sort(by_degree.begin(), by_degree.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return adj.degree(a) < adj.degree(b); });
    std::vector<std::uint32_t> ring;
    for (std::uint32_t root : by_degree) {
      if (seen[root]) continue;
      seen[root] = 1;
      std::size_t head = cm.size();
      cm.push_back(root);
      while (head < cm.size()) {
        const std::uint32_t v = cm[head++];
        ring.clear();
        for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) {
          const std::uint32_t w = adj.neighbor[k];
          if (role[w] == 2 && !seen[w]) {
            seen[w] = 1;
            ring.push_back(w);
          }
        }
        std::stable_sort(ring.begin(), ring.end(),
                         [&](std::uint32_t a, std::uint32_t b) { return adj.degree(a) < adj.degree(b); });
        cm.insert(cm.end(), ring.begin(), ring.end());
      }
    }
    std::vector<std::uint32_t> cm_number(n, 0);
    for (std::size_t i = 0; i < cm.size(); ++i) cm_number[cm[i]] = static_cast<std::uint32_t>(i);
    const std::uint32_t cm_band = ring_bandwidth(adj, is_free, cm_number);
    if (cm_band < band) {
      band = cm_band;
      slot_order = std::move(cm);
      number = std::move(cm_number);
    }
  }
  plan.bandwidth = band;
  plan.local = std::move(slot_order);
  plan.active = static_cast<std::uint32_t>(plan.local.size());
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> to_local(n, kNone);
  for (std::uint32_t i = 0; i < plan.active; ++i) to_local[plan.local[i]] = i;
  for (std::size_t v = 0; v < n; ++v)
    if (role[v] == 1) {
      to_local[v] = static_cast<std::uint32_t>(plan.local.size());
      plan.local.push_back(static_cast<std::uint32_t>(v));
    }

  const std::uint32_t active = plan.active;
  plan.offset.assign(active + 1, 0);
  std::uint32_t max_degree = 0;
  for (std::uint32_t i = 0; i < active; ++i) {
    plan.offset[i + 1] = plan.offset[i] + adj.degree(plan.local[i]);
    max_degree = std::max(max_degree, adj.degree(plan.local[i]));
  }
  plan.inv_degree.assign(max_degree + 1, 0.0);
  for (std::uint32_t d = 1; d <= max_degree; ++d) plan.inv_degree[d] = 1.0 / d;
  plan.neighbor.resize(plan.offset[active]);
  par::for_each_n(ctx, active, [&](std::size_t i) {
    const std::uint32_t v = plan.local[i];
    std::uint32_t k = plan.offset[i];
    for (std::uint32_t a = adj.offset[v]; a < adj.offset[v + 1]; ++a) plan.neighbor[k++] = to_local[adj.neighbor[a]];
  });
  // The damped diagonal relaxation / nu_v (Kobbelt): nu = 1 + 1/n sum_j 1/n_j.
  plan.inv_nu.assign(active, 0.0);
  par::for_each_n(ctx, active, [&](std::size_t i) {
    if (!is_free[plan.local[i]]) return;
    double s = 0;
    for (std::uint32_t k = plan.offset[i]; k < plan.offset[i + 1]; ++k) s += 1.0 / adj.degree(adj.neighbor[k]);
    plan.inv_nu[i] = prm.relaxation / (1.0 + s * plan.inv_degree[plan.offset[i + 1] - plan.offset[i]]);
  });
  for (std::uint32_t i = 0; i < active; ++i) plan.free += plan.inv_nu[i] > 0.0;
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

namespace {

// Working positions and umbrellas: xyz plus a zero lane, so a point is two
// aligned SSE packets (or one AVX register) and the per-component arithmetic
// is exactly that of Vec3d.
using P4 = Eigen::Vector4d;

/// sum_j x[j] over a ring, in ring order (regular valence 6 unrolled).
inline P4 ring_sum(const P4* x, const std::uint32_t* nb, std::uint32_t b, std::uint32_t e) noexcept {
  if (e - b == 6) {
    const std::uint32_t* r = nb + b;
    return ((((x[r[0]] + x[r[1]]) + x[r[2]]) + x[r[3]]) + x[r[4]]) + x[r[5]];
  }
  P4 s = x[nb[b]];
  for (std::uint32_t k = b + 1; k < e; ++k) s += x[nb[k]];
  return s;
}

/// The same over a rolling window (index & mask).
inline P4 ring_sum_masked(const P4* x, const std::uint32_t* nb, std::uint32_t b, std::uint32_t e,
                          std::size_t mask) noexcept {
  if (e - b == 6) {
    const std::uint32_t* r = nb + b;
    return ((((x[r[0] & mask] + x[r[1] & mask]) + x[r[2] & mask]) + x[r[3] & mask]) + x[r[4] & mask]) + x[r[5] & mask];
  }
  P4 s = x[nb[b] & mask];
  for (std::uint32_t k = b + 1; k < e; ++k) s += x[nb[k] & mask];
  return s;
}

/// The collision test of one move (see the header): returns the admissible
/// end point and updates the node's distance bound and counters.
struct CollisionState {
  std::vector<double> lower;          // lower bound of the distance, per free node
  std::vector<std::uint8_t> exact;    // lower[i] is the exact distance at the current position
  std::vector<std::uint32_t> queries, refused;
};

Vec3d collide_move(const FairParams& prm, CollisionState& cs, std::size_t i, const Vec3d& from, const Vec3d& step) {
  const Vec3d q = from + step;
  const double len = step.norm();
  if (cs.lower[i] - len > prm.clearance) {  // 1-Lipschitz: no point of the move comes near the body
    cs.lower[i] -= len;
    cs.exact[i] = 0;
    return q;
  }
  // Near the body. The end point first: when the move neither enters nor
  // deepens the forbidden zone and cannot tunnel (every point of the segment
  // is within len/2 of an end, and both ends are at least that far out), it
  // is taken whole with one query.
  const double d_start = cs.exact[i] ? cs.lower[i] : prm.signed_distance(from);
  cs.queries[i] += cs.exact[i] ? 1 : 2;
  const double d_end = prm.signed_distance(q);
  cs.exact[i] = 1;
  if ((d_end >= prm.clearance || d_end >= d_start) && std::min(d_start, d_end) - 0.5 * len >= 0.0) {
    cs.lower[i] = d_end;
    return q;
  }
  // Otherwise advance in sub-steps from the start and keep the last
  // admissible one (seed 000 section 4.2: "subdivided into several steps").
  Vec3d last = from;
  double last_d = d_start;
  for (int k = 1; k <= prm.substeps; ++k) {
    const Vec3d t = from + step * (static_cast<double>(k) / prm.substeps);
    const double d = prm.signed_distance(t);
    ++cs.queries[i];
    if (d < prm.clearance && d < last_d) {  // entering, or going deeper into, the forbidden zone
      ++cs.refused[i];
      break;
    }
    last = t;
    last_d = d;
  }
  cs.lower[i] = last_d;
  return last;
}

}  // namespace

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
  const bool collide = static_cast<bool>(prm.signed_distance);
  const bool bounds_io = collide && !prm.distance_bounds.empty();
  if (bounds_io && prm.distance_bounds.size() < n)
    return Status(ErrorCode::kMismatch, "fair_umbrella: distance_bounds has " +
                                            std::to_string(prm.distance_bounds.size()) + " entries for " +
                                            std::to_string(n) + " nodes");
  const std::size_t nactive = plan.active, nlocal = plan.local.size();
  const std::uint32_t* local = plan.local.data();
  FairReport rep;
  if (plan.free == 0) return rep;

  // Collision state per active node (used by the free ones only).
  CollisionState cs;
  if (collide) {
    cs.lower.assign(nactive, -std::numeric_limits<double>::infinity());
    if (bounds_io)
      for (std::size_t i = 0; i < nactive; ++i)
        if (plan.inv_nu[i] > 0.0) cs.lower[i] = prm.distance_bounds[local[i]];
    cs.exact.assign(nactive, 0);
    cs.queries.assign(nactive, 0);
    cs.refused.assign(nactive, 0);
  }

  // Blocks of active nodes, a fixed partition (results are per node, the
  // partition only shapes the work). Each block computes U over its own
  // nodes widened by the bandwidth into a rolling window: U(j) is made when
  // the sweep reaches j - b and read until j + b, so a window of 2b + 1
  // entries suffices; U and U2 then cost one streaming pass over positions
  // and rings instead of two, and no array of U for the whole mesh. Wide
  // bands (poorly local meshes) use blocks as wide as the band.
  const std::size_t band = plan.bandwidth;
  std::size_t window = 1;
  while (window < 2 * band + 2) window <<= 1;
  const std::size_t block = std::max<std::size_t>(8192, 4 * band);
  const std::size_t blocks = (nactive + block - 1) / block;
  const std::size_t mask = window - 1;

  // Double buffer over the local range: nodes that do not move hold the same
  // value in both and free nodes are rewritten every iteration, so no copy
  // pass is needed. First touch by block, as the sweeps will read them.
  std::vector<P4> buf_a(nlocal), buf_b(nlocal), rings(blocks * window);
  par::for_each_block(ctx, nlocal, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) buf_a[i] = buf_b[i] = P4(p[local[i]].x(), p[local[i]].y(), p[local[i]].z(), 0.0);
  });
  P4* cur = buf_a.data();
  P4* nxt = buf_b.data();
  const std::uint32_t* off = plan.offset.data();
  const std::uint32_t* nb = plan.neighbor.data();
  const double* inv_deg = plan.inv_degree.data();
  const double* inv_nu = plan.inv_nu.data();

  std::vector<double> block_max(blocks);
  bool cancelled = false;
  // One arena for the whole run (not one per loop): the workers stay in it
  // across iterations.
  par::in_arena(ctx, [&] {
    ExecContext bctx = ctx;
    if (ctx.threads > 1) bctx.threads = 0;  // run in the enclosing arena
    bctx.grain = 1;
    bctx.sequential_threshold = std::max<std::size_t>(1, ctx.sequential_threshold / block);
    for (int it = 0; it < prm.iterations; ++it) {
      if (ctx.cancelled()) {
        cancelled = true;
        return;
      }
      par::for_each_n(bctx, blocks, [&](std::size_t blk) {
        P4* u = rings.data() + blk * window;
        const std::size_t b = blk * block, e = std::min(nactive, b + block);
        std::size_t next_u = b > band ? b - band : 0;  // next U to make
        const std::size_t u_end = std::min(nactive, e + band);
        double mx = 0;
        for (std::size_t i = b; i < e; ++i) {
          // U(p) = 1/n sum_j p_j - p (seed 000 section 4.2) up to i + b.
          for (const std::size_t last = std::min(u_end, i + band + 1); next_u < last; ++next_u) {
            const std::uint32_t k0 = off[next_u], k1 = off[next_u + 1];
            u[next_u & mask] = ring_sum(cur, nb, k0, k1) * inv_deg[k1 - k0] - cur[next_u];
          }
          if (!(inv_nu[i] > 0.0)) continue;  // not free
          // p <- p - w U2(p) / nu, U2 = 1/n sum_j U(p_j) - U(p).
          const std::uint32_t k0 = off[i], k1 = off[i + 1];
          const P4 step = -inv_nu[i] * (ring_sum_masked(u, nb, k0, k1, mask) * inv_deg[k1 - k0] - u[i & mask]);
          P4 q = cur[i] + step;
          if (collide) {
            const Vec3d q3 = collide_move(prm, cs, i, cur[i].head<3>(), step.head<3>());
            q = P4(q3.x(), q3.y(), q3.z(), 0.0);
          }
          const double dx = q.x() - cur[i].x(), dy = q.y() - cur[i].y(), dz = q.z() - cur[i].z();
          mx = std::max(mx, dx * dx + dy * dy + dz * dz);
          nxt[i] = q;
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
  });
  if (cancelled) return Status(ErrorCode::kCancelled, "fair_umbrella cancelled");
  par::for_each_n(ctx, nactive, [&](std::size_t i) {
    if (inv_nu[i] > 0.0) p[local[i]] = cur[i].head<3>();
  });
  if (collide) {
    for (std::size_t i = 0; i < nactive; ++i) {
      if (bounds_io && inv_nu[i] > 0.0) prm.distance_bounds[local[i]] = cs.lower[i];
      rep.distance_queries += cs.queries[i];
      rep.refused_moves += cs.refused[i];
    }
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
