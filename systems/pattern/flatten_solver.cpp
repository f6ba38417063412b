// Phase 2 of the energy-based flattening (Wang, Smith, Yuen 2002, the
// reference [48] of seed 001 section 7), the planar mesh deformation: L-BFGS
// on the spring energy with the spring Laplacian as its initial Hessian
// (after Liu, Bouaziz, Kavan, "Quasi-Newton methods for real-time simulation
// of hyperelastic materials", ACM TOG 36(3), 2017), the flip barrier and the
// filtered line search, and the flip and overlap counts.
// Why this file is long: the energies, the step limit and the solver that
// calls them share the block structure of their sums and the step cap, which
// keep every path (sequential scatter, parallel gather) at the same bits;
// apart, those contracts would span two files.
#include <atelier/engine/parallel.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "flatten_detail.h"

namespace atelier::pattern_detail {

namespace {

/// Phase 2 adds a barrier -(r - r0)^2 ln(r / r0) (times the rest area) for
/// triangles below this area ratio r: zero elsewhere, infinite as a triangle
/// collapses, so the minimiser never reaches a flip.
constexpr double kBarrierRatio = 0.1;
constexpr double kClearlyAbove = 2 * kBarrierRatio * (1 + 1e-9);

/// Seam lengths: the initial penalty rho (times the mean stiffness), the
/// rounds of multiplier updates at most, and the relative residual |c| / T
/// that ends them (the projection then goes to rounding).
constexpr double kSeamPenalty = 100;
constexpr double kSeamPenaltyMax = 1e2;  // rho grows tenfold per slow round, up to this times its start
constexpr int kSeamRounds = 8;
constexpr double kSeamTolerance = 1e-9;

/// par::transform_reduce's block: the sequential paths below sum in the
/// same blocks, so E has the same bits for any thread count.
constexpr std::size_t kReduceBlock = 4096;

/// The line search starts at min(1, 0.9 s_max): s_max is only needed
/// exactly below 1 / 0.9, so max_feasible_step may skip the triangles that
/// cannot flip before this.
constexpr double kStepCap = 1.25;

}  // namespace

std::size_t count_flipped(const PieceTopology& t, std::span<const Vec2d> uv, const ExecContext& ctx) {
  return par::transform_reduce(
      ctx, t.tri.size(), std::size_t{0},
      [&](std::size_t f) -> std::size_t {
        const auto& c = t.tri[f];
        return signed_area2(uv[c[0]], uv[c[1]], uv[c[2]]) > 0 ? 0 : 1;
      },
      [](std::size_t a, std::size_t b) { return a + b; });
}

std::size_t count_boundary_crossings(const PieceTopology& t, std::span<const Vec2d> uv) {
  struct Seg {
    std::uint32_t a, b;
  };
  // Called once per line-search step: the buffers stay with the thread.
  thread_local std::vector<Seg> seg;
  thread_local std::vector<std::pair<std::int64_t, std::uint32_t>> entries;  // (cell, segment)
  thread_local std::vector<std::pair<std::uint32_t, std::uint32_t>> hits;
  seg.clear(), entries.clear(), hits.clear();
  for (const auto& lp : t.loops)
    for (std::size_t i = 0; i < lp.size(); ++i) seg.push_back({lp[i], lp[(i + 1) % lp.size()]});
  if (seg.size() < 4) return 0;
  Eigen::AlignedBox2d box;
  double mean = 0;
  for (const Seg& s : seg) {
    box.extend(uv[s.a]);
    mean += (uv[s.b] - uv[s.a]).norm();
  }
  mean /= static_cast<double>(seg.size());
  const double cell = std::max(2 * mean, 1e-300);
  const Vec2d size = box.sizes();
  const auto nx = static_cast<std::int64_t>(std::min(4096.0, std::floor(size.x() / cell) + 1));
  const auto ny = static_cast<std::int64_t>(std::min(4096.0, std::floor(size.y() / cell) + 1));
  const double cx = std::max(size.x() / static_cast<double>(nx), 1e-300);
  const double cy = std::max(size.y() / static_cast<double>(ny), 1e-300);
  auto cell_of = [&](const Vec2d& p, std::int64_t& i, std::int64_t& j) {
    i = std::clamp<std::int64_t>(static_cast<std::int64_t>((p.x() - box.min().x()) / cx), 0, nx - 1);
    j = std::clamp<std::int64_t>(static_cast<std::int64_t>((p.y() - box.min().y()) / cy), 0, ny - 1);
  };
  for (std::uint32_t s = 0; s < seg.size(); ++s) {
    std::int64_t i0, j0, i1, j1;
    cell_of(uv[seg[s].a], i0, j0);
    cell_of(uv[seg[s].b], i1, j1);
    for (std::int64_t i = std::min(i0, i1); i <= std::max(i0, i1); ++i)
      for (std::int64_t j = std::min(j0, j1); j <= std::max(j0, j1); ++j) entries.emplace_back(j * nx + i, s);
  }
  std::sort(entries.begin(), entries.end());
  auto crosses = [&](const Seg& p, const Seg& q) {
    if (p.a == q.a || p.a == q.b || p.b == q.a || p.b == q.b) return false;
    const Vec2d &a = uv[p.a], &b = uv[p.b], &c = uv[q.a], &d = uv[q.b];
    const double d1 = signed_area2(a, b, c), d2 = signed_area2(a, b, d);
    const double d3 = signed_area2(c, d, a), d4 = signed_area2(c, d, b);
    return ((d1 > 0) != (d2 > 0) || d1 == 0 || d2 == 0) && ((d3 > 0) != (d4 > 0) || d3 == 0 || d4 == 0) &&
           !(d1 == 0 && d2 == 0);  // collinear overlaps are not crossings of distinct segments here
  };
  for (std::size_t i = 0; i < entries.size();) {
    std::size_t j = i;
    while (j < entries.size() && entries[j].first == entries[i].first) ++j;
    for (std::size_t x = i; x < j; ++x)
      for (std::size_t y = x + 1; y < j; ++y)
        if (crosses(seg[entries[x].second], seg[entries[y].second]))
          hits.emplace_back(std::min(entries[x].second, entries[y].second),
                            std::max(entries[x].second, entries[y].second));
    i = j;
  }
  std::sort(hits.begin(), hits.end());
  return static_cast<std::size_t>(std::unique(hits.begin(), hits.end()) - hits.begin());
}

double spring_energy(const PieceTopology& t, const RestState& rest, std::span<const Vec2d> uv,
                     std::span<Vec2d> gradient, std::vector<Vec2d>& scratch, const ExecContext& ctx) {
  const bool want = !gradient.empty();
  const std::size_t ns = t.spring.size();
  if (par::run_sequential(ctx, ns)) {
    // One pass over the springs, the force scattered to both ends in spring
    // order: each vertex receives its springs' terms in the order of the
    // gather below (vs_spring is in spring order), so the gradient has the
    // same bits; E is summed in par::transform_reduce's blocks.
    if (want) std::fill(gradient.begin(), gradient.end(), Vec2d::Zero());
    double e = 0;
    for (std::size_t b0 = 0; b0 < ns; b0 += kReduceBlock) {
      double acc = 0;
      const std::size_t b1 = std::min(ns, b0 + kReduceBlock);
      for (std::size_t s = b0; s < b1; ++s) {
        const auto& sp = t.spring[s];
        const Vec2d d = uv[sp[0]] - uv[sp[1]];
        const double r = d.norm(), l = rest.length[s], c = rest.stiffness[s];
        if (want) {
          const Vec2d f = r > 0 ? Vec2d(c * (r - l) / r * d) : Vec2d::Zero();
          gradient[sp[0]] += f;
          gradient[sp[1]] -= f;
        }
        acc += 0.5 * c * (r - l) * (r - l);
      }
      e += acc;
    }
    return e;
  }
  if (want) scratch.resize(ns);
  const double e = par::transform_reduce(
      ctx, ns, 0.0,
      [&](std::size_t s) {
        const auto& sp = t.spring[s];
        const Vec2d d = uv[sp[0]] - uv[sp[1]];
        const double r = d.norm(), l = rest.length[s], c = rest.stiffness[s];
        if (want) scratch[s] = r > 0 ? Vec2d(c * (r - l) / r * d) : Vec2d::Zero();
        return 0.5 * c * (r - l) * (r - l);
      },
      [](double a, double b) { return a + b; });
  if (want) {
    par::for_each_n(ctx, t.vertex_count(), [&](std::size_t v) {
      Vec2d g = Vec2d::Zero();
      for (std::uint32_t k = t.vs_off[v]; k < t.vs_off[v + 1]; ++k) {
        const std::uint32_t s = t.vs_spring[k];
        if (t.spring[s][0] == v)
          g += scratch[s];
        else
          g -= scratch[s];
      }
      gradient[v] = g;
    });
  }
  return e;
}

double barrier_energy(const PieceTopology& t, const RestState& rest, std::span<const Vec2d> uv,
                      std::span<Vec2d> gradient, std::vector<Vec2d>& scratch, const ExecContext& ctx) {
  const bool want = !gradient.empty();
  const std::size_t nt = t.tri.size();
  // phi(r) = -(r - r0)^2 ln(r / r0) for r = a_2D / A below r0: zero with its
  // first two derivatives at r0, infinite at 0 (and for a flipped
  // triangle). Nearly every triangle is above r0 nearly always, and its
  // terms are exact zeros: the sums below skip them. Skipping +0 keeps the
  // bits, since a sum that starts at +0 is never -0. `ratio` returns r0
  // itself, without the division, when 2 a_2D exceeds 2 r0 A by more than
  // rounding (r would come out at least r0).
  auto ratio = [&](std::size_t f) {
    const auto& c = t.tri[f];
    const double a2 = signed_area2(uv[c[0]], uv[c[1]], uv[c[2]]);
    if (a2 > kClearlyAbove * rest.area[f]) return kBarrierRatio;
    return 0.5 * a2 / rest.area[f];
  };
  auto term = [&](std::size_t f, double r) {
    if (!(r > 0)) return std::numeric_limits<double>::infinity();
    const double d = r - kBarrierRatio, lg = std::log(r / kBarrierRatio);
    return -rest.area[f] * d * d * lg;
  };
  // dphi/dq_k = phi'(r) (da/dq_k) / A, the area factor cancelling against
  // the energy's (A phi).
  auto corner_gradient = [&](std::size_t f, double r, int k) -> Vec2d {
    const auto& c = t.tri[f];
    const double d = r - kBarrierRatio, lg = std::log(r / kBarrierRatio);
    const double dphi = -2 * d * lg - d * d / r;
    return dphi * area_gradient(uv[c[(k + 1) % 3]], uv[c[(k + 2) % 3]]);
  };
  if (par::run_sequential(ctx, nt)) {
    // E in par::transform_reduce's blocks; the gradient scattered in
    // triangle order, which is each vertex's order in vt_tri, over the
    // triangles below r0 listed (with their r) by the energy's pass.
    thread_local std::vector<std::pair<std::uint32_t, double>> active;
    active.clear();
    double e = 0;
    for (std::size_t b0 = 0; b0 < nt; b0 += kReduceBlock) {
      double acc = 0;
      const std::size_t b1 = std::min(nt, b0 + kReduceBlock);
      for (std::size_t f = b0; f < b1; ++f) {
        const double r = ratio(f);
        if (r >= kBarrierRatio) continue;
        acc += term(f, r);
        active.emplace_back(static_cast<std::uint32_t>(f), r);
      }
      e += acc;
    }
    if (want && !active.empty() && std::isfinite(e)) {
      scratch.assign(t.vertex_count(), Vec2d::Zero());
      for (const auto& [f, r] : active)
        for (int k = 0; k < 3; ++k) scratch[t.tri[f][k]] += corner_gradient(f, r, k);
      for (std::size_t v = 0; v < t.vertex_count(); ++v) gradient[v] += scratch[v];
    }
    return e;
  }
  if (want) scratch.assign(3 * nt, Vec2d::Zero());
  std::atomic<bool> any{false};
  const double e = par::transform_reduce(
      ctx, nt, 0.0,
      [&](std::size_t f) {
        const double r = ratio(f);
        if (r >= kBarrierRatio) return 0.0;
        any.store(true, std::memory_order_relaxed);
        if (want && r > 0)
          for (int k = 0; k < 3; ++k) scratch[3 * f + k] = corner_gradient(f, r, k);
        return term(f, r);
      },
      [](double a, double b) { return a + b; });
  if (want && any.load() && std::isfinite(e)) {
    par::for_each_n(ctx, t.vertex_count(), [&](std::size_t v) {
      Vec2d g = Vec2d::Zero();
      for (std::uint32_t k = t.vt_off[v]; k < t.vt_off[v + 1]; ++k) {
        const std::uint32_t f = t.vt_tri[k];
        const auto& c = t.tri[f];
        g += scratch[3 * f + (c[0] == v ? 0 : c[1] == v ? 1 : 2)];
      }
      gradient[v] += g;
    });
  }
  return e;
}

double max_feasible_step(const PieceTopology& t, std::span<const Vec2d> uv, std::span<const Vec2d> dir,
                         const ExecContext& ctx, double cap) {
  auto root = [&](std::size_t f) {
    // 2 a(s) = cross(e1 + s f1, e2 + s f2) = alpha + beta s + gamma s^2.
    const auto& c = t.tri[f];
    const Vec2d e1 = uv[c[1]] - uv[c[0]], e2 = uv[c[2]] - uv[c[0]];
    const Vec2d f1 = dir[c[1]] - dir[c[0]], f2 = dir[c[2]] - dir[c[0]];
    const double alpha = cross2(e1, e2), beta = cross2(e1, f2) + cross2(f1, e2), gamma = cross2(f1, f2);
    double best = std::numeric_limits<double>::infinity();
    // A CCW triangle with alpha - |beta| s - |gamma| s^2 > 0 (a lower bound
    // of 2 a(s)) at s = cap keeps its area positive on [0, cap]: it has no
    // root there, so its roots need not be found (no square root, no
    // division). The margin covers the rounding of the bound.
    if (alpha > 0 && (alpha - cap * (std::abs(beta) + cap * std::abs(gamma)) > 1e-6 * alpha)) return best;
    if (std::abs(gamma) <= 1e-14 * std::abs(beta)) {
      if (beta < 0) best = -alpha / beta;
      return best;
    }
    const double disc = beta * beta - 4 * alpha * gamma;
    if (disc < 0) return best;
    // Stable roots: q = -(beta + sign(beta) sqrt(disc)) / 2; roots q / gamma, alpha / q.
    const double q = -0.5 * (beta + std::copysign(std::sqrt(disc), beta));
    for (double x : {q / gamma, q != 0 ? alpha / q : std::numeric_limits<double>::infinity()})
      if (x > 0) best = std::min(best, x);
    return best;
  };
  if (par::run_sequential(ctx, t.tri.size())) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t f = 0; f < t.tri.size(); ++f) best = std::min(best, root(f));
    return best;
  }
  return par::transform_reduce(ctx, t.tri.size(), std::numeric_limits<double>::infinity(), root,
                               [](double a, double b) { return std::min(a, b); });
}

void Phase2Solver::analyze(const PieceTopology& t) {
  const auto n = static_cast<Eigen::Index>(t.vertex_count());
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(n + 2 * t.spring.size());
  for (Eigen::Index v = 0; v < n; ++v) trip.emplace_back(v, v, 1.0);
  for (const auto& s : t.spring) {
    trip.emplace_back(s[0], s[1], -1.0);
    trip.emplace_back(s[1], s[0], -1.0);
  }
  laplacian_.resize(n, n);
  laplacian_.setFromTriplets(trip.begin(), trip.end());
  laplacian_.makeCompressed();
  auto slot = [&](std::uint32_t row, std::uint32_t col) {
    const int* inner = laplacian_.innerIndexPtr();
    const int* outer = laplacian_.outerIndexPtr();
    const int* it = std::lower_bound(inner + outer[col], inner + outer[col + 1], static_cast<int>(row));
    return static_cast<std::uint32_t>(it - inner);
  };
  for (auto& x : value_of_spring_) x.resize(t.spring.size());
  for (std::size_t s = 0; s < t.spring.size(); ++s) {
    value_of_spring_[0][s] = slot(t.spring[s][0], t.spring[s][1]);
    value_of_spring_[1][s] = slot(t.spring[s][1], t.spring[s][0]);
  }
  value_of_diag_.resize(t.vertex_count());
  for (std::uint32_t v = 0; v < t.vertex_count(); ++v) value_of_diag_[v] = slot(v, v);
  llt_.analyzePattern(laplacian_);
  analyzed_ = true;
  factor_.reset();
}

void Phase2Solver::solve(std::span<const Vec2d> b, std::span<Vec2d> x) const {
  // P^T L L^T P x = b with both columns (u and v) in one pass over the
  // factor (Eigen's solve streams L once per right-hand side), its values
  // read as floats (H0 only preconditions L-BFGS: its precision sets the
  // speed of convergence, not the minimiser), sums in double.
  const Factor& F = *factor_;
  const int* outer = F.outer.data();
  const int* inner = F.inner.data();
  const float* val = F.values.data();
  const double* inv = F.inverse_diagonal.data();
  const int* perm = F.perm.data();
  const std::size_t n = F.inverse_diagonal.size();
  Vec2d* y = work_.data();
  for (std::size_t i = 0; i < n; ++i) y[perm[i]] = b[i];
  for (std::size_t j = 0; j < n; ++j) {  // L y = b (the diagonal leads each column)
    const Vec2d yj = y[j] * inv[j];
    y[j] = yj;
    for (int p = outer[j] + 1; p < outer[j + 1]; ++p) y[inner[p]] -= double(val[p]) * yj;
  }
  for (std::size_t j = n; j-- > 0;) {  // L^T x = y
    Vec2d acc = y[j];
    for (int p = outer[j] + 1; p < outer[j + 1]; ++p) acc -= double(val[p]) * y[inner[p]];
    y[j] = acc * inv[j];
  }
  for (std::size_t i = 0; i < n; ++i) x[i] = y[perm[i]];
}

bool Phase2Solver::run(const PieceTopology& t, const RestState& rest, const SolverParams& prm, std::vector<Vec2d>& uv,
                       SolverStats& stats, const ExecContext& ctx, bool reuse, SeamLengths* seams) {
  if (!analyzed_) analyze(t);
  const auto t0 = Clock::now();
  const std::size_t n = t.vertex_count();
  // H0 = the spring Laplacian sum C_ij (e_i - e_j)(e_i - e_j)^T for x and y
  // alike (the Hessian of E at rest with the transverse terms made equal to
  // the axial ones), made definite by anchoring vertex 0 with its own
  // diagonal (translations are the only null space). A factor of nearly the
  // same stiffnesses (another body of the same piece) preconditions as well:
  // it is kept when `reuse` and no stiffness moved by more than 25%.
  bool keep =
      reuse && factor_ && factor_->stiffness.size() == rest.stiffness.size() && factor_->inverse_diagonal.size() == n;
  for (std::size_t s = 0; keep && s < rest.stiffness.size(); ++s)
    keep = std::abs(rest.stiffness[s] / factor_->stiffness[s] - 1) <= 0.25;
  stats.reused_factor = keep;
  if (!keep) {
    factor_.reset();
    double* val = laplacian_.valuePtr();
    std::fill(val, val + laplacian_.nonZeros(), 0.0);
    for (std::size_t s = 0; s < t.spring.size(); ++s) {
      const double c = rest.stiffness[s];
      val[value_of_spring_[0][s]] = -c;
      val[value_of_spring_[1][s]] = -c;
      val[value_of_diag_[t.spring[s][0]]] += c;
      val[value_of_diag_[t.spring[s][1]]] += c;
    }
    val[value_of_diag_[0]] *= 2;
    llt_.factorize(laplacian_);
    if (llt_.info() != Eigen::Success) return false;
    const auto& L = llt_.matrixL().nestedExpression();
    auto F = std::make_shared<Factor>();
    F->outer.assign(L.outerIndexPtr(), L.outerIndexPtr() + n + 1);
    F->inner.assign(L.innerIndexPtr(), L.innerIndexPtr() + L.nonZeros());
    F->values.assign(L.valuePtr(), L.valuePtr() + L.nonZeros());
    const int* perm = llt_.permutationP().indices().data();
    F->perm.assign(perm, perm + n);
    F->inverse_diagonal.resize(n);
    for (std::size_t j = 0; j < n; ++j) F->inverse_diagonal[j] = 1 / L.valuePtr()[L.outerIndexPtr()[j]];
    F->stiffness = rest.stiffness;
    factor_ = std::move(F);
  }
  stats.factor_ms = ms_since(t0);
  work_.resize(n);

  // Vectors of R^2n as arrays of Vec2d (u, v interleaved); dot products and
  // updates through Eigen maps, in a fixed order (thread-independent).
  using Vec = std::vector<Vec2d>;
  auto flat = [n](Vec& v) { return Eigen::Map<Eigen::VectorXd>(reinterpret_cast<double*>(v.data()), 2 * n); };
  auto cflat = [n](const Vec& v) {
    return Eigen::Map<const Eigen::VectorXd>(reinterpret_cast<const double*>(v.data()), 2 * n);
  };
  auto dot = [&](const Vec& a, const Vec& b) { return cflat(a).dot(cflat(b)); };

  // Seam lengths (FlattenOptions::seam_lengths): constraints
  // c_k(Q) = L_k(Q) - T_k = 0 with L_k the chain's 2D length. E is
  // minimised subject to them by the augmented Lagrangian
  //   E + sum_k lambda_k c_k + rho/2 c_k^2
  // (Nocedal, Wright, Numerical Optimization, 2nd ed., section 17.3, eq.
  // 17.36): each round minimises it by L-BFGS, then lambda += rho c. The
  // penalty's Gauss-Newton term rho G G^T (G = [grad c_k]) joins H0 through
  // the Sherman-Morrison-Woodbury identity, so a stiff rho does not slow
  // L-BFGS. A last projection x -= Z (G^T Z)^-1 c, Z = H0^-1 G (Newton on c
  // in the metric of H0) makes the lengths exact to rounding.
  const std::size_t kc = seams ? seams->size() : 0;
  if (seams) seams->lambda.resize(kc, 0.0);
  std::vector<std::vector<std::uint32_t>> seam_verts(kc);
  for (std::size_t i = 0; i < kc; ++i) {
    for (const auto& sd : seams->sides[i]) seam_verts[i].insert(seam_verts[i].end(), sd.begin(), sd.end());
    std::sort(seam_verts[i].begin(), seam_verts[i].end());
    seam_verts[i].erase(std::unique(seam_verts[i].begin(), seam_verts[i].end()), seam_verts[i].end());
  }
  double rho = 0;
  if (kc) {
    double cm = 0;
    for (double c : rest.stiffness) cm += c;
    rho = kSeamPenalty * cm / static_cast<double>(rest.stiffness.size());
  }
  const double rho0 = rho;
  auto seam_values = [&](const Vec& at, std::vector<double>& c) {
    c.resize(kc);
    for (std::size_t i = 0; i < kc; ++i) {
      double l = 0;
      for (const auto& sd : seams->sides[i]) l += (at[sd[0]] - at[sd[1]]).norm();
      c[i] = l - seams->target[i];
    }
  };
  auto worst_relative = [&](const std::vector<double>& c) {
    double w = 0;
    for (std::size_t i = 0; i < kc; ++i) w = std::max(w, std::abs(c[i]) / seams->target[i]);
    return w;
  };
  // w * grad L_i added into `grad` (dense).
  auto add_seam_gradient = [&](const Vec& at, std::size_t i, double w, Vec& grad) {
    for (const auto& sd : seams->sides[i]) {
      const Vec2d d = at[sd[0]] - at[sd[1]];
      const double r = d.norm();
      if (!(r > 0)) continue;
      const Vec2d u = (w / r) * d;
      grad[sd[0]] += u;
      grad[sd[1]] -= u;
    }
  };
  // Woodbury data at a point: G's columns (dense), Z = H0^-1 G, and the
  // factor of M = I/rho + G^T Z (rho = inf: the projection's G^T Z).
  std::vector<Vec> G(kc), Z(kc);
  Eigen::LDLT<Eigen::MatrixXd> M;
  auto refresh = [&](const Vec& at, double penalty) {
    Eigen::MatrixXd A(kc, kc);
    for (std::size_t i = 0; i < kc; ++i) {
      G[i].assign(n, Vec2d::Zero());
      add_seam_gradient(at, i, 1.0, G[i]);
      Z[i].resize(n);
      solve(G[i], Z[i]);
    }
    for (std::size_t i = 0; i < kc; ++i)
      for (std::size_t j = 0; j < kc; ++j) {
        double g = 0;
        for (std::uint32_t v : seam_verts[i]) g += G[i][v].dot(Z[j][v]);
        A(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = g;
      }
    A = 0.5 * (A + A.transpose()).eval();
    if (std::isfinite(penalty)) A.diagonal().array() += 1 / penalty;
    M.compute(A);
  };
  // r = (H0 + rho G G^T)^-1 q.
  Eigen::VectorXd ky(static_cast<Eigen::Index>(kc));
  auto precondition = [&](const Vec& q, Vec& r) {
    solve(q, r);
    if (!kc) return;
    for (std::size_t i = 0; i < kc; ++i) {
      double g = 0;
      for (std::uint32_t v : seam_verts[i]) g += G[i][v].dot(r[v]);
      ky[static_cast<Eigen::Index>(i)] = g;
    }
    const Eigen::VectorXd z = M.solve(ky);
    for (std::size_t i = 0; i < kc; ++i) flat(r) -= z[static_cast<Eigen::Index>(i)] * cflat(Z[i]);
  };

  Vec x(uv), xt(n), g(n), gt(n), q(n), r(n), p(n), scratch, tscratch;
  std::vector<double> cv;
  // The objective: E plus the flip barrier (zero unless a triangle is below
  // a tenth of its rest area), plus the seam terms.
  auto objective = [&](const Vec& at, Vec& grad) {
    double e = spring_energy(t, rest, at, grad, scratch, ctx);
    e += barrier_energy(t, rest, at, grad, tscratch, ctx);
    if (kc && std::isfinite(e)) {
      seam_values(at, cv);
      for (std::size_t i = 0; i < kc; ++i) {
        const double c = cv[i], l = seams->lambda[i];
        e += l * c + 0.5 * rho * c * c;
        add_seam_gradient(at, i, l + rho * c, grad);
      }
    }
    return e;
  };
  stats.energy_phase1 = spring_energy(t, rest, x, {}, scratch, ctx);
  const std::size_t overlaps0 = count_boundary_crossings(t, x);
  // Below this E a length error of 1e-14 relative is reached: nothing is
  // left to release (a developable piece after phase 1).
  double scale = 0;
  for (std::size_t s = 0; s < t.spring.size(); ++s) scale += 0.5 * rest.stiffness[s] * rest.length[s] * rest.length[s];
  const double tiny = 1e-28 * scale;

  // A warm start is given up (stats.stalled) when each of the first
  // prm.stall_window iterations of the first round had its step cut by the
  // flip limit: it presses triangles into a flip on every step, and such a
  // start crawls to the iteration cap (docs/glossary.md, warm starts).
  int cut_run = 0;
  bool watch_stall = prm.stall_window > 0;

  // L-BFGS from x for at most `budget` iterations; returns those done.
  auto lbfgs = [&](int budget) {
    double e = objective(x, g);
    std::vector<Vec> S, Y;
    std::vector<double> rho_k, alpha;
    int it = 0, small = 0;
    for (; it < budget && e > tiny && std::isfinite(e); ++it) {
      if (ctx.cancelled()) break;
      // Two-loop recursion with H0^-1 applied by the Cholesky factor.
      q = g;
      alpha.assign(S.size(), 0);
      for (std::size_t i = S.size(); i-- > 0;) {
        alpha[i] = rho_k[i] * dot(S[i], q);
        flat(q) -= alpha[i] * cflat(Y[i]);
      }
      precondition(q, r);
      for (std::size_t i = 0; i < S.size(); ++i) {
        const double beta = rho_k[i] * dot(Y[i], r);
        flat(r) += (alpha[i] - beta) * cflat(S[i]);
      }
      flat(p) = -cflat(r);
      double slope = dot(g, p);
      if (!(slope < 0)) {
        S.clear(), Y.clear(), rho_k.clear();
        precondition(g, p);
        flat(p) = -cflat(p);
        slope = dot(g, p);
        if (!(slope < 0)) break;
      }
      // Filtered line search: start below the largest step that keeps every
      // triangle CCW, then backtrack (Armijo). The overlap guard refuses a
      // step that makes the boundary cross itself more than at the start.
      const double limit = max_feasible_step(t, x, p, ctx, kStepCap);
      double step = std::min(1.0, 0.9 * limit);
      if (step < 1) ++stats.rejected_steps;
      if (watch_stall) {
        cut_run = step < 1 ? cut_run + 1 : 0;
        watch_stall = cut_run > 0;
        if (cut_run >= prm.stall_window) {
          stats.stalled = true;
          break;
        }
      }
      bool accepted = false;
      double et = 0;
      for (int tries = 0; tries < 40; ++tries, step *= 0.5) {
        flat(xt) = cflat(x) + step * cflat(p);
        et = objective(xt, gt);
        if (!(et <= e + 1e-4 * step * slope)) continue;
        if (count_boundary_crossings(t, xt) > overlaps0) {
          ++stats.rejected_steps;
          continue;
        }
        accepted = true;
        break;
      }
      if (!accepted) {
        if (S.empty()) break;
        S.clear(), Y.clear(), rho_k.clear();
        continue;
      }
      // Curvature pair (s, y); the oldest pair's storage is reused.
      Vec sk, yk;
      if (static_cast<int>(S.size()) == prm.memory) {
        sk = std::move(S.front()), yk = std::move(Y.front());
        S.erase(S.begin()), Y.erase(Y.begin()), rho_k.erase(rho_k.begin());
      }
      sk.resize(n), yk.resize(n);
      flat(sk) = cflat(xt) - cflat(x);
      flat(yk) = cflat(gt) - cflat(g);
      const double sy = dot(sk, yk);
      if (sy > 1e-300) S.push_back(std::move(sk)), Y.push_back(std::move(yk)), rho_k.push_back(1 / sy);
      const double decrease = e - et;
      std::swap(x, xt);
      std::swap(g, gt);
      e = et;
      // Converged after two iterations in a row that release less than
      // `tolerance` of E.
      small = decrease <= prm.tolerance * std::abs(e) ? small + 1 : 0;
      if (small == 2) {
        ++it;
        break;
      }
    }
    return it;
  };

  int used = 0;
  if (!kc) {
    used = lbfgs(prm.max_iterations);
  } else {
    double previous = std::numeric_limits<double>::infinity();
    for (int round = 0; round < kSeamRounds && used < prm.max_iterations; ++round) {
      refresh(x, rho);
      used += lbfgs(prm.max_iterations - used);
      ++stats.seam_rounds;
      if (stats.stalled) break;
      seam_values(x, cv);
      const double worst = worst_relative(cv);
      if (worst <= kSeamTolerance) break;
      for (std::size_t i = 0; i < kc; ++i) seams->lambda[i] += rho * cv[i];
      if (worst > 0.25 * previous && rho < kSeamPenaltyMax * rho0) rho *= 10;
      previous = worst;
    }
  }
  if (stats.stalled) {  // uv unchanged: the caller starts again cold
    stats.iterations = used;
    stats.phase2_ms = ms_since(t0);
    return true;
  }
  if (kc) {
    // Projection onto the constraints (a Newton step on c in the metric of
    // H0), guarded like the line search; repeated while it gains.
    seam_values(x, cv);
    double worst = worst_relative(cv);
    for (int it = 0; it < 8 && worst > 1e-14; ++it) {
      refresh(x, std::numeric_limits<double>::infinity());
      Eigen::VectorXd c(static_cast<Eigen::Index>(kc));
      for (std::size_t i = 0; i < kc; ++i) c[static_cast<Eigen::Index>(i)] = cv[i];
      const Eigen::VectorXd mu = M.solve(c);
      flat(p).setZero();
      for (std::size_t i = 0; i < kc; ++i) flat(p) -= mu[static_cast<Eigen::Index>(i)] * cflat(Z[i]);
      if (!p.empty() && !cflat(p).allFinite()) break;
      double step = std::min(1.0, 0.9 * max_feasible_step(t, x, p, ctx, kStepCap));
      const double barrier_now = barrier_energy(t, rest, x, {}, tscratch, ctx);
      bool accepted = false;
      std::vector<double> ct;
      for (int tries = 0; tries < 20 && !accepted; ++tries, step *= 0.5) {
        flat(xt) = cflat(x) + step * cflat(p);
        seam_values(xt, ct);
        // No triangle pushed into (or deeper into) the flip barrier's zone.
        accepted = worst_relative(ct) < worst && count_flipped(t, xt, ctx) == 0 &&
                   barrier_energy(t, rest, xt, {}, tscratch, ctx) <= barrier_now &&
                   count_boundary_crossings(t, xt) <= overlaps0;
      }
      if (!accepted) break;
      std::swap(x, xt);
      cv = ct;
      worst = worst_relative(cv);
      ++stats.seam_projections;
    }
    for (std::size_t i = 0; i < kc; ++i) stats.seam_residual = std::max(stats.seam_residual, std::abs(cv[i]));
  }
  const double e = spring_energy(t, rest, x, {}, scratch, ctx);
  uv = x;
  stats.energy = e;
  stats.iterations = used;
  stats.phase2_ms = ms_since(t0);
  return true;
}
}  // namespace atelier::pattern_detail
