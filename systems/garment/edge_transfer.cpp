#include <atelier/engine/parallel.h>
#include <atelier/systems/garment/edge_transfer.h>
#include <atelier/systems/mesh/normals.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cmath>
#include <string>

#include "edge_transfer_detail.h"

namespace atelier {

void EdgeTransferSolver::solve(std::span<const Vec3d> b, std::span<Vec3d> x, std::vector<Vec3d>& y) const {
  const std::size_t n = inv_d.size();
  y.resize(n);
  for (std::size_t i = 0; i < n; ++i) y[perm[i]] = b[i];
  for (std::size_t j = 0; j < n; ++j) {  // L y' = y, by columns
    const Vec3d yj = y[j];
    for (int k = col_start[j]; k < col_start[j + 1]; ++k) y[row[k]] -= value[k] * yj;
  }
  for (std::size_t j = 0; j < n; ++j) y[j] *= inv_d[j];
  for (std::size_t j = n; j-- > 0;) {  // L^T x' = y', column j of L is row j of L^T
    Vec3d s = y[j];
    for (int k = col_start[j]; k < col_start[j + 1]; ++k) s -= value[k] * y[row[k]];
    y[j] = s;
  }
  for (std::size_t i = 0; i < n; ++i) x[i] = y[perm[i]];
}

Expected<EdgeTransfer> encode_edge_transfer(std::span<const Vec3d> source,
                                            std::span<const std::array<std::uint32_t, 2>> edges,
                                            const CollisionBody& body, const EdgeTransferParams& params,
                                            const ExecContext& ctx) {
  const std::size_t n = source.size();
  if (n == 0) return Status(ErrorCode::kInvalidArgument, "edge transfer: empty garment");
  if (body.empty()) return Status(ErrorCode::kInvalidArgument, "edge transfer: source body not built");
  if (!(params.anchor > 0) || !std::isfinite(params.anchor))
    return Status(ErrorCode::kInvalidArgument, "edge transfer: anchor must be positive");
  if (params.length_iterations < 0 || params.length_sweeps < 0 || params.anderson_window < 0 ||
      !(params.length_tolerance >= 0))
    return Status(ErrorCode::kInvalidArgument,
                  "edge transfer: length iterations, sweeps, Anderson window and tolerance must not be negative");
  for (std::size_t v = 0; v < n; ++v)
    if (!is_finite(source[v]))
      return Status(ErrorCode::kDegenerate, "edge transfer: garment vertex " + std::to_string(v) + " is not finite");
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (edges[e][0] >= n || edges[e][1] >= n || edges[e][0] == edges[e][1])
      return Status(ErrorCode::kInvalidArgument, "edge transfer: edge " + std::to_string(e) + " (" +
                                                     std::to_string(edges[e][0]) + ", " + std::to_string(edges[e][1]) +
                                                     ") is not an edge of " + std::to_string(n) + " vertices");
  EdgeTransfer t;
  t.vertices = n;
  t.length_iterations = params.length_iterations;
  t.length_sweeps = params.length_sweeps;
  t.anderson_window = params.anderson_window;
  t.length_tolerance = params.length_tolerance;
  t.edges.assign(edges.begin(), edges.end());
  const std::size_t ne = edges.size();
  t.triangle.assign(ne, kNoTriangle);
  t.coefficient.assign(ne, Vec3d::Zero());
  t.weight.assign(ne, 0.0);
  const auto tris = body.topology().triangles();
  const auto pos = body.positions();
  par::for_each_n(ctx, ne, [&](std::size_t e) {
    const Vec3d& a = source[edges[e][0]];
    const Vec3d& b = source[edges[e][1]];
    const double l2 = (b - a).squaredNorm();
    if (!(l2 > 0)) return;
    const std::uint32_t tri = body.query(0.5 * (a + b)).triangle;
    if (tri == kNoTriangle) return;
    const Mat3d m = triangle_basis(pos, tris[tri]);
    const Eigen::FullPivLU<Mat3d> lu(m);  // a zero-area triangle (zero normal) is not invertible
    if (!lu.isInvertible()) return;
    t.triangle[e] = tri;
    t.coefficient[e] = lu.solve(b - a);
    t.weight[e] = 1.0 / l2;
  });
  // a_v = anchor * mean weight of v's edges (1 for a vertex without any:
  // it keeps its decoded position).
  std::vector<double> wsum(n, 0.0);
  std::vector<std::uint32_t> deg(n, 0);
  for (std::size_t e = 0; e < ne; ++e)
    for (std::uint32_t v : edges[e]) {
      wsum[v] += t.weight[e];
      deg[v] += t.weight[e] > 0;
    }
  t.residual_scale.assign(n, 0.0);
  for (std::size_t e = 0; e < ne; ++e)
    if (t.weight[e] > 0)
      for (std::uint32_t v : edges[e]) t.residual_scale[v] = std::max(t.residual_scale[v], std::sqrt(t.weight[e]));
  t.anchor.resize(n);
  for (std::size_t v = 0; v < n; ++v) t.anchor[v] = deg[v] > 0 ? params.anchor * wsum[v] / deg[v] : 1.0;
  t.inv_diagonal.resize(n);
  for (std::size_t v = 0; v < n; ++v) t.inv_diagonal[v] = 1.0 / (t.anchor[v] + wsum[v]);
  t.vertex_edge_offset.assign(n + 1, 0);
  for (std::size_t e = 0; e < ne; ++e)
    if (t.weight[e] > 0)
      for (std::uint32_t v : edges[e]) ++t.vertex_edge_offset[v + 1];
  for (std::size_t v = 0; v < n; ++v) t.vertex_edge_offset[v + 1] += t.vertex_edge_offset[v];
  t.vertex_edge.resize(t.vertex_edge_offset[n]);
  {
    std::vector<std::uint32_t> fill(t.vertex_edge_offset.begin(), t.vertex_edge_offset.end() - 1);
    for (std::size_t e = 0; e < ne; ++e)
      if (t.weight[e] > 0)
        for (std::uint32_t v : edges[e]) t.vertex_edge[fill[v]++] = static_cast<std::uint32_t>(e);
  }
  // Normal matrix D^T W D + A.
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(4 * ne + n);
  for (std::size_t e = 0; e < ne; ++e) {
    const double w = t.weight[e];
    if (w == 0) continue;
    const auto [i, j] = edges[e];
    trip.emplace_back(i, i, w);
    trip.emplace_back(j, j, w);
    trip.emplace_back(i, j, -w);
    trip.emplace_back(j, i, -w);
  }
  for (std::size_t v = 0; v < n; ++v) trip.emplace_back(v, v, t.anchor[v]);
  Eigen::SparseMatrix<double> a(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  a.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(a);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0).all())
    return Status(ErrorCode::kDegenerate, "edge transfer: the normal matrix does not factor");
  auto solver = std::make_shared<EdgeTransferSolver>();
  const Eigen::SparseMatrix<double>& l = ldlt.matrixL().nestedExpression();
  solver->col_start.assign(l.outerIndexPtr(), l.outerIndexPtr() + n + 1);
  const auto nnz = static_cast<std::size_t>(solver->col_start[n]);
  solver->row.assign(l.innerIndexPtr(), l.innerIndexPtr() + nnz);
  solver->value.assign(l.valuePtr(), l.valuePtr() + nnz);
  solver->inv_d.resize(n);
  for (std::size_t i = 0; i < n; ++i) solver->inv_d[i] = 1.0 / ldlt.vectorD()[static_cast<Eigen::Index>(i)];
  solver->perm.assign(ldlt.permutationP().indices().data(), ldlt.permutationP().indices().data() + n);
  t.solver = std::move(solver);
  return t;
}

namespace {

// The right-hand side D^T W T + A d, gathered per vertex in a fixed order.
void rhs_of(const EdgeTransfer& t, std::span<const Vec3d> decoded, std::span<const Vec3d> target,
            std::vector<Vec3d>& rhs) {
  rhs.resize(t.vertices);
  for (std::size_t v = 0; v < t.vertices; ++v) rhs[v] = t.anchor[v] * decoded[v];
  for (std::size_t e = 0; e < t.edges.size(); ++e) {
    if (t.weight[e] == 0) continue;
    const Vec3d f = t.weight[e] * target[e];
    rhs[t.edges[e][1]] += f;
    rhs[t.edges[e][0]] -= f;
  }
}

// The local step: every target turned to its edge's current direction,
// keeping its length. Returns the edge part of the energy at x,
// sum_e w_e (|x_j - x_i| - L_e)^2 (what the turned targets leave).
double turn_targets(const EdgeTransfer& t, std::span<const Vec3d> x, std::span<const double> length,
                    std::span<Vec3d> target) {
  double energy = 0;
  for (std::size_t e = 0; e < t.edges.size(); ++e) {
    if (t.weight[e] == 0) continue;
    const Vec3d cur = x[t.edges[e][1]] - x[t.edges[e][0]];
    const double l2 = cur.squaredNorm();
    if (l2 > 0) {
      const double l = std::sqrt(l2);
      target[e] = (length[e] / l) * cur;
      energy += t.weight[e] * (l - length[e]) * (l - length[e]);
    } else {
      energy += t.weight[e] * length[e] * length[e];
    }
  }
  return energy;
}

// One Gauss-Seidel sweep of the global step in vertex order, in place: each
// vertex moves to the minimum of the energy with its neighbours fixed.
void gauss_seidel_sweep(const EdgeTransfer& t, std::span<const Vec3d> decoded, std::span<const Vec3d> target,
                        std::span<Vec3d> x) {
  for (std::size_t v = 0; v < t.vertices; ++v) {
    Vec3d s = t.anchor[v] * decoded[v];
    for (std::uint32_t k = t.vertex_edge_offset[v]; k < t.vertex_edge_offset[v + 1]; ++k) {
      const std::uint32_t e = t.vertex_edge[k];
      const auto [i, j] = t.edges[e];
      // v = j: x_j = x_i + T_e; v = i: x_i = x_j - T_e.
      const double w = t.weight[e];
      s += v == j ? Vec3d(w * x[i] + w * target[e]) : Vec3d(w * x[j] - w * target[e]);
    }
    x[v] = s * t.inv_diagonal[v];
  }
}

// The length iterations as a fixed-point problem x = G(x), G = one local
// step then one Gauss-Seidel sweep, accelerated by Anderson's method
// (Walker & Ni 2011, type II, window m) with the energy safeguard of Peng
// et al. 2018 ("Anderson acceleration for geometry optimization and physics
// simulation", Algorithm 1): the extrapolated point
//   x_AA = G(x_k) - sum_j gamma_j (G(x_j+1) - G(x_j)),
//   gamma = argmin |f_k - sum_j gamma_j (f_j+1 - f_j)|,  f = G(x) - x,
// is kept only when it lowers the energy E(x) = sum_e w_e (|x_j - x_i| -
// L_e)^2 + sum_v a_v |x_v - d_v|^2 below that of x_k (a plain step never
// raises it); otherwise the plain step G(x_k) is taken and the history
// cleared. It stops when a plain step's moves, each over the shortest rest
// length at its vertex (the strain the step still changes), have an RMS of
// at most length_tolerance, or after length_iterations steps; it ends on a
// plain step's result.
// Sequential, in a fixed order: the same bits for any thread count.
void accelerated_length_iterations(const EdgeTransfer& t, std::span<const Vec3d> decoded,
                                   std::span<const double> length, std::span<Vec3d> target, std::vector<Vec3d>& x) {
  const std::size_t n = t.vertices;
  const std::size_t m = static_cast<std::size_t>(std::max(0, t.anderson_window));
  const double tol2 = t.length_tolerance * t.length_tolerance * static_cast<double>(n);
  auto anchor_energy = [&](std::span<const Vec3d> y) {
    double s = 0;
    for (std::size_t v = 0; v < n; ++v) s += t.anchor[v] * (y[v] - decoded[v]).squaredNorm();
    return s;
  };
  std::vector<Vec3d> g(n), f(n), g_prev(n), f_prev(n);
  std::vector<Vec3d> dg(m * n), df(m * n);  // ring of m columns of n vertices
  Eigen::MatrixXd gram(std::max<std::size_t>(m, 1), std::max<std::size_t>(m, 1));
  std::size_t cols = 0, next = 0;  // columns held, slot of the next one
  bool have_prev = false;
  double energy = turn_targets(t, x, length, target) + anchor_energy(x);
  for (int it = 0; it < t.length_iterations; ++it) {
    std::copy(x.begin(), x.end(), g.begin());
    gauss_seidel_sweep(t, decoded, target, g);
    double residual = 0;  // sum over vertices of (|f_v| / shortest rest length at v)^2
    for (std::size_t v = 0; v < n; ++v) {
      f[v] = g[v] - x[v];
      residual += f[v].squaredNorm() * (t.residual_scale[v] * t.residual_scale[v]);
    }
    if (residual <= tol2 || it + 1 == t.length_iterations) {
      std::swap(x, g);
      return;
    }
    if (m > 0 && have_prev) {
      Vec3d* dfc = df.data() + next * n;
      Vec3d* dgc = dg.data() + next * n;
      for (std::size_t v = 0; v < n; ++v) {
        dfc[v] = f[v] - f_prev[v];
        dgc[v] = g[v] - g_prev[v];
      }
      cols = std::min(cols + 1, m);
      for (std::size_t c = 0; c < cols; ++c) {
        const Vec3d* o = df.data() + c * n;
        double s = 0;
        for (std::size_t v = 0; v < n; ++v) s += dfc[v].dot(o[v]);
        gram(static_cast<Eigen::Index>(next), static_cast<Eigen::Index>(c)) = s;
        gram(static_cast<Eigen::Index>(c), static_cast<Eigen::Index>(next)) = s;
      }
      next = (next + 1) % m;
    }
    std::swap(f_prev, f);
    std::swap(g_prev, g);
    have_prev = true;
    // f_prev, g_prev now hold this step's f and G(x).
    bool accelerated = false;
    if (cols > 0) {
      const auto k = static_cast<Eigen::Index>(cols);
      Eigen::VectorXd rhs(k);
      for (std::size_t c = 0; c < cols; ++c) {
        const Vec3d* o = df.data() + c * n;
        double s = 0;
        for (std::size_t v = 0; v < n; ++v) s += o[v].dot(f_prev[v]);
        rhs[static_cast<Eigen::Index>(c)] = s;
      }
      Eigen::VectorXd gamma;
      if (edge_transfer_detail::anderson_gamma(gram, rhs, gamma)) {
        for (std::size_t v = 0; v < n; ++v) {
          Vec3d s = g_prev[v];
          for (std::size_t c = 0; c < cols; ++c) s -= gamma[static_cast<Eigen::Index>(c)] * dg[c * n + v];
          x[v] = s;
        }
        const double e_aa = turn_targets(t, x, length, target) + anchor_energy(x);
        if (e_aa < energy) {
          energy = e_aa;
          accelerated = true;
        } else {
          cols = 0;
          next = 0;
        }
      }
    }
    if (!accelerated) {
      std::copy(g_prev.begin(), g_prev.end(), x.begin());
      energy = turn_targets(t, x, length, target) + anchor_energy(x);
    }
  }
}

}  // namespace

namespace edge_transfer_detail {

bool anderson_gamma(const Eigen::MatrixXd& gram, const Eigen::VectorXd& rhs, Eigen::VectorXd& gamma) {
  // Normal equations of the small least-squares problem, with a Tikhonov
  // term relative to the diagonal (nearly parallel columns).
  const Eigen::Index k = rhs.size();
  Eigen::MatrixXd a = gram.topLeftCorner(k, k);
  a.diagonal() *= 1.0 + 1e-10;
  gamma = a.ldlt().solve(rhs);
  return gamma.allFinite();
}

Status targets_and_rhs(const EdgeTransfer& t, std::span<const Vec3d> body_points,
                       std::span<const Triangle> body_triangles, std::span<const Vec3d> garment,
                       std::vector<Vec3d>& target, std::vector<Vec3d>& rhs, const ExecContext& ctx) {
  const std::size_t n = t.vertices;
  if (!t.solver) return Status(ErrorCode::kInvalidArgument, "edge transfer: not encoded");
  if (garment.size() != n)
    return Status(ErrorCode::kMismatch, "edge transfer: " + std::to_string(garment.size()) +
                                            " garment vertices for an encoding of " + std::to_string(n));
  for (std::size_t e = 0; e < t.edges.size(); ++e) {
    if (t.triangle[e] == kNoTriangle) continue;
    if (t.triangle[e] >= body_triangles.size())
      return Status(ErrorCode::kMismatch, "edge transfer: the body has " + std::to_string(body_triangles.size()) +
                                              " triangles; the encoding uses triangle " +
                                              std::to_string(t.triangle[e]));
    for (std::uint32_t c : body_triangles[t.triangle[e]])
      if (c >= body_points.size())
        return Status(ErrorCode::kMismatch, "edge transfer: triangle " + std::to_string(t.triangle[e]) +
                                                " uses point " + std::to_string(c) + " of " +
                                                std::to_string(body_points.size()));
  }
  for (std::size_t v = 0; v < n; ++v)
    if (!is_finite(garment[v]))
      return Status(ErrorCode::kDegenerate, "edge transfer: garment vertex " + std::to_string(v) + " is not finite");
  // Edge targets T_e = B_new c_e, then the right-hand side D^T W T + A d,
  // gathered per vertex in a fixed order (deterministic).
  target.assign(t.edges.size(), Vec3d::Zero());
  par::for_each_n(ctx, t.edges.size(), [&](std::size_t e) {
    if (t.weight[e] == 0) return;
    const Mat3d m = triangle_basis(body_points, body_triangles[t.triangle[e]]);
    // A triangle collapsed on this body (zero normal) gives no stretch: the
    // edge keeps its decoded vector.
    target[e] = m.col(2).squaredNorm() > 0 ? Vec3d(m * t.coefficient[e])
                                           : Vec3d(garment[t.edges[e][1]] - garment[t.edges[e][0]]);
  });
  rhs_of(t, garment, target, rhs);
  return Status::ok();
}

}  // namespace edge_transfer_detail

Status apply_edge_transfer(const EdgeTransfer& t, std::span<const Vec3d> body_points,
                           std::span<const Triangle> body_triangles, std::span<Vec3d> garment, const ExecContext& ctx) {
  const std::size_t n = t.vertices;
  std::vector<Vec3d> target, rhs, x(n), scratch;
  if (Status s = edge_transfer_detail::targets_and_rhs(t, body_points, body_triangles, garment, target, rhs, ctx); !s)
    return s;
  auto solve = [&] {
    rhs_of(t, garment, target, rhs);
    t.solver->solve(rhs, x, scratch);
  };
  t.solver->solve(rhs, x, scratch);
  // Length iterations (local-global, as in as-rigid-as-possible solvers):
  // only an edge's length is prescribed, its direction is free, so each
  // target is turned to the edge's current direction and the same energy is
  // relaxed again. Vector targets over-constrain the garment (three
  // equations per edge, about two edges per vertex); lengths do not. The
  // targets' lengths never change.
  std::vector<double> length(t.edges.size());
  for (std::size_t e = 0; e < t.edges.size(); ++e) length[e] = target[e].norm();
  if ((t.anderson_window > 0 || t.length_tolerance > 0) && t.length_sweeps == 1) {
    accelerated_length_iterations(t, garment, length, target, x);
  } else {
    for (int it = 0; it < t.length_iterations; ++it) {
      // Sequential: between two sequential sweeps, waking the workers for a
      // loop this short costs more than it saves.
      (void)turn_targets(t, x, length, target);
      if (t.length_sweeps == 0) {
        solve();
        continue;
      }
      for (int sw = 0; sw < t.length_sweeps; ++sw) gauss_seidel_sweep(t, garment, target, x);
    }
  }
  std::copy(x.begin(), x.end(), garment.begin());
  return Status::ok();
}

}  // namespace atelier
