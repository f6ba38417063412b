#include <atelier/engine/math.h>
#include <atelier/systems/smooth/fairing.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <new>
#include <sstream>
#include <utility>

#include <atelier/engine/cpu_features.h>
#include <atelier/engine/parallel.h>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace atelier {

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
// SSE packets or one AVX register and the per-component arithmetic is
// exactly that of Vec3d.
using P4 = Eigen::Vector4d;

/// 64-byte aligned storage: an AVX load of a point never splits a cache line.
template <class T>
struct Aligned64 {
  using value_type = T;
  Aligned64() = default;
  template <class U>
  Aligned64(const Aligned64<U>&) noexcept {}  // NOLINT: allocators rebind implicitly
  [[nodiscard]] T* allocate(std::size_t n) {
    return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t{64}));
  }
  void deallocate(T* p, std::size_t) noexcept { ::operator delete(p, std::align_val_t{64}); }
  /// Default-initialises (no zero fill: every entry is written before it is read).
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... A>
  void construct(U* p, A&&... a) {
    ::new (static_cast<void*>(p)) U(std::forward<A>(a)...);
  }
  friend bool operator==(const Aligned64&, const Aligned64&) noexcept { return true; }
};
using P4Array = std::vector<P4, Aligned64<P4>>;

/// sum_j x[j & mask] over a ring (regular valence 6 unrolled as a tree of
/// three levels instead of a chain of five dependent adds; other valences
/// in ring order). mask = ~0 for positions, window - 1 for the rolling
/// window of U.
inline P4 ring_sum(const P4* x, const std::uint32_t* nb, std::uint32_t b, std::uint32_t e,
                   std::uint32_t mask) noexcept {
  if (e - b == 6) {
    const std::uint32_t* r = nb + b;
    return ((x[r[0] & mask] + x[r[1] & mask]) + (x[r[2] & mask] + x[r[3] & mask])) +
           (x[r[4] & mask] + x[r[5] & mask]);
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

/// One block [b, e) of active nodes in one Jacobi iteration. U(j) is made
/// when the sweep reaches j - band and read until j + band, so a rolling
/// window of 2 band + 1 entries (u, index & mask) holds every U a node's
/// U2 needs: U and U2 in one streaming pass (seed 000 section 4.2).
struct Sweep {
  const P4* cur = nullptr;
  P4* nxt = nullptr;
  P4* u = nullptr;  // the block's window
  const std::uint32_t* off = nullptr;
  const std::uint32_t* nb = nullptr;
  const double* inv_deg = nullptr;
  const double* inv_nu = nullptr;
  std::size_t band = 0, nactive = 0;
  std::uint32_t mask = 0;
};

/// Portable kernel (SSE2 through Eigen); with Collide, every move goes
/// through collide_move. Returns the largest squared move.
template <bool Collide>
double sweep_portable(const Sweep& s, std::size_t b, std::size_t e, const FairParams* prm,
                      CollisionState* cs) {
  std::size_t next_u = b > s.band ? b - s.band : 0;  // next U to make
  const std::size_t u_end = std::min(s.nactive, e + s.band);
  double mx = 0;
  for (std::size_t i = b; i < e; ++i) {
    // U(p) = 1/n sum_j p_j - p up to i + band.
    for (const std::size_t last = std::min(u_end, i + s.band + 1); next_u < last; ++next_u) {
      const std::uint32_t k0 = s.off[next_u], k1 = s.off[next_u + 1];
      s.u[next_u & s.mask] = ring_sum(s.cur, s.nb, k0, k1, ~0u) * s.inv_deg[k1 - k0] - s.cur[next_u];
    }
    if (!(s.inv_nu[i] > 0.0)) continue;  // not free
    // p <- p - w U2(p) / nu, U2 = 1/n sum_j U(p_j) - U(p).
    const std::uint32_t k0 = s.off[i], k1 = s.off[i + 1];
    const P4 step = -s.inv_nu[i] * (ring_sum(s.u, s.nb, k0, k1, s.mask) * s.inv_deg[k1 - k0] - s.u[i & s.mask]);
    P4 q = s.cur[i] + step;
    if constexpr (Collide) {
      const Vec3d q3 = collide_move(*prm, *cs, i, s.cur[i].head<3>(), step.head<3>());
      q = P4(q3.x(), q3.y(), q3.z(), 0.0);
    }
    const P4 d = q - s.cur[i];
    mx = std::max(mx, (d.x() * d.x() + d.y() * d.y()) + d.z() * d.z());
    s.nxt[i] = q;
  }
  return mx;
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define ATELIER_FAIR_AVX2 1

// The AVX2 kernel: a point is one 256-bit register, so each ring term is
// one load and one add instead of two of each. The operations and their
// order are those of sweep_portable and "avx2" does not enable FMA, so no
// multiply-add is contracted: the results are bit-identical to the
// portable kernel (tests check it).
#define ATELIER_AVX2_FN __attribute__((target("avx2"), always_inline)) inline

bool have_avx2() noexcept { return cpu_features().avx2; }

ATELIER_AVX2_FN __m256d ring_sum_avx2(const double* x, const std::uint32_t* nb, std::uint32_t b, std::uint32_t e,
                                      std::uint32_t mask) noexcept {
  if (e - b == 6) {
    const std::uint32_t* r = nb + b;
    auto at = [&](int k) { return x + 4 * std::size_t(r[k] & mask); };
    const __m256d s01 = _mm256_add_pd(_mm256_load_pd(at(0)), _mm256_load_pd(at(1)));
    const __m256d s23 = _mm256_add_pd(_mm256_load_pd(at(2)), _mm256_load_pd(at(3)));
    const __m256d s45 = _mm256_add_pd(_mm256_load_pd(at(4)), _mm256_load_pd(at(5)));
    return _mm256_add_pd(_mm256_add_pd(s01, s23), s45);
  }
  __m256d s = _mm256_load_pd(x + 4 * std::size_t(nb[b] & mask));
  for (std::uint32_t k = b + 1; k < e; ++k) s = _mm256_add_pd(s, _mm256_load_pd(x + 4 * std::size_t(nb[k] & mask)));
  return s;
}

__attribute__((target("avx2"))) double sweep_avx2(const Sweep& s, std::size_t b, std::size_t e) noexcept {
  const double* cur = s.cur->data();
  double* nxt = s.nxt->data();
  double* u = s.u->data();
  std::size_t next_u = b > s.band ? b - s.band : 0;
  const std::size_t u_end = std::min(s.nactive, e + s.band);
  __m128d mx = _mm_setzero_pd();
  for (std::size_t i = b; i < e; ++i) {
    for (const std::size_t last = std::min(u_end, i + s.band + 1); next_u < last; ++next_u) {
      const std::uint32_t k0 = s.off[next_u], k1 = s.off[next_u + 1];
      const __m256d sum = ring_sum_avx2(cur, s.nb, k0, k1, ~0u);
      _mm256_store_pd(u + 4 * (next_u & s.mask),
                      _mm256_sub_pd(_mm256_mul_pd(sum, _mm256_set1_pd(s.inv_deg[k1 - k0])),
                                    _mm256_load_pd(cur + 4 * next_u)));
    }
    if (!(s.inv_nu[i] > 0.0)) continue;
    const std::uint32_t k0 = s.off[i], k1 = s.off[i + 1];
    const __m256d su = ring_sum_avx2(u, s.nb, k0, k1, s.mask);
    const __m256d u2 = _mm256_sub_pd(_mm256_mul_pd(su, _mm256_set1_pd(s.inv_deg[k1 - k0])),
                                     _mm256_load_pd(u + 4 * (i & s.mask)));
    const __m256d step = _mm256_mul_pd(_mm256_set1_pd(-s.inv_nu[i]), u2);
    const __m256d c = _mm256_load_pd(cur + 4 * i);
    const __m256d q = _mm256_add_pd(c, step);
    const __m256d d = _mm256_sub_pd(q, c);
    const __m256d d2 = _mm256_mul_pd(d, d);
    const __m128d xy = _mm256_castpd256_pd128(d2);
    // (dx dx + dy dy) + dz dz, as the portable kernel sums it.
    const __m128d n2 = _mm_add_sd(_mm_add_sd(xy, _mm_unpackhi_pd(xy, xy)), _mm256_extractf128_pd(d2, 1));
    mx = _mm_max_sd(n2, mx);  // max(mx, n2) for non-NaN moves
    _mm256_store_pd(nxt + 4 * i, q);
  }
  return _mm_cvtsd_f64(mx);
}
#endif

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
#ifdef ATELIER_FAIR_AVX2
  const bool avx2 = !collide && prm.allow_avx2 && have_avx2();
#else
  const bool avx2 = false;
#endif
  rep.avx2 = avx2;

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

  // Blocks of active nodes (see Sweep), a partition that only shapes the
  // work: every U is the same function of the positions in any block, so
  // results do not depend on it. Equal blocks, a fixed number per thread so
  // no thread idles on an odd last block; each block recomputes the U of
  // the band before and after it, so blocks stay wider than a few bands.
  const std::size_t band = plan.bandwidth;
  std::size_t window = 1;
  while (window < 2 * band + 2) window <<= 1;
  const bool sequential = ctx.threads == 1 || nactive < ctx.sequential_threshold;
  const std::size_t threads =
      ctx.threads > 0 ? static_cast<std::size_t>(ctx.threads)
                      : static_cast<std::size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
  constexpr std::size_t kBlocksPerThread = 2;
  std::size_t blocks = sequential ? 1 : threads * kBlocksPerThread;
  std::size_t block = (nactive + blocks - 1) / blocks;
  if (blocks > 1 && block < std::max<std::size_t>(1024, 4 * band)) block = std::max<std::size_t>(1024, 4 * band);
  blocks = (nactive + block - 1) / block;

  // Double buffer over the local range: nodes that do not move hold the same
  // value in both and free nodes are rewritten every iteration, so no copy
  // pass is needed. First touch by block, as the sweeps will read them.
  P4Array buf_a(nlocal), buf_b(nlocal), rings(blocks * window);
  P4* cur = buf_a.data();
  P4* nxt = buf_b.data();
  const double* inv_nu = plan.inv_nu.data();

  std::vector<double> block_max(blocks);
  bool cancelled = false;
  // One arena for the whole run (not one per loop): the workers stay in it
  // from the first copy to the last.
  par::in_arena(ctx, [&] {
    ExecContext ictx = ctx;
    if (ctx.threads > 1) ictx.threads = 0;  // run in the enclosing arena
    par::for_each_block(ictx, nlocal, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) cur[i] = nxt[i] = P4(p[local[i]].x(), p[local[i]].y(), p[local[i]].z(), 0.0);
    });
    ExecContext bctx = ictx;
    bctx.grain = 1;
    bctx.sequential_threshold = 2;
    for (int it = 0; it < prm.iterations; ++it) {
      if (ctx.cancelled()) {
        cancelled = true;
        return;
      }
      par::for_each_n(bctx, blocks, [&](std::size_t blk) {
        Sweep s;
        s.cur = cur;
        s.nxt = nxt;
        s.u = rings.data() + blk * window;
        s.off = plan.offset.data();
        s.nb = plan.neighbor.data();
        s.inv_deg = plan.inv_degree.data();
        s.inv_nu = inv_nu;
        s.band = band;
        s.nactive = nactive;
        s.mask = static_cast<std::uint32_t>(window - 1);
        const std::size_t b = blk * block, e = std::min(nactive, b + block);
        if (collide)
          block_max[blk] = sweep_portable<true>(s, b, e, &prm, &cs);
#ifdef ATELIER_FAIR_AVX2
        else if (avx2)
          block_max[blk] = sweep_avx2(s, b, e);
#endif
        else
          block_max[blk] = sweep_portable<false>(s, b, e, nullptr, nullptr);
      });
      std::swap(cur, nxt);
      rep.iterations = it + 1;
      double mx = 0;
      for (double b : block_max) mx = std::max(mx, b);  // max is exact in any order
      rep.last_max_move = std::sqrt(mx);
      if (rep.last_max_move <= prm.tolerance) break;
    }
    par::for_each_block(ictx, nactive, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i)
        if (inv_nu[i] > 0.0) p[local[i]] = cur[i].head<3>();
    });
  });
  if (cancelled) return Status(ErrorCode::kCancelled, "fair_umbrella cancelled");
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
