// Phase 1 of the energy-based flattening (Wang, Smith, Yuen 2002, the
// reference [48] of seed 001 section 7): triangle flattening breadth-first
// with circle intersections and the relaxation of the partial spring-mass
// system where loops close; and the Tutte embedding phase 2 falls back to.
#include <atelier/engine/parallel.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include "flatten_detail.h"

namespace atelier::pattern_detail {

namespace {

/// The third corner c of a triangle (a, b, c), CCW, at the intersection of
/// the circles of radius r_a about a and r_b about b (the 3D lengths of the
/// two new edges), on the left of ab. When the current |ab| no longer admits
/// an intersection (after relaxation), c goes a thousandth of the shorter
/// radius to the left of the line ab, so the triangle keeps its orientation.
[[nodiscard]] Vec2d circle_apex(const Vec2d& a, const Vec2d& b, double ra, double rb) noexcept {
  const Vec2d ab = b - a;
  const double d = ab.norm();
  if (!(d > 0)) return a + Vec2d(0, ra);
  const Vec2d u = ab / d, left(-u.y(), u.x());
  const double x = (d * d + ra * ra - rb * rb) / (2 * d);
  const double h2 = ra * ra - x * x;
  const double h = std::max(h2 > 0 ? std::sqrt(h2) : 0.0, 1e-3 * std::min(ra, rb));
  return a + x * u + h * left;
}

/// Below this fraction of its rest area a flattened triangle is penalised in
/// the phase 1 relaxation (so a loop that closes on a flipped triangle can
/// unfold it), with this weight relative to the spring energy.
constexpr double kPenaltyRatio = 0.25;
constexpr double kPenaltyWeight = 4.0;

/// The partial spring-mass system of phase 1: springs and triangles already
/// flattened, and the local relaxation where a loop closes.
struct Phase1State {
  const PieceTopology& t;
  const RestState& rest;
  std::vector<Vec2d>& uv;
  std::vector<std::uint8_t> placed, done, active;  // per vertex, triangle, spring

  /// Energy of v's active springs and flattened triangles at position x,
  /// with gradient and a positive semi-definite Hessian: per spring the
  /// projected C (u u^T + max(0, 1 - l / r) (I - u u^T)); per triangle whose
  /// area ratio r is below kPenaltyRatio the penalty w A (r0 - r)^2 (r is
  /// linear in one corner, so its Hessian is exact).
  double local(std::uint32_t v, const Vec2d& x, Vec2d* g, Eigen::Matrix2d* H) const {
    double e = 0;
    if (g) g->setZero();
    if (H) H->setZero();
    for (std::uint32_t k = t.vs_off[v]; k < t.vs_off[v + 1]; ++k) {
      const std::uint32_t s = t.vs_spring[k];
      if (!active[s]) continue;
      const Vec2d d = x - uv[t.vs_other[k]];
      const double r = d.norm(), l = rest.length[s], c = rest.stiffness[s];
      e += 0.5 * c * (r - l) * (r - l);
      if (!(r > 0)) continue;
      const Vec2d u = d / r;
      if (g) *g += c * (r - l) * u;
      if (H) {
        const Eigen::Matrix2d uu = u * u.transpose();
        *H += c * (uu + std::max(0.0, 1 - l / r) * (Eigen::Matrix2d::Identity() - uu));
      }
    }
    for (std::uint32_t k = t.vt_off[v]; k < t.vt_off[v + 1]; ++k) {
      const std::uint32_t f = t.vt_tri[k];
      if (!done[f]) continue;
      const auto& c = t.tri[f];
      const int i = c[0] == v ? 0 : c[1] == v ? 1 : 2;
      const Vec2d& a = uv[c[(i + 1) % 3]];
      const Vec2d& b = uv[c[(i + 2) % 3]];
      const double A = rest.area[f];
      const double ratio = 0.5 * cross2(a - x, b - x) / A;
      if (ratio >= kPenaltyRatio) continue;
      const double w = kPenaltyWeight * A, gap = kPenaltyRatio - ratio;
      e += w * gap * gap;
      const Vec2d dr = area_gradient(a, b) / A;
      if (g) *g -= 2 * w * gap * dr;
      if (H) *H += 2 * w * dr * dr.transpose();
    }
    return e;
  }

  [[nodiscard]] bool bad(std::uint32_t f) const {
    const auto& c = t.tri[f];
    return !(signed_area2(uv[c[0]], uv[c[1]], uv[c[2]]) > 0);
  }

  /// Flattened triangles around v that are not CCW with v at x.
  [[nodiscard]] int bad_around(std::uint32_t v, const Vec2d& x) const {
    int n = 0;
    for (std::uint32_t k = t.vt_off[v]; k < t.vt_off[v + 1]; ++k) {
      const std::uint32_t f = t.vt_tri[k];
      if (!done[f]) continue;
      const auto& c = t.tri[f];
      const Vec2d p0 = c[0] == v ? x : uv[c[0]], p1 = c[1] == v ? x : uv[c[1]], p2 = c[2] == v ? x : uv[c[2]];
      if (!(signed_area2(p0, p1, p2) > 0)) ++n;
    }
    return n;
  }

  /// Grows `region` by `rings` rings (over flattened springs), sorted.
  void grow(std::vector<std::uint32_t>& region, int rings, std::vector<std::uint32_t>& mark,
            std::uint32_t stamp) const {
    for (std::uint32_t v : region) mark[v] = stamp;
    std::size_t begin = 0;
    for (int r = 0; r < rings; ++r) {
      const std::size_t end = region.size();
      for (std::size_t i = begin; i < end; ++i) {
        const std::uint32_t v = region[i];
        for (std::uint32_t k = t.vs_off[v]; k < t.vs_off[v + 1]; ++k) {
          const std::uint32_t w = t.vs_other[k];
          if (active[t.vs_spring[k]] && mark[w] != stamp) {
            mark[w] = stamp;
            region.push_back(w);
          }
        }
      }
      begin = end;
    }
    std::sort(region.begin(), region.end());
  }

  /// Guarded Newton sweeps over `region` (seed 001 section 7: the partial
  /// system releases its strain). A move is kept only when it lowers the
  /// local energy and adds no triangle that is not CCW.
  void sweep(const std::vector<std::uint32_t>& region, int sweeps) {
    for (int k = 0; k < sweeps; ++k) {
      for (std::uint32_t v : region) {
        Vec2d g;
        Eigen::Matrix2d H;
        const double e0 = local(v, uv[v], &g, &H);
        H.diagonal().array() += 1e-12 * (H.trace() + 1e-300);
        const double det = H.determinant();
        if (!(det > 0)) continue;
        Vec2d step = -H.inverse() * g;
        const int bad0 = bad_around(v, uv[v]);
        for (int halving = 0; halving < 5; ++halving, step *= 0.5) {
          const Vec2d x = uv[v] + step;
          if (local(v, x, nullptr, nullptr) < e0 && bad_around(v, x) <= bad0) {
            uv[v] = x;
            break;
          }
        }
      }
    }
  }

  /// Where a loop closes on triangle f: relax its neighbourhood; a closing
  /// triangle that came out flipped gets a wider region and more sweeps
  /// until it is CCW (four tries).
  void relax(std::uint32_t f, int rings, int sweeps, std::vector<std::uint32_t>& region,
             std::vector<std::uint32_t>& mark, std::uint32_t& stamp) {
    const bool hard = bad(f);
    int r = hard ? std::max(rings, 2) : rings, n = hard ? std::max(sweeps, 4) : sweeps;
    for (int attempt = 0; attempt < (hard ? 4 : 1); ++attempt, r += 2) {
      region.assign(t.tri[f].begin(), t.tri[f].end());
      grow(region, r, mark, ++stamp);
      sweep(region, n);
      if (!bad(f)) break;
    }
  }
};
}  // namespace

void run_phase1(const PieceTopology& t, const RestState& rest, std::uint32_t seed, const SolverParams& prm,
                std::vector<Vec2d>& uv, SolverStats& stats) {
  const auto t0 = Clock::now();
  const std::size_t n = t.vertex_count(), nt = t.tri.size();
  uv.assign(n, Vec2d::Zero());
  Phase1State st{t,
                 rest,
                 uv,
                 std::vector<std::uint8_t>(n, 0),
                 std::vector<std::uint8_t>(nt, 0),
                 std::vector<std::uint8_t>(t.spring.size(), 0)};
  auto length = [&](std::uint32_t f, int k) { return rest.length[t.tri_spring[f][k]]; };
  std::vector<std::uint32_t> queue;
  queue.reserve(nt);
  auto finish = [&](std::uint32_t f) {
    st.done[f] = 1;
    for (int k = 0; k < 3; ++k) {
      st.active[t.tri_spring[f][k]] = 1;
      const std::uint32_t g = t.tri_adj[f][k];
      if (g != kNone && !st.done[g]) queue.push_back(g);
    }
  };
  {  // The seed triangle: a at the origin, b on +x, c on the left.
    const auto& c = t.tri[seed];
    uv[c[0]] = Vec2d::Zero();
    uv[c[1]] = Vec2d(length(seed, 0), 0);
    uv[c[2]] = circle_apex(uv[c[0]], uv[c[1]], length(seed, 2), length(seed, 1));
    for (std::uint32_t v : c) st.placed[v] = 1;
    finish(seed);
  }
  std::vector<std::uint32_t> region, mark(n, 0);
  std::uint32_t stamp = 0;
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const std::uint32_t f = queue[head];
    if (st.done[f]) continue;
    const auto& c = t.tri[f];
    int k = -1;
    for (int i = 0; i < 3; ++i)
      if (!st.placed[c[(i + 2) % 3]]) k = i;
    if (k < 0) {
      // All three corners are placed: a loop of triangles closes here.
      finish(f);
      ++stats.closures;
      st.relax(f, prm.relax_rings, prm.relax_sweeps, region, mark, stamp);
      continue;
    }
    // Side k = (c[k], c[k+1]) is placed (f was queued across it); the new
    // corner is c[k+2], at distances |c[k+2] c[k]| (side k+2) and
    // |c[k+1] c[k+2]| (side k+1).
    const std::uint32_t a = c[k], b = c[(k + 1) % 3], v = c[(k + 2) % 3];
    uv[v] = circle_apex(uv[a], uv[b], length(f, (k + 2) % 3), length(f, (k + 1) % 3));
    st.placed[v] = 1;
    finish(f);
  }
  // Triangles still flipped (saddles: a loop that closed on too much angle):
  // relax around all of them together, wider each round.
  for (int round = 0; round < 6; ++round) {
    region.clear();
    for (std::uint32_t f = 0; f < nt; ++f)
      if (st.bad(f)) region.insert(region.end(), t.tri[f].begin(), t.tri[f].end());
    if (region.empty()) break;
    std::sort(region.begin(), region.end());
    region.erase(std::unique(region.begin(), region.end()), region.end());
    st.grow(region, 2 + 2 * round, mark, ++stamp);
    st.sweep(region, 4);
  }
  stats.phase1_ms = ms_since(t0);
}

void tutte_embedding(const PieceTopology& t, const RestState& rest, std::vector<Vec2d>& uv) {
  const std::size_t n = t.vertex_count();
  uv.assign(n, Vec2d::Zero());
  // The longest loop goes on a circle, clockwise (the front lies to the right
  // of a boundary chain), spaced by its 3D arc length.
  std::size_t outer = 0;
  std::vector<double> perimeter(t.loops.size(), 0);
  auto edge_len = [&](std::uint32_t a, std::uint32_t b) {
    for (std::uint32_t k = t.vs_off[a]; k < t.vs_off[a + 1]; ++k)
      if (t.vs_other[k] == b) return rest.length[t.vs_spring[k]];
    return 0.0;
  };
  for (std::size_t l = 0; l < t.loops.size(); ++l) {
    const auto& lp = t.loops[l];
    for (std::size_t i = 0; i < lp.size(); ++i) perimeter[l] += edge_len(lp[i], lp[(i + 1) % lp.size()]);
    if (perimeter[l] > perimeter[outer]) outer = l;
  }
  std::vector<std::uint8_t> fixed(n, 0);
  const auto& lp = t.loops[outer];
  const double P = perimeter[outer], R = P / (2 * M_PI);
  double s = 0;
  for (std::size_t i = 0; i < lp.size(); ++i) {
    const double th = -2 * M_PI * s / P;
    uv[lp[i]] = R * Vec2d(std::cos(th), std::sin(th));
    fixed[lp[i]] = 1;
    s += edge_len(lp[i], lp[(i + 1) % lp.size()]);
  }
  std::vector<std::uint32_t> free_index(n, kNone);
  std::uint32_t nf = 0;
  for (std::size_t v = 0; v < n; ++v)
    if (!fixed[v]) free_index[v] = nf++;
  if (nf == 0) return;
  std::vector<Eigen::Triplet<double>> trip;
  Eigen::MatrixX2d rhs = Eigen::MatrixX2d::Zero(nf, 2);
  for (std::size_t v = 0; v < n; ++v) {
    if (fixed[v]) continue;
    double diag = 0;
    for (std::uint32_t k = t.vs_off[v]; k < t.vs_off[v + 1]; ++k) {
      const double w = rest.stiffness[t.vs_spring[k]];
      const std::uint32_t o = t.vs_other[k];
      diag += w;
      if (fixed[o])
        rhs.row(free_index[v]) += w * uv[o].transpose();
      else
        trip.emplace_back(free_index[v], free_index[o], -w);
    }
    trip.emplace_back(free_index[v], free_index[v], diag);
  }
  Eigen::SparseMatrix<double> A(nf, nf);
  A.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt(A);
  if (llt.info() != Eigen::Success) return;
  const Eigen::MatrixX2d x = llt.solve(rhs);
  for (std::size_t v = 0; v < n; ++v)
    if (!fixed[v]) uv[v] = x.row(free_index[v]).transpose();
}
}  // namespace atelier::pattern_detail
