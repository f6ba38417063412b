#include <atelier/engine/math.h>
#include <atelier/systems/garment/collision_pass.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include <atelier/engine/parallel.h>

namespace atelier {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string vec_str(const Vec3d& p) {
  std::ostringstream s;
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

}  // namespace

// ------------------------------------------------------------ encoding

Expected<ClearanceEncoding> encode_clearance(std::span<const Vec3d> garment, const CollisionBody& source,
                                             const ExecContext& ctx) {
  if (garment.empty()) return Status(ErrorCode::kInvalidArgument, "encode_clearance: empty garment");
  if (source.empty()) return Status(ErrorCode::kInvalidArgument, "encode_clearance: collision body not built");
  for (std::size_t v = 0; v < garment.size(); ++v)
    if (!is_finite(garment[v]))
      return Status(ErrorCode::kDegenerate,
                    "encode_clearance: garment vertex " + std::to_string(v) + " is " + vec_str(garment[v]));
  ExecContext qctx = ctx;
  qctx.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 256);
  if (ctx.grain == 0) qctx.grain = 64;
  ClearanceEncoding enc;
  enc.clearance.resize(garment.size());
  enc.triangle.resize(garment.size());
  par::for_each_n(qctx, garment.size(), [&](std::size_t v) {
    const BodyDistance d = source.query(garment[v]);
    enc.clearance[v] = static_cast<float>(d.distance);
    enc.triangle[v] = d.triangle;
  });
  return enc;
}

// ------------------------------------------------------------ the pass

namespace {

Status check_params(const CollisionParams& p) {
  if (!(p.min_clearance >= 0) || !(p.max_clearance >= p.min_clearance) || !(p.tolerance >= 0) || p.push_rounds < 1 ||
      p.fair_rings < 0 || p.fair_iterations < 0 || p.substeps < 1 || !(p.layer_gap >= 0))
    return Status(ErrorCode::kInvalidArgument,
                  "collision pass: bad parameters (need 0 <= min_clearance <= max_clearance, tolerance >= 0, "
                  "push_rounds >= 1, fair_rings >= 0, fair_iterations >= 0, substeps >= 1, layer_gap >= 0)");
  return Status::ok();
}

/// Layer floor at a body point: the inner layers' clearance at the corners
/// of its triangle (barycentric when all three are covered, else the
/// largest covered corner).
double floor_at(std::span<const double> floor, const CollisionBody& body, const BodyDistance& d) {
  if (floor.empty()) return -kInf;
  const Triangle& tr = body.topology().triangles()[d.triangle];
  double mx = -kInf, s = 0;
  bool all = true;
  for (int k = 0; k < 3; ++k) {
    const double f = floor[tr[k]];
    mx = std::max(mx, f);
    all = all && f > -kInf;
    s += d.barycentric[k] * f;
  }
  return all ? s : mx;
}

Expected<CollisionReport> resolve_impl(std::span<Vec3d> g, const NodeAdjacency& adj, const ClearanceEncoding& enc,
                                       const CollisionBody& body, const CollisionParams& prm,
                                       std::span<const double> floor, std::vector<BodyDistance>* final_out,
                                       const ExecContext& ctx) {
  const std::size_t n = g.size();
  if (n == 0) return Status(ErrorCode::kInvalidArgument, "resolve_collisions: empty garment");
  if (body.empty()) return Status(ErrorCode::kInvalidArgument, "resolve_collisions: collision body not built");
  if (Status s = check_params(prm); !s) return s;
  if (enc.clearance.size() != n || (!enc.triangle.empty() && enc.triangle.size() != n) || adj.offset.size() != n + 1) {
    std::ostringstream s;
    s << "resolve_collisions: " << n << " garment vertices, " << enc.clearance.size() << " clearances, "
      << enc.triangle.size() << " hints and an adjacency of " << (adj.offset.empty() ? 0 : adj.offset.size() - 1)
      << " vertices do not match";
    return Status(ErrorCode::kMismatch, s.str());
  }
  const std::size_t nt = body.topology().triangles().size();
  for (std::size_t v = 0; v < n; ++v) {
    if (!is_finite(g[v]))
      return Status(ErrorCode::kDegenerate,
                    "resolve_collisions: garment vertex " + std::to_string(v) + " is " + vec_str(g[v]));
    if (!enc.triangle.empty() && enc.triangle[v] >= nt && enc.triangle[v] != kNoTriangle)
      return Status(ErrorCode::kMismatch,
                    "resolve_collisions: hint of vertex " + std::to_string(v) + " is not a triangle of this body");
  }
  // Per-vertex work here is exact body queries (microseconds each): split
  // much smaller loops than the default threshold assumes.
  ExecContext qctx = ctx;
  qctx.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 256);
  if (ctx.grain == 0) qctx.grain = 64;
  CollisionReport rep;
  rep.vertices = n;
  std::vector<BodyDistance> d(n);
  std::vector<double> target(n);
  std::vector<std::uint32_t> queries(n, 0);
  // exact[v]: d[v] is the exact query; otherwise d[v].distance is a positive
  // lower bound at or above the target (see the check after fairing) and
  // the rest of d[v] is that of the vertex's previous position.
  std::vector<std::uint8_t> exact(n, 1);
  // Every vertex's exact distance, by clusters of neighbours (one traversal
  // per cluster, each vertex bounded by its hint).
  if (Status s = body.query_many(g, enc.triangle, d, qctx); !s) return s;
  par::for_each_n(qctx, n, [&](std::size_t v) {
    queries[v] = 1;
    target[v] = std::clamp(static_cast<double>(enc.clearance[v]), prm.min_clearance, prm.max_clearance);
    // The tolerance is added to the layer target: the pass leaves vertices
    // up to `tolerance` below their target, and an outer layer left there
    // would lie on, or under, the inner one (issue 26, outfit_test.cpp).
    if (!floor.empty())
      target[v] = std::max(target[v], floor_at(floor, body, d[v]) + prm.layer_gap + prm.tolerance);
  });
  std::vector<std::uint8_t> moved(n, 0);
  const std::vector<Vec3d> entry(g.begin(), g.end());  // the fairing smooths displacements from here
  for (std::size_t v = 0; v < n; ++v) {
    rep.inside_before += d[v].distance < 0;
    rep.below_before += d[v].distance < target[v] - prm.tolerance;
    rep.max_depth_before = std::max(rep.max_depth_before, -d[v].distance);
  }
  // Push (issue 7): out along the outward normal at the closest point to the
  // target clearance; a push landing short (concave body, another limb) is
  // redone from the new closest point; the better of start and end is kept,
  // so no vertex ends deeper than it started.
  // A vertex inside always moves, at least a hair off the surface (so that a
  // zero clearance does not leave it on the sign's knife edge).
  auto must_move = [&](std::size_t v) { return d[v].distance < 0 || d[v].distance < target[v] - prm.tolerance; };
  par::for_each_n(qctx, n, [&](std::size_t v) {
    if (!must_move(v)) return;
    const Vec3d start = g[v];
    const BodyDistance d0 = d[v];
    const double level = std::max(target[v], 1e-5);
    for (int r = 0; r < prm.push_rounds && must_move(v); ++r) {
      g[v] = d[v].closest + level * d[v].normal;
      d[v] = body.query(g[v], d[v].triangle);
      ++queries[v];
    }
    if (d[v].distance < d0.distance) {
      g[v] = start;
      d[v] = d0;
    } else {
      moved[v] = 1;
    }
  });
  // Free region: the moved vertices and `fair_rings` rings around them.
  std::vector<std::uint8_t> free_flag(moved);
  std::vector<std::uint32_t> front;
  for (std::size_t v = 0; v < n; ++v)
    if (moved[v]) front.push_back(static_cast<std::uint32_t>(v));
  rep.pushed = front.size();
  for (int ring = 0; ring < prm.fair_rings && !front.empty(); ++ring) {
    std::vector<std::uint32_t> next;
    for (std::uint32_t v : front)
      for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) {
        const std::uint32_t w = adj.neighbor[k];
        if (!free_flag[w]) {
          free_flag[w] = 1;
          next.push_back(w);
        }
      }
    front = std::move(next);
  }
  std::vector<std::uint32_t> free_nodes;
  for (std::size_t v = 0; v < n; ++v)
    if (free_flag[v] && adj.offset[v + 1] > adj.offset[v]) free_nodes.push_back(static_cast<std::uint32_t>(v));
  rep.faired = free_nodes.size();
  // Restricted umbrella fairing (seed 000 section 4.2; Kobbelt's U2 Jacobi
  // step p <- p - U2(p)/nu as in systems/fairing.h) of the free region, the
  // others fixed; every move is tested in sub-steps against the vertex's own
  // target clearance and cut at its last admissible sub-step (seed 000 Fig.
  // 16 tests against the body alone).
  if (prm.fair_iterations > 0 && !free_nodes.empty()) {
    // The region in local, contiguous arrays: the free nodes F and the
    // nodes U whose umbrella they need (F and its neighbours). Outside F the
    // garment never moves, so its displacement from `entry` is zero and a
    // U node's umbrella sums only its free neighbours.
    const std::size_t nf = free_nodes.size();
    std::vector<std::uint32_t> local(n, kNone);  // vertex -> index in U
    std::vector<std::uint32_t> u_nodes;
    for (std::uint32_t v : free_nodes) {
      if (local[v] == kNone) local[v] = static_cast<std::uint32_t>(u_nodes.size()), u_nodes.push_back(v);
      for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) {
        const std::uint32_t w = adj.neighbor[k];
        if (local[w] == kNone && adj.offset[w + 1] > adj.offset[w])
          local[w] = static_cast<std::uint32_t>(u_nodes.size()), u_nodes.push_back(w);
      }
    }
    std::vector<std::uint32_t> free_index(n, kNone);  // vertex -> index in F
    for (std::size_t i = 0; i < nf; ++i) free_index[free_nodes[i]] = static_cast<std::uint32_t>(i);
    const std::size_t nu = u_nodes.size();
    // U node i: its free neighbours (F indices) and whether it is free.
    std::vector<std::uint32_t> uf_offset(nu + 1, 0), uf_list, u_self(nu);
    std::vector<double> u_inv_deg(nu);
    for (std::size_t i = 0; i < nu; ++i) {
      const std::uint32_t v = u_nodes[i];
      for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k)
        if (free_index[adj.neighbor[k]] != kNone) uf_list.push_back(free_index[adj.neighbor[k]]);
      uf_offset[i + 1] = static_cast<std::uint32_t>(uf_list.size());
      u_self[i] = free_index[v];
      u_inv_deg[i] = 1.0 / (adj.offset[v + 1] - adj.offset[v]);
    }
    // F node i: its U index and its neighbours' U indices.
    std::vector<std::uint32_t> fu_self(nf), fu_offset(nf + 1, 0), fu_list;
    std::vector<double> inv_nu(nf);
    for (std::size_t i = 0; i < nf; ++i) {
      const std::uint32_t v = free_nodes[i];
      fu_self[i] = local[v];
      double s = 0;
      for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) {
        fu_list.push_back(local[adj.neighbor[k]]);
        s += u_inv_deg[local[adj.neighbor[k]]];
      }
      fu_offset[i + 1] = static_cast<std::uint32_t>(fu_list.size());
      inv_nu[i] = 1.0 / (1.0 + s * u_inv_deg[local[v]]);
    }
    // Moves are along the body normal n at the closest point x, so to first
    // order the signed distance is (p - x).n + d_x: sub-steps are tested on
    // that tangent plane (no body query per sub-step), and the end state is
    // verified exactly below.
    std::vector<Vec3d> u(nu), disp(nf), next(nf), start(nf);
    std::vector<double> lin(nf), next_lin(nf);
    for (std::size_t i = 0; i < nf; ++i) {
      const std::uint32_t v = free_nodes[i];
      start[i] = g[v];
      disp[i] = g[v] - entry[v];
      lin[i] = d[v].distance;
    }
    std::vector<std::uint32_t> refused(nf, 0);
    // A fairing sweep costs nanoseconds per vertex on these local arrays:
    // only regions of thousands of vertices are worth splitting, in blocks
    // that amortise the task overhead.
    const double inv_substeps = 1.0 / prm.substeps;
    ExecContext fctx = ctx;
    fctx.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 4096);
    if (ctx.grain == 0) fctx.grain = 1024;
    for (int it = 0; it < prm.fair_iterations; ++it) {
      if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "resolve_collisions cancelled");
      par::for_each_n(fctx, nu, [&](std::size_t i) {
        Vec3d s = Vec3d::Zero();
        for (std::uint32_t k = uf_offset[i]; k < uf_offset[i + 1]; ++k) s += disp[uf_list[k]];
        u[i] = s * u_inv_deg[i] - (u_self[i] != kNone ? disp[u_self[i]] : Vec3d::Zero());
      });
      par::for_each_n(fctx, nf, [&](std::size_t i) {
        const std::uint32_t v = free_nodes[i];
        Vec3d s = Vec3d::Zero();
        for (std::uint32_t k = fu_offset[i]; k < fu_offset[i + 1]; ++k) s += u[fu_list[k]];
        // Half a Jacobi step: U2 is not diagonally dominant, and on the open
        // boundary of a garment (degree 2-3) full Jacobi steps diverge.
        // Only the component along the body normal is kept: the pass smooths
        // the garment's offset from the body (the bump left by the push), and
        // tangential moves would slide open hems along the body (a free
        // boundary shrinks under U2 fairing) and add strain.
        const Vec3d& nrm = d[v].normal;
        const double along = nrm.dot(-0.5 * inv_nu[i] * (s * u_inv_deg[fu_self[i]] - u[fu_self[i]]));
        // The last admissible sub-step: one that does not enter, or go
        // deeper into, the forbidden zone (below the target).
        const double step = along * inv_substeps;
        double reached = lin[i];
        int taken = 0;
        for (int k = 1; k <= prm.substeps; ++k) {
          const double dk = lin[i] + step * k;
          if (dk < target[v] && dk < reached) {
            ++refused[i];
            break;
          }
          reached = dk;
          taken = k;
        }
        next[i] = disp[i] + nrm * (step * taken);
        next_lin[i] = reached;
      });
      std::swap(disp, next);
      std::swap(lin, next_lin);
    }
    for (std::size_t i = 0; i < nf; ++i) g[free_nodes[i]] = entry[free_nodes[i]] + disp[i];
    // Exact check of the faired vertices: one that ended deeper than both
    // its target and its pre-fairing distance (curvature beyond the tangent
    // plane) goes back to where the push left it.
    par::for_each_n(qctx, free_nodes.size(), [&](std::size_t i) {
      const std::uint32_t v = free_nodes[i];
      // A vertex that fairing moved by less than its margin over the target
      // is still above it (1-Lipschitz distance): no query.
      const double bound = d[v].distance - (g[v] - start[i]).norm();
      if (bound > 0 && bound >= target[v] - prm.tolerance) {
        d[v].distance = bound;
        exact[v] = 0;
        return;
      }
      const BodyDistance q = body.query(g[v], d[v].triangle);
      ++queries[v];
      if (q.distance < target[v] - prm.tolerance && q.distance < d[v].distance) {
        g[v] = start[i];
        ++refused[i];
      } else {
        d[v] = q;
      }
    });
    for (auto r : refused) rep.refused_moves += r;
  }
  if (final_out)
    par::for_each_n(qctx, n, [&](std::size_t v) {
      if (exact[v]) return;
      d[v] = body.query(g[v], d[v].triangle);
      ++queries[v];
    });
  for (std::size_t v = 0; v < n; ++v) {
    rep.queries += queries[v];
    rep.inside_after += d[v].distance < 0;
    rep.below_after += d[v].distance < target[v] - prm.tolerance;
    rep.max_depth_after = std::max(rep.max_depth_after, -d[v].distance);
  }
  if (final_out) *final_out = std::move(d);
  return rep;
}

}  // namespace

Expected<CollisionReport> resolve_collisions(std::span<Vec3d> garment, const NodeAdjacency& adjacency,
                                             const ClearanceEncoding& encoding, const CollisionBody& body,
                                             const CollisionParams& params, const ExecContext& ctx) {
  return resolve_impl(garment, adjacency, encoding, body, params, {}, nullptr, ctx);
}

Expected<CollisionReport> resolve_collisions(std::span<Vec3d> garment, const NodeAdjacency& adjacency,
                                             const ClearanceEncoding& encoding, const CollisionBody& body,
                                             const CollisionParams& params, std::vector<BodyDistance>& final_distance,
                                             const ExecContext& ctx) {
  return resolve_impl(garment, adjacency, encoding, body, params, {}, &final_distance, ctx);
}

Expected<std::vector<CollisionReport>> resolve_layers(std::span<GarmentLayer> layers, const CollisionBody& body,
                                                      const CollisionParams& params, const ExecContext& ctx) {
  if (body.empty()) return Status(ErrorCode::kInvalidArgument, "resolve_layers: collision body not built");
  for (std::size_t i = 0; i < layers.size(); ++i)
    if (!layers[i].adjacency || !layers[i].encoding)
      return Status(ErrorCode::kInvalidArgument,
                    "resolve_layers: layer " + std::to_string(i) + " has no adjacency or encoding");
  std::vector<std::size_t> order(layers.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return layers[a].z_depth < layers[b].z_depth; });
  const CollisionTopology& topo = body.topology();
  const auto tris = topo.triangles();
  std::vector<double> floor;  // per body point: clearance of the inner layers (-inf: none)
  std::vector<CollisionReport> reps(layers.size());
  std::vector<BodyDistance> fin;
  for (std::size_t i : order) {
    GarmentLayer& L = layers[i];
    auto r = resolve_impl(L.positions, *L.adjacency, *L.encoding, body, params, floor, &fin, ctx);
    if (!r) return Status(r.status().code(), "layer " + std::to_string(i) + ": " + r.status().message());
    reps[i] = *r;
    if (L.final_distance) *L.final_distance = fin;
    // Splat this layer's clearances on the corners of the triangles under
    // it, then widen by one ring of body points so that outer vertices
    // between the inner layer's vertices are covered.
    if (floor.empty()) floor.assign(topo.point_count(), -kInf);
    std::vector<double> splat(topo.point_count(), -kInf);
    for (const BodyDistance& q : fin)
      for (std::uint32_t c : tris[q.triangle]) splat[c] = std::max(splat[c], q.distance);
    std::vector<double> wide(splat);
    for (std::size_t t = 0; t < tris.size(); ++t) {
      const double m = std::max({splat[tris[t][0]], splat[tris[t][1]], splat[tris[t][2]]});
      for (std::uint32_t c : tris[t]) wide[c] = std::max(wide[c], m);
    }
    for (std::size_t c = 0; c < floor.size(); ++c) floor[c] = std::max(floor[c], wide[c]);
  }
  return reps;
}

}  // namespace atelier
