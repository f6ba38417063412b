#include <atelier/systems/garment/detail_template.h>

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>

#include <atelier/engine/cpu_features.h>
#include <atelier/engine/parallel.h>
#include <atelier/systems/body/body_set.h>

namespace atelier {

// ------------------------------------------------------------- body polygons

namespace {
std::uint64_t fnv1a(std::uint64_t h, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}
}  // namespace

BodyPolygons BodyPolygons::from_model(const Model& body) {
  return from_model(body, SurfaceIdx{});
}

BodyPolygons BodyPolygons::from_model(const Model& body, SurfaceIdx surface) {
  BodyPolygons b;
  b.node_count = static_cast<std::uint32_t>(body.nodes.slots.capacity());
  std::vector<NodeIdx> fn;
  for (std::uint32_t f = 0; f < body.faces.slots.capacity(); ++f) {
    if (!body.alive(FaceIdx{f})) continue;
    if (surface.valid() && body.faces.surface[f] != surface) continue;
    body.face_nodes(FaceIdx{f}, fn);
    for (NodeIdx v : fn) b.face_nodes.push_back(v.value);
    b.face_offsets.push_back(static_cast<std::uint32_t>(b.face_nodes.size()));
  }
  std::uint64_t h = 0xcbf29ce484222325ull;
  h = fnv1a(h, &b.node_count, sizeof b.node_count);
  h = fnv1a(h, b.face_offsets.data(), b.face_offsets.size() * 4);
  h = fnv1a(h, b.face_nodes.data(), b.face_nodes.size() * 4);
  b.topology_hash = h;
  return b;
}

// -------------------------------------------------------------------- frames

namespace {

struct FrameD {
  Vec3d c, x, y, z;
  bool degenerate;
};

// Eq. (8). The normal is Newell's (exact for planar polygons, a robust
// average otherwise). Y is p_1 - p_c with its normal component removed, so
// the frame is orthonormal even for non-planar quads and encoding then
// decoding on the same body returns q exactly.
//
// With `ref` (fitted frames), Y is then turned by the best-fit rotation of
// the polygon's corners onto their reference shape (2D Procrustes: the angle
// maximising sum r_k . R d_k, whose cosine and sine are (sdot, scross)
// normalised). Scalar code over a local copy of the corners: this runs for
// every polygon of every decoded body.
//
// `p.get(node, xyz)` gives a node's position (from a span of doubles, or a
// body set's float columns read in place).
template <class Pos>
FrameD polygon_frame(const BodyPolygons& b, const Pos& p, std::size_t f, std::span<const Eigen::Vector2f> ref = {}) {
  const std::uint32_t s = b.face_offsets[f], e = b.face_offsets[f + 1];
  const std::size_t n = e - s;
  constexpr std::size_t kLocal = 16;
  double local[3 * kLocal];
  std::vector<double> big;
  double* P = local;
  if (n > kLocal) {
    big.resize(3 * n);
    P = big.data();
  }
  for (std::size_t k = 0; k < n; ++k) p.get(b.face_nodes[s + k], P + 3 * k);
  double c[3] = {0, 0, 0}, nr[3] = {0, 0, 0}, scale = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double* A = P + 3 * k;
    const double* Q = P + 3 * (k + 1 < n ? k + 1 : 0);
    c[0] += A[0];
    c[1] += A[1];
    c[2] += A[2];
    nr[0] += A[1] * Q[2] - A[2] * Q[1];
    nr[1] += A[2] * Q[0] - A[0] * Q[2];
    nr[2] += A[0] * Q[1] - A[1] * Q[0];
    const double d0 = Q[0] - A[0], d1 = Q[1] - A[1], d2 = Q[2] - A[2];
    scale = std::max(scale, d0 * d0 + d1 * d1 + d2 * d2);
  }
  const double inv_n = 1.0 / static_cast<double>(n);
  c[0] *= inv_n;
  c[1] *= inv_n;
  c[2] *= inv_n;
  FrameD fr;  // every field is set below (a zeroing constructor costs more than the arithmetic)
  fr.c = Vec3d(c[0], c[1], c[2]);
  fr.x = fr.y = fr.z = Vec3d::Zero();
  const double nn = std::sqrt(nr[0] * nr[0] + nr[1] * nr[1] + nr[2] * nr[2]);
  if (!(nn > 1e-12 * scale) || !(scale > 0)) {
    fr.degenerate = true;
    return fr;
  }
  const double inv_nn = 1.0 / nn;
  const double x[3] = {nr[0] * inv_nn, nr[1] * inv_nn, nr[2] * inv_nn};
  double y[3] = {P[0] - c[0], P[1] - c[1], P[2] - c[2]};
  const double yx = y[0] * x[0] + y[1] * x[1] + y[2] * x[2];
  y[0] -= yx * x[0];
  y[1] -= yx * x[1];
  y[2] -= yx * x[2];
  const double yn = std::sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]);
  fr.x = Vec3d(x[0], x[1], x[2]);
  if (!(yn > 1e-9 * std::sqrt(scale))) {
    fr.degenerate = true;
    return fr;
  }
  const double inv_yn = 1.0 / yn;
  y[0] *= inv_yn;
  y[1] *= inv_yn;
  y[2] *= inv_yn;
  double z[3] = {x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2], x[0] * y[1] - x[1] * y[0]};
  if (!ref.empty()) {
    double sdot = 0, scross = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const double q[3] = {P[3 * k] - c[0], P[3 * k + 1] - c[1], P[3 * k + 2] - c[2]};
      const double d1 = q[0] * y[0] + q[1] * y[1] + q[2] * y[2];
      const double d2 = q[0] * z[0] + q[1] * z[1] + q[2] * z[2];
      const double r1 = ref[s + k].x(), r2 = ref[s + k].y();
      sdot += r1 * d1 + r2 * d2;
      scross += r1 * d2 - r2 * d1;
    }
    const double r = std::sqrt(sdot * sdot + scross * scross);  // sums of squared lengths: no overflow to fear
    if (r > 0) {                                                // else no preferred angle (atan2(0, 0) = 0)
      const double inv_r = 1.0 / r, cs = sdot * inv_r, sn = scross * inv_r;
      for (int i = 0; i < 3; ++i) y[i] = cs * y[i] + sn * z[i];
      z[0] = x[1] * y[2] - x[2] * y[1];
      z[1] = x[2] * y[0] - x[0] * y[2];
      z[2] = x[0] * y[1] - x[1] * y[0];
    }
  }
  fr.y = Vec3d(y[0], y[1], y[2]);
  fr.z = Vec3d(z[0], z[1], z[2]);
  fr.degenerate = false;
  return fr;
}

struct SpanPos {
  std::span<const Vec3d> p;
  void get(std::uint32_t n, double* out) const noexcept {
    out[0] = p[n].x();
    out[1] = p[n].y();
    out[2] = p[n].z();
  }
};

}  // namespace

void compute_frames(const BodyPolygons& b, std::span<const Vec3d> p, PolygonFrames& out, const ExecContext& ctx,
                    std::span<const Eigen::Vector2f> ref) {
  const std::size_t n = b.size();
  out.centroid.resize(n);
  out.x.resize(n);
  out.y.resize(n);
  out.z.resize(n);
  out.degenerate.resize(n);
  const SpanPos pos{p};
  par::for_each_n(ctx, n, [&](std::size_t f) {
    const FrameD fr = polygon_frame(b, pos, f, ref);
    out.centroid[f] = fr.c.cast<float>();
    out.x[f] = fr.x.cast<float>();
    out.y[f] = fr.y.cast<float>();
    out.z[f] = fr.z.cast<float>();
    out.degenerate[f] = fr.degenerate;
  });
}

// ---------------------------------------------------------------- the grid

namespace {
using Cand = std::pair<double, std::uint32_t>;  // (squared distance, polygon): lexicographic = tie-break by index
}

void nearest_brute_force(std::span<const Vec3d> c, std::span<const std::uint8_t> skip, const Vec3d& q, std::size_t k,
                         std::vector<std::uint32_t>& out) {
  std::vector<Cand> all;
  all.reserve(c.size());
  for (std::uint32_t i = 0; i < c.size(); ++i)
    if (skip.empty() || !skip[i]) all.emplace_back((c[i] - q).squaredNorm(), i);
  k = std::min(k, all.size());
  std::partial_sort(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(k), all.end());
  out.clear();
  for (std::size_t i = 0; i < k; ++i) out.push_back(all[i].second);
}

void CentroidGrid::build(std::span<const Vec3d> c, std::span<const std::uint8_t> skip, std::size_t k_hint,
                         double cell) {
  Box3d box;
  std::vector<std::uint32_t> live;
  for (std::uint32_t i = 0; i < c.size(); ++i)
    if (skip.empty() || !skip[i]) {
      box.extend(c[i]);
      live.push_back(i);
    }
  if (live.empty()) {
    start_.assign(2, 0);
    ids_.clear();
    exact_.clear();
    by_id_.clear();
    nx_ = ny_ = nz_ = 1;
    return;
  }
  k_hint_ = std::max<std::size_t>(k_hint, 8);
  if (cell <= 0) {
    // Cell = half the typical distance to the k-th nearest centroid, measured
    // on a deterministic sample, so a query touches a few rings of boxes.
    // The sample points are centroids themselves: skip them (k + 1), and
    // size for at least 8 neighbours so k = 1 does not make tiny cells.
    const std::size_t k = std::clamp<std::size_t>(std::max<std::size_t>(k_hint, 8) + 1, 1, live.size());
    std::vector<double> radii;
    std::vector<double> d2(live.size());
    const std::size_t samples = std::min<std::size_t>(32, live.size());
    for (std::size_t s = 0; s < samples; ++s) {
      const Vec3d& q = c[live[(s * 2654435761ull) % live.size()]];
      for (std::size_t j = 0; j < live.size(); ++j) d2[j] = (c[live[j]] - q).squaredNorm();
      std::nth_element(d2.begin(), d2.begin() + static_cast<std::ptrdiff_t>(k - 1), d2.end());
      radii.push_back(std::sqrt(d2[k - 1]));
    }
    std::sort(radii.begin(), radii.end());
    radius_ = radii[radii.size() / 2];
    cell = radius_ * 0.5;
  } else {
    radius_ = 2 * cell;
  }
  // Never more boxes than about 4 per centroid (duplicates or a degenerate
  // sample must not blow the grid up).
  const Vec3d ext0 = (box.hi - box.lo).cwiseMax(1e-12);
  const double min_cell = std::cbrt(ext0.prod() / (4.0 * static_cast<double>(live.size())));
  cell = std::max({cell, min_cell, 1e-9 * (1.0 + ext0.maxCoeff())});
  cell_ = cell;
  lo_ = box.lo;
  const Vec3d ext = box.hi - box.lo;
  auto dim = [&](double e) { return std::max(1, static_cast<int>(std::floor(e / cell)) + 1); };
  nx_ = dim(ext.x());
  ny_ = dim(ext.y());
  nz_ = dim(ext.z());
  const std::size_t ncell = static_cast<std::size_t>(nx_) * ny_ * nz_;
  auto cell_of = [&](const Vec3d& p) {
    const int i = std::clamp(static_cast<int>((p.x() - lo_.x()) / cell_), 0, nx_ - 1);
    const int j = std::clamp(static_cast<int>((p.y() - lo_.y()) / cell_), 0, ny_ - 1);
    const int k = std::clamp(static_cast<int>((p.z() - lo_.z()) / cell_), 0, nz_ - 1);
    return (static_cast<std::size_t>(k) * ny_ + j) * nx_ + i;
  };
  start_.assign(ncell + 1, 0);
  for (auto i : live) ++start_[cell_of(c[i]) + 1];
  for (std::size_t i = 0; i < ncell; ++i) start_[i + 1] += start_[i];
  ids_.resize(live.size());
  std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
  for (auto i : live) {  // increasing polygon index within each cell
    const auto slot = fill[cell_of(c[i])]++;
    ids_[slot] = i;
  }
  // Keep exact doubles for the distances (ties must match brute force).
  exact_.resize(live.size());
  for (std::size_t s = 0; s < live.size(); ++s) exact_[s] = c[ids_[s]];
  by_id_.assign(c.begin(), c.end());
}

template <class F>
void CentroidGrid::scan_ball(const Vec3d& q, double r2, F&& f) const {
  auto span_of = [&](double c, double r, double l, int n) {
    return std::pair<int, int>{std::clamp(static_cast<int>(std::floor((c - r - l) / cell_)), 0, n - 1),
                               std::clamp(static_cast<int>(std::floor((c + r - l) / cell_)), 0, n - 1)};
  };
  // Squared distance from coordinate c to box interval i along one axis.
  auto gap2 = [&](double c, double l, int i) {
    const double a = l + cell_ * i, b = a + cell_;
    const double g = c < a ? a - c : (c > b ? c - b : 0.0);
    return g * g;
  };
  // Boxes are pruned with a little slack: a centroid's box comes from
  // rounded arithmetic and may sit a rounding error outside it.
  const double reach = std::sqrt(r2) * (1 + 1e-9) + 1e-12 * cell_, reach2 = reach * reach;
  const auto [k_lo, k_hi] = span_of(q.z(), reach, lo_.z(), nz_);
  const auto [j_lo, j_hi] = span_of(q.y(), reach, lo_.y(), ny_);
  for (int kk = k_lo; kk <= k_hi; ++kk) {
    const double gz = gap2(q.z(), lo_.z(), kk);
    if (gz > reach2) continue;
    for (int j = j_lo; j <= j_hi; ++j) {
      // Only the boxes of this row the ball reaches (a cube scans about
      // twice as many centroids).
      const double gyz = gz + gap2(q.y(), lo_.y(), j);
      if (gyz > reach2) continue;
      const double half = std::sqrt(reach2 - gyz);
      const auto [i_lo, i_hi] = span_of(q.x(), half, lo_.x(), nx_);
      const std::size_t row = (static_cast<std::size_t>(kk) * ny_ + j) * nx_;
      const std::uint32_t b = start_[row + i_lo], e = start_[row + i_hi + 1];  // cells i_lo..i_hi are contiguous
      if (b < e) f(b, e);
    }
  }
}

namespace {
double select_sorted(std::vector<Cand>& cand, std::size_t k, double max2, std::vector<std::uint32_t>& count,
                     std::vector<std::uint32_t>& out) {
  // The k smallest (distance, index) pairs in order, all distances at most
  // max2. A counting sort into buckets of equal width in d2 (centroids on a
  // surface are about uniform in d2 around a query) keeps only the buckets
  // up to the one holding the k-th pair, which are then put in exact order.
  // Unlike nth_element and sort, this has few unpredictable branches.
  // Buckets are monotone in d2, so the cut drops none of the k.
  const std::size_t n = cand.size();
  double lo = max2;
  for (const Cand& c : cand) lo = std::min(lo, c.first);
  const std::size_t nb = 2 * n;
  const double scale = static_cast<double>(nb) / (max2 - lo);
  if (!(max2 > lo) || !std::isfinite(scale)) {
    std::sort(cand.begin(), cand.end());
  } else {
    count.assign(nb + 1, 0);
    auto bucket = [&](double d2) { return std::min(nb - 1, static_cast<std::size_t>((d2 - lo) * scale)); };
    for (const Cand& c : cand) ++count[bucket(c.first) + 1];
    std::size_t last = 0;  // bucket holding the k-th pair
    for (std::size_t b = 0; b < nb; ++b) {
      count[b + 1] += count[b];
      if (count[b] < k) last = b;
    }
    // The kept pairs go after the candidates, then move to the front; the
    // others land (branch-free) on one spare slot past them.
    const std::size_t keep = count[last + 1];
    cand.resize(n + keep + 1);
    Cand* sorted = cand.data() + n;
    count[nb] = static_cast<std::uint32_t>(keep);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t b = bucket(cand[i].first);
      const bool kept = b <= last;
      const std::size_t slot = kept ? b : nb;
      sorted[count[slot]] = cand[i];
      count[slot] += kept;
    }
    // Only pairs of one bucket can be out of order: an insertion sort
    // rarely moves anything, and its branches are predictable. A crowded
    // bucket (many equal distances) would make it quadratic: sort then.
    std::size_t crowded = 0;
    for (std::size_t b = 0, begin = 0; b <= last; begin = count[b++]) crowded = std::max(crowded, count[b] - begin);
    if (crowded > 32) {
      std::sort(sorted, sorted + keep);
    } else {
      for (std::size_t i = 1; i < keep; ++i) {
        const Cand x = sorted[i];
        std::size_t j = i;
        for (; j > 0 && x < sorted[j - 1]; --j) sorted[j] = sorted[j - 1];
        sorted[j] = x;
      }
    }
    std::copy(sorted, sorted + k, cand.begin());
  }
  cand.resize(k);
  for (const auto& c : cand) out.push_back(c.second);
  return std::sqrt(cand.back().first);
}
}  // namespace

void CentroidGrid::nearest(const Vec3d& q, std::size_t k, std::vector<std::uint32_t>& out,
                           std::vector<std::pair<double, std::uint32_t>>& heap) const {
  (void)nearest_bounded(q, k, std::numeric_limits<double>::infinity(), out, heap);
}

double CentroidGrid::nearest_bounded(const Vec3d& q, std::size_t k, double bound, std::vector<std::uint32_t>& out,
                                     std::vector<std::pair<double, std::uint32_t>>& heap) const {
  std::vector<std::uint32_t> count;
  return nearest_bounded(q, k, bound, out, heap, count);
}

double CentroidGrid::nearest_bounded(const Vec3d& q, std::size_t k, double bound, std::vector<std::uint32_t>& out,
                                     std::vector<std::pair<double, std::uint32_t>>& heap,
                                     std::vector<std::uint32_t>& count) const {
  out.clear();
  heap.clear();
  k = std::min(k, ids_.size());
  if (k == 0) return 0.0;
  // Candidates farther than the bound can never be among the k nearest.
  const double bound2 = bound * bound;
  if (bound2 < std::numeric_limits<double>::infinity()) {
    // With a bound no heap is needed: collect every centroid inside the
    // bound from the boxes the bound's cube overlaps, then select the k
    // smallest (distance, index) pairs: the same set and order as brute force.
    scan_ball(q, bound2, [&](std::uint32_t b, std::uint32_t e) {
      std::size_t n = heap.size();
      heap.resize(n + (e - b));
      for (std::uint32_t s = b; s < e; ++s) {  // branch-free: most tests are unpredictable
        const double d2 = (exact_[s] - q).squaredNorm();
        heap[n] = Cand(d2, ids_[s]);
        n += d2 <= bound2;
      }
      heap.resize(n);
    });
    if (heap.size() < k) return nearest_bounded(q, k, std::numeric_limits<double>::infinity(), out, heap, count);
    return select_sorted(heap, k, bound2, count, out);
  }
  const int i0 = std::clamp(static_cast<int>(std::floor((q.x() - lo_.x()) / cell_)), 0, nx_ - 1);
  const int j0 = std::clamp(static_cast<int>(std::floor((q.y() - lo_.y()) / cell_)), 0, ny_ - 1);
  const int k0 = std::clamp(static_cast<int>(std::floor((q.z() - lo_.z()) / cell_)), 0, nz_ - 1);
  const int hmax = std::max({i0, nx_ - 1 - i0, j0, ny_ - 1 - j0, k0, nz_ - 1 - k0});
  auto visit_cell = [&](int i, int j, int kk) {
    const std::size_t c = (static_cast<std::size_t>(kk) * ny_ + j) * nx_ + i;
    const std::uint32_t b = start_[c], e = start_[c + 1];
    if (b == e) return;
    {
      // Prune boxes entirely farther than the current k-th candidate or the bound.
      const double limit = heap.size() == k ? heap.front().first : bound2;
      const Vec3d blo = lo_ + cell_ * Vec3d(i, j, kk);
      const Vec3d d = (blo - q).cwiseMax(q - (blo.array() + cell_).matrix()).cwiseMax(0.0);
      if (d.squaredNorm() > limit) return;
    }
    for (std::uint32_t s = b; s < e; ++s) {
      const Cand cand((exact_[s] - q).squaredNorm(), ids_[s]);
      if (cand.first > bound2) continue;
      if (heap.size() < k) {
        heap.push_back(cand);
        std::push_heap(heap.begin(), heap.end());
      } else if (cand < heap.front()) {
        std::pop_heap(heap.begin(), heap.end());
        heap.back() = cand;
        std::push_heap(heap.begin(), heap.end());
      }
    }
  };
  for (int h = 0; h <= hmax; ++h) {
    // The shell of boxes at Chebyshev distance h from (i0, j0, k0).
    for (int di = -h; di <= h; ++di) {
      const int i = i0 + di;
      if (i < 0 || i >= nx_) continue;
      for (int dj = -h; dj <= h; ++dj) {
        const int j = j0 + dj;
        if (j < 0 || j >= ny_) continue;
        const bool face = std::abs(di) == h || std::abs(dj) == h;
        for (int dk = -h; dk <= h; dk += face ? 1 : std::max(1, 2 * h)) {
          const int kk = k0 + dk;
          if (kk >= 0 && kk < nz_) visit_cell(i, j, kk);
        }
      }
    }
    if (heap.size() == k) {
      // Unvisited boxes lie outside the block of rings 0..h: a lower bound on
      // their distance is q's distance to that block's nearest open side.
      double ring = std::numeric_limits<double>::infinity();
      auto side = [&](int c0, int n, double qc, double l) {
        if (c0 - h > 0) ring = std::min(ring, qc - (l + cell_ * (c0 - h)));
        if (c0 + h < n - 1) ring = std::min(ring, l + cell_ * (c0 + h + 1) - qc);
      };
      side(i0, nx_, q.x(), lo_.x());
      side(j0, ny_, q.y(), lo_.y());
      side(k0, nz_, q.z(), lo_.z());
      if (ring > 0 && heap.front().first < ring * ring) break;
    }
  }
  const double kth = std::sqrt(heap.front().first);
  std::sort_heap(heap.begin(), heap.end());
  for (const auto& c : heap) out.push_back(c.second);
  return kth;
}

void CentroidGrid::nearest_many(std::span<const Vec3d> queries, std::size_t k, std::span<std::uint32_t> out,
                                const ExecContext& ctx) const {
  k = std::min(k, ids_.size());
  if (k == 0) return;
  ExecContext c = ctx;
  c.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 256);
  c.grain = ctx.grain ? ctx.grain : 256;
  par::for_each_block(c, queries.size(), [&](std::size_t begin, std::size_t end) {
    std::vector<std::uint32_t> near, count;
    std::vector<Cand> scratch;
    scratch.reserve(8 * k);
    for (std::size_t v = begin; v < end; ++v) {
      if (ctx.cancelled()) return;
      const Vec3d& q = queries[v];
      double bound;
      if (v > begin) {
        // The previous query's k centroids all lie within their farthest
        // distance from q, so the k-th nearest of q does too (tighter than
        // the triangle inequality's k-th distance plus the step).
        double far2 = 0;
        for (const std::uint32_t id : out.subspan((v - 1) * k, k))
          far2 = std::max(far2, (by_id_[id] - q).squaredNorm());
        bound = std::sqrt(far2) * (1 + 1e-12) + 1e-300;
      } else {
        // First query of a block: twice the typical k-th distance from the
        // nearest point of the centroids' box; a bound that holds fewer than
        // k centroids is detected and the search redone without it.
        const Vec3d hi = lo_ + cell_ * Vec3d(nx_, ny_, nz_);
        const double out_of_box = (lo_ - q).cwiseMax(q - hi).cwiseMax(0.0).norm();
        bound =
            out_of_box +
            2 * radius_ * std::sqrt(static_cast<double>(std::max<std::size_t>(k, 8)) / static_cast<double>(k_hint_));
      }
      (void)nearest_bounded(q, k, bound, near, scratch, count);
      std::copy(near.begin(), near.end(), out.begin() + static_cast<std::ptrdiff_t>(v * k));
    }
  });
}

// ------------------------------------------------------------------ encode

Expected<DetailEncoding> encode_detail(const BodyPolygons& body, std::span<const Vec3d> bp,
                                       std::span<const Vec3d> garment, const DetailParams& params,
                                       const ExecContext& ctx) {
  const std::size_t np = body.size();
  if (np == 0) return Status(ErrorCode::kInvalidArgument, "encode_detail: the body has no polygons");
  if (bp.size() != body.node_count) {
    std::ostringstream s;
    s << "encode_detail: " << bp.size() << " body positions for a body of " << body.node_count << " nodes";
    return Status(ErrorCode::kMismatch, s.str());
  }
  for (std::size_t v = 0; v < garment.size(); ++v)
    if (!garment[v].allFinite()) {
      std::ostringstream s;
      s << "encode_detail: garment vertex " << v << " is not finite";
      return Status(ErrorCode::kDegenerate, s.str());
    }
  std::vector<FrameD> frames(np);
  par::for_each_n(ctx, np, [&](std::size_t f) { frames[f] = polygon_frame(body, SpanPos{bp}, f); });
  std::vector<Vec3d> centroids(np);
  std::vector<std::uint8_t> skip(np);
  std::size_t usable = 0;
  for (std::size_t f = 0; f < np; ++f) {
    centroids[f] = frames[f].c;
    skip[f] = frames[f].degenerate;
    usable += !skip[f];
  }
  std::size_t k = params.single_polygon        ? 1
                  : params.polygons_per_vertex ? params.polygons_per_vertex
                                               : static_cast<std::size_t>(std::lround(np / 100.0));
  k = std::max<std::size_t>(k, 1);
  if (usable < k) {
    std::ostringstream s;
    s << "encode_detail: the body has " << usable << " usable polygons, " << k << " are needed per vertex";
    return Status(ErrorCode::kInvalidArgument, s.str());
  }
  CentroidGrid grid;
  grid.build(centroids, skip, k, params.cell);

  DetailEncoding enc;
  if (params.fitted_frames) {
    enc.reference_corners.resize(body.face_nodes.size(), Eigen::Vector2f::Zero());
    for (std::size_t f = 0; f < np; ++f) {
      if (frames[f].degenerate) continue;
      for (std::uint32_t k = body.face_offsets[f]; k < body.face_offsets[f + 1]; ++k) {
        const Vec3d q = bp[body.face_nodes[k]] - frames[f].c;
        enc.reference_corners[k] =
            Eigen::Vector2f(static_cast<float>(q.dot(frames[f].y)), static_cast<float>(q.dot(frames[f].z)));
      }
    }
  }
  enc.polygon_count = static_cast<std::uint32_t>(np);
  enc.body_node_count = body.node_count;
  enc.topology_hash = body.topology_hash;
  const std::size_t nv = garment.size();
  enc.row.resize(nv + 1);
  for (std::size_t v = 0; v <= nv; ++v) enc.row[v] = static_cast<std::uint32_t>(v * k);
  enc.polygon.resize(nv * k);
  enc.a.resize(nv * k);
  enc.b.resize(nv * k);
  enc.c.resize(nv * k);
  enc.d.resize(nv * k);
  const double eps = params.epsilon;
  const bool taper = params.tapered_weights && usable > k;
  const std::size_t kq = taper ? k + 1 : k;
  std::vector<std::uint32_t> nearest(nv * kq);
  grid.nearest_many(garment, kq, nearest, ctx);
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "encode_detail cancelled");
  ExecContext c = ctx;
  c.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 256);
  c.grain = ctx.grain ? ctx.grain : 256;
  par::for_each_block(c, nv, [&](std::size_t begin, std::size_t end) {
    std::vector<std::uint32_t> near;
    std::vector<std::array<double, 5>> coef;
    for (std::size_t v = begin; v < end; ++v) {
      const Vec3d& q = garment[v];
      near.assign(nearest.begin() + static_cast<std::ptrdiff_t>(v * kq),
                  nearest.begin() + static_cast<std::ptrdiff_t>((v + 1) * kq));
      double w_cut = 0;
      if (taper) {
        w_cut = 1.0 / (eps + std::pow((q - frames[near.back()].c).norm(), 3));
        near.pop_back();
      }
      // Entries in polygon order: decoding then walks frames monotonically.
      std::sort(near.begin(), near.end());
      coef.resize(k);
      double wsum = 0;
      for (std::size_t i = 0; i < k; ++i) {
        const FrameD& fr = frames[near[i]];
        const Vec3d dq = q - fr.c;
        const double w = 1.0 / (eps + std::pow(dq.norm(), 3)) - w_cut;  // eq. (10), tapered
        coef[i] = {w, dq.dot(fr.x), dq.dot(fr.y), dq.dot(fr.z), 0};     // eq. (9)
        wsum += w;
      }
      if (!(wsum > 0)) {  // all k as far as the cut-off: plain eq. (10)
        wsum = 0;
        for (std::size_t i = 0; i < k; ++i) {
          coef[i][0] += w_cut;
          wsum += coef[i][0];
        }
      }
      for (std::size_t i = 0; i < k; ++i) {
        const std::size_t e = v * k + i;
        const double a = coef[i][0] / wsum;
        enc.polygon[e] = near[i];
        enc.a[e] = static_cast<float>(a);
        enc.b[e] = static_cast<float>(a * coef[i][1]);
        enc.c[e] = static_cast<float>(a * coef[i][2]);
        enc.d[e] = static_cast<float>(a * coef[i][3]);
      }
    }
  });
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "encode_detail cancelled");
  return enc;
}

Status check_topology(const DetailEncoding& enc, const BodyPolygons& body) {
  if (enc.polygon_count != body.size() || enc.body_node_count != body.node_count ||
      enc.topology_hash != body.topology_hash) {
    std::ostringstream s;
    s << "the body's topology (" << body.node_count << " nodes, " << body.size()
      << " polygons) differs from the one the detail template was encoded on (" << enc.body_node_count << " nodes, "
      << enc.polygon_count << " polygons)";
    return {ErrorCode::kMismatch, s.str()};
  }
  return {};
}

// ------------------------------------------------------------------ decode

namespace {

bool have_avx2_fma() noexcept { return cpu_features().avx2 && cpu_features().fma; }

bool have_avx512f() noexcept { return cpu_features().avx512f; }

// The widest kernel both the CPU and the caller allow.
DecodeKernel pick_kernel(DecodeKernel allow) noexcept {
  DecodeKernel k = have_avx512f()    ? DecodeKernel::kAvx512
                   : have_avx2_fma() ? DecodeKernel::kAvx2
                                     : DecodeKernel::kPortable;
  return allow != DecodeKernel::kAuto && allow > k ? allow : k;
}

// Frames of one body packed per polygon as 16 floats on a 64-byte line,
// transposed: (p_c.x, X.x, Y.x, Z.x, p_c.y, X.y, Y.y, Z.y, p_c.z, X.z, Y.z,
// Z.z, 0, 0, 0, 0). An entry's (a, b, c, d), broadcast to the four
// quarters, times the line gives the 12 products of eq. (12) in one
// 16-wide FMA; each quarter's sum is one coordinate.
struct PackedFrames {
  std::vector<float> storage;
  float* data = nullptr;
  void pack(const PolygonFrames& fr, const ExecContext& ctx) {
    const std::size_t n = fr.centroid.size();
    storage.assign(n * 16 + 16, 0.0f);
    const auto addr = reinterpret_cast<std::uintptr_t>(storage.data());
    data = storage.data() + ((64 - addr % 64) % 64) / sizeof(float);
    par::for_each_n(ctx, n, [&](std::size_t p) {
      float* f = data + p * 16;
      const Vec3f* v[4] = {&fr.centroid[p], &fr.x[p], &fr.y[p], &fr.z[p]};
      for (int j = 0; j < 4; ++j)
        for (int k = 0; k < 3; ++k) f[4 * k + j] = (*v[j])[k];
    });
  }
};

// A row's entries go round-robin into 4 accumulators (FMA latency 4, so 4
// entries are in flight); the accumulators are added (0 + 1) + (2 + 3) and
// each quarter summed as (l0 + l1) + (l2 + l3). The AVX-512 and AVX2
// kernels do exactly this per lane (the AVX2 one on two 8-lane halves of the
// same 16 lanes), so they give the same bits. An entry's (a, b, c, d) come
// from the encoding's four columns, four entries at a time, transposed in
// registers.
constexpr int kRowChains = 4;

__attribute__((target("avx2,fma"))) inline __m128 quarter_sums(__m128 x, __m128 y, __m128 z) {
  __m128 w = _mm_setzero_ps();
  _MM_TRANSPOSE4_PS(x, y, z, w);  // now x = lane 0 of each quarter, ...
  return _mm_add_ps(_mm_add_ps(x, y), _mm_add_ps(z, w));
}

// Entries e .. e+3 as (a, b, c, d) rows; past the row's end, zeros.
__attribute__((target("avx2,fma"), always_inline)) inline void coefficients4(const DetailEncoding& enc, std::uint32_t e,
                                                                             std::uint32_t e1, __m128* k) {
  if (e + 4 <= e1) {
    k[0] = _mm_loadu_ps(enc.a.data() + e);
    k[1] = _mm_loadu_ps(enc.b.data() + e);
    k[2] = _mm_loadu_ps(enc.c.data() + e);
    k[3] = _mm_loadu_ps(enc.d.data() + e);
  } else {
    alignas(16) float t[4][4] = {};
    for (std::uint32_t i = e; i < e1; ++i) {
      t[0][i - e] = enc.a[i];
      t[1][i - e] = enc.b[i];
      t[2][i - e] = enc.c[i];
      t[3][i - e] = enc.d[i];
    }
    for (int j = 0; j < 4; ++j) k[j] = _mm_load_ps(t[j]);
  }
  _MM_TRANSPOSE4_PS(k[0], k[1], k[2], k[3]);
}

// (The masked broadcasts and extracts with an all-ones mask are the plain
// instructions; their unmasked intrinsics pass GCC 12 an undefined source
// that -Wmaybe-uninitialized reports.)
// Eqs. (11)-(12), one body, AVX-512: per entry one 64-byte frame line times
// its (a, b, c, d) in every quarter, one FMA.
__attribute__((target("avx512f,avx2,fma"))) void decode_rows_avx512(const DetailEncoding& enc, const float* frames,
                                                                    std::size_t begin, std::size_t end, Vec3d* out) {
  const std::uint32_t* poly = enc.polygon.data();
  for (std::size_t v = begin; v < end; ++v) {
    __m512 s[kRowChains];
    for (auto& x : s) x = _mm512_setzero_ps();
    const std::uint32_t e1 = enc.row[v + 1];
    for (std::uint32_t e = enc.row[v]; e < e1; e += kRowChains) {
      __m128 k[4];
      coefficients4(enc, e, e1, k);
      for (std::uint32_t j = 0; j < kRowChains && e + j < e1; ++j)
        s[j] = _mm512_fmadd_ps(_mm512_mask_broadcast_f32x4(_mm512_setzero_ps(), 0xFFFF, k[j]),
                               _mm512_load_ps(frames + std::size_t{poly[e + j]} * 16), s[j]);
    }
    const __m512 t = _mm512_add_ps(_mm512_add_ps(s[0], s[1]), _mm512_add_ps(s[2], s[3]));
    alignas(16) float r[4];
    _mm_store_ps(r, quarter_sums(_mm512_mask_extractf32x4_ps(_mm_setzero_ps(), 0xF, t, 0),
                                 _mm512_mask_extractf32x4_ps(_mm_setzero_ps(), 0xF, t, 1),
                                 _mm512_mask_extractf32x4_ps(_mm_setzero_ps(), 0xF, t, 2)));
    out[v] = Vec3d(r[0], r[1], r[2]);
  }
}

// The same with AVX2: the line's two halves, two FMAs per entry.
__attribute__((target("avx2,fma"))) void decode_rows_avx2(const DetailEncoding& enc, const float* frames,
                                                          std::size_t begin, std::size_t end, Vec3d* out) {
  const std::uint32_t* poly = enc.polygon.data();
  for (std::size_t v = begin; v < end; ++v) {
    __m256 lo[kRowChains], hi[kRowChains];
    for (int j = 0; j < kRowChains; ++j) lo[j] = hi[j] = _mm256_setzero_ps();
    const std::uint32_t e1 = enc.row[v + 1];
    for (std::uint32_t e = enc.row[v]; e < e1; e += kRowChains) {
      __m128 k[4];
      coefficients4(enc, e, e1, k);
      for (std::uint32_t j = 0; j < kRowChains && e + j < e1; ++j) {
        const __m256 kk = _mm256_set_m128(k[j], k[j]);
        const float* f = frames + std::size_t{poly[e + j]} * 16;
        lo[j] = _mm256_fmadd_ps(kk, _mm256_load_ps(f), lo[j]);
        hi[j] = _mm256_fmadd_ps(kk, _mm256_load_ps(f + 8), hi[j]);
      }
    }
    const __m256 l = _mm256_add_ps(_mm256_add_ps(lo[0], lo[1]), _mm256_add_ps(lo[2], lo[3]));
    const __m256 h = _mm256_add_ps(_mm256_add_ps(hi[0], hi[1]), _mm256_add_ps(hi[2], hi[3]));
    alignas(16) float r[4];
    _mm_store_ps(r, quarter_sums(_mm256_castps256_ps128(l), _mm256_extractf128_ps(l, 1), _mm256_castps256_ps128(h)));
    out[v] = Vec3d(r[0], r[1], r[2]);
  }
}

void decode_rows_scalar(const DetailEncoding& enc, const float* frames, std::size_t begin, std::size_t end,
                        Vec3d* out) {
  for (std::size_t v = begin; v < end; ++v) {
    float s[3] = {0, 0, 0};
    for (std::uint32_t e = enc.row[v]; e < enc.row[v + 1]; ++e) {
      const float* f = frames + static_cast<std::size_t>(enc.polygon[e]) * 16;
      for (int k = 0; k < 3; ++k)
        s[k] += enc.a[e] * f[4 * k] + enc.b[e] * f[4 * k + 1] + enc.c[e] * f[4 * k + 2] + enc.d[e] * f[4 * k + 3];
    }
    out[v] = Vec3d(s[0], s[1], s[2]);
  }
}

// Batched frames: per polygon 12 rows (p_c, X, Y, Z; x, y, z) of kLanes
// bodies, so one entry applies to kLanes bodies with 12 8-wide FMAs.
constexpr std::size_t kLanes = 8;
constexpr std::size_t kFrameFloats = 12 * kLanes;

// One tile of vertices for one group of kLanes bodies: per run (a polygon
// used by several tile vertices) its frames are loaded once and applied to
// every entry of the run. acc: [tile vertex][x, y, z][lane].
__attribute__((target("avx2,fma"))) void decode_tile_avx2(const std::uint32_t* run_polygon,
                                                          const std::uint32_t* run_entry, std::size_t run_begin,
                                                          std::size_t run_end, const std::uint8_t* vertex,
                                                          const float* coef, const float* frames, float* acc) {
  for (std::size_t r = run_begin; r < run_end; ++r) {
    const float* F = frames + static_cast<std::size_t>(run_polygon[r]) * kFrameFloats;
    // The frames of a tile's polygons come from L3 (a pass's frames are
    // megabytes): fetch the next run's six lines while this run computes.
    if (r + 1 < run_end) {
      const char* next =
          reinterpret_cast<const char*>(frames + static_cast<std::size_t>(run_polygon[r + 1]) * kFrameFloats);
      for (int l = 0; l < 6; ++l) _mm_prefetch(next + 64 * l, _MM_HINT_T0);
    }
    __m256 f[12];
    for (int j = 0; j < 12; ++j) f[j] = _mm256_load_ps(F + 8 * j);
    for (std::uint32_t e = run_entry[r]; e < run_entry[r + 1]; ++e) {
      float* o = acc + static_cast<std::size_t>(vertex[e]) * 3 * kLanes;
      const float* c = coef + 4 * static_cast<std::size_t>(e);
      const __m256 a = _mm256_broadcast_ss(c), b = _mm256_broadcast_ss(c + 1), cc = _mm256_broadcast_ss(c + 2),
                   d = _mm256_broadcast_ss(c + 3);
      // A tree, (a p_c + b X) + (c Y + d Z), added to the accumulator last:
      // the products do not wait for the accumulator's load, and the
      // chains are half as deep, so more entries overlap.
      for (int k = 0; k < 3; ++k) {
        const __m256 s = _mm256_fmadd_ps(b, f[3 + k], _mm256_mul_ps(a, f[k]));
        const __m256 t = _mm256_fmadd_ps(d, f[9 + k], _mm256_mul_ps(cc, f[6 + k]));
        _mm256_store_ps(o + 8 * k, _mm256_add_ps(_mm256_load_ps(o + 8 * k), _mm256_add_ps(s, t)));
      }
    }
  }
}

// The same for two groups (16 bodies) at once, with the same arithmetic per
// lane (bit-identical to decode_tile_avx2 on each group): an entry's
// coefficients, index and loop overhead are shared by both groups. Group
// 0's X, Y, Z stay in registers; its p_c and group 1's frame are read from
// L1 (the run's 768 bytes). acc: [tile vertex][group][x, y, z][lane].
__attribute__((target("avx2,fma"))) void decode_tile2_avx2(const std::uint32_t* run_polygon,
                                                           const std::uint32_t* run_entry, std::size_t run_begin,
                                                           std::size_t run_end, const std::uint8_t* vertex,
                                                           const float* coef, const float* frames0,
                                                           const float* frames1, float* acc) {
  for (std::size_t r = run_begin; r < run_end; ++r) {
    const float* F = frames0 + static_cast<std::size_t>(run_polygon[r]) * kFrameFloats;
    const float* G = frames1 + static_cast<std::size_t>(run_polygon[r]) * kFrameFloats;
    if (r + 1 < run_end) {
      const std::size_t next = static_cast<std::size_t>(run_polygon[r + 1]) * kFrameFloats;
      for (int l = 0; l < 6; ++l) {
        _mm_prefetch(reinterpret_cast<const char*>(frames0 + next) + 64 * l, _MM_HINT_T0);
        _mm_prefetch(reinterpret_cast<const char*>(frames1 + next) + 64 * l, _MM_HINT_T0);
      }
    }
    __m256 f[9];
    for (int j = 0; j < 9; ++j) f[j] = _mm256_load_ps(F + 8 * (3 + j));
    const std::uint32_t e_end = run_entry[r + 1];
    for (std::uint32_t e = run_entry[r]; e < e_end; ++e) {
      float* o = acc + static_cast<std::size_t>(vertex[e]) * 6 * kLanes;
      const float* c = coef + 4 * static_cast<std::size_t>(e);
      const __m256 a = _mm256_broadcast_ss(c), b = _mm256_broadcast_ss(c + 1), cc = _mm256_broadcast_ss(c + 2),
                   d = _mm256_broadcast_ss(c + 3);
      for (int k = 0; k < 3; ++k) {
        const __m256 s = _mm256_fmadd_ps(b, f[k], _mm256_mul_ps(a, _mm256_load_ps(F + 8 * k)));
        const __m256 t = _mm256_fmadd_ps(d, f[6 + k], _mm256_mul_ps(cc, f[3 + k]));
        _mm256_store_ps(o + 8 * k, _mm256_add_ps(_mm256_load_ps(o + 8 * k), _mm256_add_ps(s, t)));
      }
      for (int k = 0; k < 3; ++k) {
        const __m256 s =
            _mm256_fmadd_ps(b, _mm256_load_ps(G + 8 * (3 + k)), _mm256_mul_ps(a, _mm256_load_ps(G + 8 * k)));
        const __m256 t =
            _mm256_fmadd_ps(d, _mm256_load_ps(G + 8 * (9 + k)), _mm256_mul_ps(cc, _mm256_load_ps(G + 8 * (6 + k))));
        _mm256_store_ps(o + 8 * (3 + k), _mm256_add_ps(_mm256_load_ps(o + 8 * (3 + k)), _mm256_add_ps(s, t)));
      }
    }
  }
}

void decode_tile_scalar(const std::uint32_t* run_polygon, const std::uint32_t* run_entry, std::size_t run_begin,
                        std::size_t run_end, const std::uint8_t* vertex, const float* coef, const float* frames,
                        float* acc) {
  for (std::size_t r = run_begin; r < run_end; ++r) {
    const float* F = frames + static_cast<std::size_t>(run_polygon[r]) * kFrameFloats;
    for (std::uint32_t e = run_entry[r]; e < run_entry[r + 1]; ++e) {
      float* o = acc + static_cast<std::size_t>(vertex[e]) * 3 * kLanes;
      const float* c = coef + 4 * static_cast<std::size_t>(e);
      for (std::size_t k = 0; k < 3; ++k)
        for (std::size_t w = 0; w < kLanes; ++w) {
          const float s = std::fma(c[1], F[(3 + k) * kLanes + w], c[0] * F[k * kLanes + w]);
          const float t = std::fma(c[3], F[(9 + k) * kLanes + w], c[2] * F[(6 + k) * kLanes + w]);
          o[k * kLanes + w] += s + t;
        }
    }
  }
}

// The AVX-512 layout: per polygon 12 rows of kWideLanes = 16 bodies (768
// bytes), one zmm register a row.
constexpr std::size_t kWideLanes = 16;
constexpr std::size_t kWideFrameFloats = 12 * kWideLanes;

// decode_tile2_avx2 with one 16-lane register per frame row: a run's whole
// frame (12 rows for 16 bodies) stays in registers (AVX-512 has 32), so an
// entry costs 4 broadcasts, 3 accumulator loads and 3 stores next to its 12
// FMA-unit operations, where the AVX2 kernel, with 16 registers, also reads
// 15 of its 24 frame vectors from L1 (31 memory operations per entry). The
// arithmetic per lane is the AVX2 kernel's, in the same order, so both give
// the same bits. acc: [tile vertex][x, y, z][16 lanes].
__attribute__((target("avx512f"))) void decode_tile_avx512(const std::uint32_t* run_polygon,
                                                           const std::uint32_t* run_entry, std::size_t run_begin,
                                                           std::size_t run_end, const std::uint8_t* vertex,
                                                           const float* coef, const float* frames, float* acc) {
  for (std::size_t r = run_begin; r < run_end; ++r) {
    const float* F = frames + static_cast<std::size_t>(run_polygon[r]) * kWideFrameFloats;
    if (r + 1 < run_end) {
      const char* next =
          reinterpret_cast<const char*>(frames + static_cast<std::size_t>(run_polygon[r + 1]) * kWideFrameFloats);
      for (int l = 0; l < 12; ++l) _mm_prefetch(next + 64 * l, _MM_HINT_T0);
    }
    __m512 f[12];
    for (int j = 0; j < 12; ++j) f[j] = _mm512_load_ps(F + 16 * j);
    const std::uint32_t e_end = run_entry[r + 1];
    for (std::uint32_t e = run_entry[r]; e < e_end; ++e) {
      float* o = acc + static_cast<std::size_t>(vertex[e]) * 3 * kWideLanes;
      const float* c = coef + 4 * static_cast<std::size_t>(e);
      const __m512 a = _mm512_set1_ps(c[0]), b = _mm512_set1_ps(c[1]), cc = _mm512_set1_ps(c[2]),
                   d = _mm512_set1_ps(c[3]);
      for (int k = 0; k < 3; ++k) {
        const __m512 s = _mm512_fmadd_ps(b, f[3 + k], _mm512_mul_ps(a, f[k]));
        const __m512 t = _mm512_fmadd_ps(d, f[9 + k], _mm512_mul_ps(cc, f[6 + k]));
        _mm512_store_ps(o + 16 * k, _mm512_add_ps(_mm512_load_ps(o + 16 * k), _mm512_add_ps(s, t)));
      }
    }
  }
}

// Frames of one polygon on 8 bodies at once (AVX2 floats, one body per
// lane): polygon_frame's steps with the branches as lane masks. Batched
// decoding computes polygons x bodies frames per pass; in doubles they cost
// a fifth of the whole decode. Floats keep the frames' precision because
// every product is taken on corners relative to the polygon's first corner
// (exact differences of nearby floats): the cross-product sum is invariant
// under that shift for a closed polygon, so no product of two metre-sized
// coordinates loses the centimetre-sized area to cancellation. Frames then
// differ from polygon_frame's by float rounding (a few 1e-7 relative).
//
// pos: node positions of the pass's bodies, node-major ([node][x, y, z]
// [lanes] floats), read at lanes lane .. lane + 7. out: rows (p_c, X, Y,
// Z; x, y, z) of 8 floats, row_stride floats apart (kLanes in the AVX2
// layout, kWideLanes in the AVX-512 one). Polygons of at most kMaxCorners.
constexpr std::size_t kMaxCorners = 16;
__attribute__((target("avx2,fma"), always_inline)) inline __m256 dot_x8(__m256 a0, __m256 a1, __m256 a2, __m256 b0,
                                                                        __m256 b1, __m256 b2) {
  return _mm256_fmadd_ps(a2, b2, _mm256_fmadd_ps(a1, b1, _mm256_mul_ps(a0, b0)));
}
// Without FMA: a x a is then exactly zero, so a polygon folded onto a
// segment (repeated corners) has an exactly zero normal, as in doubles.
__attribute__((target("avx2"), always_inline)) inline void cross_x8(__m256 a0, __m256 a1, __m256 a2, __m256 b0,
                                                                    __m256 b1, __m256 b2, __m256* out) {
  out[0] = _mm256_sub_ps(_mm256_mul_ps(a1, b2), _mm256_mul_ps(a2, b1));
  out[1] = _mm256_sub_ps(_mm256_mul_ps(a2, b0), _mm256_mul_ps(a0, b2));
  out[2] = _mm256_sub_ps(_mm256_mul_ps(a0, b1), _mm256_mul_ps(a1, b0));
}

__attribute__((target("avx2,fma"))) void polygon_frame_x8(const BodyPolygons& b, const float* pos, std::size_t lanes,
                                                          std::size_t lane, std::size_t f,
                                                          std::span<const Eigen::Vector2f> ref, float* out,
                                                          std::size_t row_stride) {
  const std::uint32_t s = b.face_offsets[f], e = b.face_offsets[f + 1];
  const std::size_t n = e - s;
  __m256 O[3];
  __m256 P[3 * kMaxCorners];  // corners relative to corner 0
  {
    const float* node = pos + std::size_t{b.face_nodes[s]} * 3 * lanes + lane;
    for (std::size_t d = 0; d < 3; ++d) O[d] = _mm256_loadu_ps(node + d * lanes);
  }
  P[0] = P[1] = P[2] = _mm256_setzero_ps();
  for (std::size_t k = 1; k < n; ++k) {
    const float* node = pos + std::size_t{b.face_nodes[s + k]} * 3 * lanes + lane;
    for (std::size_t d = 0; d < 3; ++d) P[3 * k + d] = _mm256_sub_ps(_mm256_loadu_ps(node + d * lanes), O[d]);
  }
  const __m256 zero = _mm256_setzero_ps();
  __m256 c0 = zero, c1 = zero, c2 = zero, nr0 = zero, nr1 = zero, nr2 = zero, scale = zero;
  for (std::size_t k = 0; k < n; ++k) {
    const __m256* A = P + 3 * k;
    const __m256* Q = P + 3 * (k + 1 < n ? k + 1 : 0);
    c0 = _mm256_add_ps(c0, A[0]);
    c1 = _mm256_add_ps(c1, A[1]);
    c2 = _mm256_add_ps(c2, A[2]);
    __m256 x[3];
    cross_x8(A[0], A[1], A[2], Q[0], Q[1], Q[2], x);
    nr0 = _mm256_add_ps(nr0, x[0]);
    nr1 = _mm256_add_ps(nr1, x[1]);
    nr2 = _mm256_add_ps(nr2, x[2]);
    const __m256 d0 = _mm256_sub_ps(Q[0], A[0]), d1 = _mm256_sub_ps(Q[1], A[1]), d2 = _mm256_sub_ps(Q[2], A[2]);
    scale = _mm256_max_ps(scale, dot_x8(d0, d1, d2, d0, d1, d2));
  }
  const __m256 inv_n = _mm256_set1_ps(1.0f / static_cast<float>(n));
  c0 = _mm256_mul_ps(c0, inv_n);  // the centroid relative to corner 0
  c1 = _mm256_mul_ps(c1, inv_n);
  c2 = _mm256_mul_ps(c2, inv_n);
  const __m256 one = _mm256_set1_ps(1.0f);
  const __m256 nn = _mm256_sqrt_ps(dot_x8(nr0, nr1, nr2, nr0, nr1, nr2));
  // polygon_frame's degeneracy tests, with bounds raised from double's
  // rounding level (1e-12, 1e-9) to float's: a polygon with collinear
  // corners has a normal of float noise, about 1e-7 of its squared size.
  // Only slivers with aspect ratios between 1e6 and 1e12 are judged
  // differently from polygon_frame.
  const __m256 ok1 = _mm256_and_ps(_mm256_cmp_ps(nn, _mm256_mul_ps(_mm256_set1_ps(1e-6f), scale), _CMP_GT_OQ),
                                   _mm256_cmp_ps(scale, zero, _CMP_GT_OQ));
  const __m256 inv_nn = _mm256_div_ps(one, nn);
  const __m256 x0 = _mm256_mul_ps(nr0, inv_nn), x1 = _mm256_mul_ps(nr1, inv_nn), x2 = _mm256_mul_ps(nr2, inv_nn);
  // Y: corner 0 minus the centroid, made orthogonal to X.
  __m256 y0 = _mm256_sub_ps(zero, c0), y1 = _mm256_sub_ps(zero, c1), y2 = _mm256_sub_ps(zero, c2);
  const __m256 yx = dot_x8(y0, y1, y2, x0, x1, x2);
  y0 = _mm256_fnmadd_ps(yx, x0, y0);
  y1 = _mm256_fnmadd_ps(yx, x1, y1);
  y2 = _mm256_fnmadd_ps(yx, x2, y2);
  const __m256 yn = _mm256_sqrt_ps(dot_x8(y0, y1, y2, y0, y1, y2));
  const __m256 ok2 =
      _mm256_and_ps(ok1, _mm256_cmp_ps(yn, _mm256_mul_ps(_mm256_set1_ps(1e-6f), _mm256_sqrt_ps(scale)), _CMP_GT_OQ));
  const __m256 inv_yn = _mm256_div_ps(one, yn);
  y0 = _mm256_mul_ps(y0, inv_yn);
  y1 = _mm256_mul_ps(y1, inv_yn);
  y2 = _mm256_mul_ps(y2, inv_yn);
  __m256 z[3];
  cross_x8(x0, x1, x2, y0, y1, y2, z);
  if (!ref.empty()) {
    __m256 sdot = zero, scross = zero;
    for (std::size_t k = 0; k < n; ++k) {
      const __m256 q0 = _mm256_sub_ps(P[3 * k], c0), q1 = _mm256_sub_ps(P[3 * k + 1], c1),
                   q2 = _mm256_sub_ps(P[3 * k + 2], c2);
      const __m256 d1 = dot_x8(q0, q1, q2, y0, y1, y2), d2 = dot_x8(q0, q1, q2, z[0], z[1], z[2]);
      const __m256 r1 = _mm256_set1_ps(ref[s + k].x()), r2 = _mm256_set1_ps(ref[s + k].y());
      sdot = _mm256_fmadd_ps(r2, d2, _mm256_fmadd_ps(r1, d1, sdot));
      scross = _mm256_fnmadd_ps(r2, d1, _mm256_fmadd_ps(r1, d2, scross));
    }
    const __m256 r = _mm256_sqrt_ps(_mm256_fmadd_ps(scross, scross, _mm256_mul_ps(sdot, sdot)));
    const __m256 turn = _mm256_cmp_ps(r, zero, _CMP_GT_OQ);
    const __m256 inv_r = _mm256_div_ps(one, r), cs = _mm256_mul_ps(sdot, inv_r), sn = _mm256_mul_ps(scross, inv_r);
    const __m256 t0 = _mm256_fmadd_ps(sn, z[0], _mm256_mul_ps(cs, y0));
    const __m256 t1 = _mm256_fmadd_ps(sn, z[1], _mm256_mul_ps(cs, y1));
    const __m256 t2 = _mm256_fmadd_ps(sn, z[2], _mm256_mul_ps(cs, y2));
    __m256 tz[3];
    cross_x8(x0, x1, x2, t0, t1, t2, tz);
    y0 = _mm256_blendv_ps(y0, t0, turn);
    y1 = _mm256_blendv_ps(y1, t1, turn);
    y2 = _mm256_blendv_ps(y2, t2, turn);
    for (int i = 0; i < 3; ++i) z[i] = _mm256_blendv_ps(z[i], tz[i], turn);
  }
  const __m256 rows[12] = {_mm256_add_ps(O[0], c0),  _mm256_add_ps(O[1], c1),  _mm256_add_ps(O[2], c2),
                           _mm256_and_ps(x0, ok1),   _mm256_and_ps(x1, ok1),   _mm256_and_ps(x2, ok1),
                           _mm256_and_ps(y0, ok2),   _mm256_and_ps(y1, ok2),   _mm256_and_ps(y2, ok2),
                           _mm256_and_ps(z[0], ok2), _mm256_and_ps(z[1], ok2), _mm256_and_ps(z[2], ok2)};
  for (std::size_t j = 0; j < 12; ++j) _mm256_store_ps(out + j * row_stride, rows[j]);
}

// A body's node positions read in place from a body set's float columns
// (the same doubles BodySet::positions gives).
struct SetPos {
  const float *x, *y, *z;
  void get(std::uint32_t n, double* out) const noexcept {
    out[0] = x[n];
    out[1] = y[n];
    out[2] = z[n];
  }
};

}  // namespace

DecodeKernel decode_detail(const DetailEncoding& enc, const PolygonFrames& frames, std::span<Vec3d> out,
                           const ExecContext& ctx, DecodeKernel allow) {
  PackedFrames packed;
  packed.pack(frames, ctx);
  ExecContext c = ctx;
  c.grain = ctx.grain ? ctx.grain : 256;
  const DecodeKernel kernel = pick_kernel(allow);
  par::for_each_block(c, enc.vertex_count(), [&](std::size_t b, std::size_t e) {
    if (kernel == DecodeKernel::kAvx512)
      decode_rows_avx512(enc, packed.data, b, e, out.data());
    else if (kernel == DecodeKernel::kAvx2)
      decode_rows_avx2(enc, packed.data, b, e, out.data());
    else
      decode_rows_scalar(enc, packed.data, b, e, out.data());
  });
  return kernel;
}

Status decode_detail(const DetailEncoding& enc, const BodyPolygons& body, std::span<const Vec3d> bp,
                     std::span<Vec3d> out, const ExecContext& ctx) {
  if (Status s = check_topology(enc, body); !s) return s;
  if (bp.size() != body.node_count || out.size() != enc.vertex_count())
    return {ErrorCode::kMismatch, "decode_detail: position or output array has the wrong size"};
  PolygonFrames fr;
  compute_frames(body, bp, fr, ctx, enc.reference_corners);
  decode_detail(enc, fr, out, ctx);
  return {};
}

DetailDecoder::DetailDecoder(const DetailEncoding& enc, const ExecContext& ctx)
    : polygon_count_(enc.polygon_count),
      body_node_count_(enc.body_node_count),
      topology_hash_(enc.topology_hash),
      vertex_count_(static_cast<std::uint32_t>(enc.vertex_count())),
      reference_corners_(enc.reference_corners) {
  const std::size_t nv = enc.vertex_count(), ne = enc.entries(), np = enc.polygon_count;
  const std::size_t tiles = (nv + kTile - 1) / kTile;
  vertex_.resize(ne);
  coef_.resize(4 * ne);
  // Per tile, a counting sort of its entries by polygon; within a run the
  // tile's vertices stay in increasing order, so every vertex still sums
  // its entries in row order.
  std::vector<std::vector<std::uint32_t>> polys(tiles), ends(tiles);
  ExecContext c = ctx;
  c.grain = 4;
  c.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 8);
  par::for_each_block(c, tiles, [&](std::size_t t0, std::size_t t1) {
    std::vector<std::uint32_t> slot(np, 0);
    std::vector<std::uint32_t> touched;
    for (std::size_t t = t0; t < t1; ++t) {
      const std::size_t v0 = t * kTile, v1 = std::min(nv, v0 + kTile);
      const std::uint32_t base = enc.row[v0];
      touched.clear();
      for (std::uint32_t e = base; e < enc.row[v1]; ++e)
        if (slot[enc.polygon[e]]++ == 0) touched.push_back(enc.polygon[e]);
      std::sort(touched.begin(), touched.end());
      std::uint32_t at = base;
      for (const std::uint32_t p : touched) {
        const std::uint32_t n = slot[p];
        slot[p] = at;  // count -> next free position of the run
        at += n;
        ends[t].push_back(at);
      }
      polys[t] = touched;
      for (std::size_t v = v0; v < v1; ++v)
        for (std::uint32_t e = enc.row[v]; e < enc.row[v + 1]; ++e) {
          const std::uint32_t pos = slot[enc.polygon[e]]++;
          vertex_[pos] = static_cast<std::uint8_t>(v - v0);
          coef_[4 * std::size_t{pos}] = enc.a[e];
          coef_[4 * std::size_t{pos} + 1] = enc.b[e];
          coef_[4 * std::size_t{pos} + 2] = enc.c[e];
          coef_[4 * std::size_t{pos} + 3] = enc.d[e];
        }
      for (const std::uint32_t p : touched) slot[p] = 0;
    }
  });
  tile_run_.assign(tiles + 1, 0);
  for (std::size_t t = 0; t < tiles; ++t) tile_run_[t + 1] = tile_run_[t] + static_cast<std::uint32_t>(polys[t].size());
  run_polygon_.resize(tile_run_.back());
  run_entry_.resize(tile_run_.back() + 1);
  run_entry_[0] = 0;
  for (std::size_t t = 0; t < tiles; ++t) {
    std::copy(polys[t].begin(), polys[t].end(), run_polygon_.begin() + tile_run_[t]);
    std::copy(ends[t].begin(), ends[t].end(), run_entry_.begin() + tile_run_[t] + 1);
  }
  // A garment rarely covers the whole body (a skirt uses a fifth of the
  // skin's polygons): frames are computed for these polygons only.
  std::vector<std::uint8_t> used(np, 0);
  for (const std::uint32_t p : run_polygon_) used[p] = 1;
  for (std::size_t p = 0; p < np; ++p)
    if (used[p]) used_polygons_.push_back(static_cast<std::uint32_t>(p));
}

Status DetailDecoder::check_topology(const BodyPolygons& body) const {
  if (polygon_count_ != body.size() || body_node_count_ != body.node_count || topology_hash_ != body.topology_hash) {
    std::ostringstream s;
    s << "the body's topology (" << body.node_count << " nodes, " << body.size()
      << " polygons) differs from the one the detail template was encoded on (" << body_node_count_ << " nodes, "
      << polygon_count_ << " polygons)";
    return {ErrorCode::kMismatch, s.str()};
  }
  return {};
}

Status decode_detail_batch(const DetailDecoder& dec, const BodyPolygons& body, const BodySet& bodies, std::size_t first,
                           std::size_t count, std::span<Vec3f> out, const ExecContext& ctx) {
  DecodeWorkspace ws;
  return decode_detail_batch(dec, body, bodies, first, count, out, ws, ctx);
}

Status decode_detail_batch(const DetailDecoder& dec, const BodyPolygons& body, const BodySet& bodies, std::size_t first,
                           std::size_t count, std::span<Vec3f> out, DecodeWorkspace& ws, const ExecContext& ctx) {
  if (Status s = dec.check_topology(body); !s) return s;
  if (bodies.node_count() != body.node_count)
    return {ErrorCode::kMismatch, "decode_detail_batch: the body set has another node count than the template's body"};
  if (first + count > bodies.size())
    return {ErrorCode::kInvalidArgument, "decode_detail_batch: body range out of bounds"};
  const std::size_t nv = dec.vertex_count();
  if (out.size() != count * nv) return {ErrorCode::kMismatch, "decode_detail_batch: output has the wrong size"};
  if (count == 0 || nv == 0) return {};
  const std::size_t np = body.size();
  const DecodeKernel kernel = pick_kernel(ws.allow);
  ws.ran = kernel;
  const bool fast = kernel != DecodeKernel::kPortable, wide = kernel == DecodeKernel::kAvx512;
  // Groups of kLanes bodies; kGroups groups share one pass over the matrix
  // (a tile's entries stay in L2 while each group's frames stream through).
  // The AVX-512 kernel takes both groups in one register (its frames are
  // laid out 16 lanes a row), so its passes always hold 16 lanes.
  constexpr std::size_t kGroups = 2;
  static_assert(kGroups * kLanes == kWideLanes);
  const std::size_t pass_groups = wide ? kGroups : std::min(kGroups, (count + kLanes - 1) / kLanes);
  // Frame of polygon p for group g: rows of `row` floats.
  const std::size_t row = wide ? kWideLanes : kLanes;
  auto frame_of = [&](float* base, std::size_t g, std::size_t p) {
    return wide ? base + p * kWideFrameFloats + g * kLanes : base + (g * np + p) * kFrameFloats;
  };
  // Every lane of every frame the decoder reads (its used polygons') is
  // written below before it is read.
  if (ws.frames.size() < pass_groups * np * kFrameFloats + 16) ws.frames.resize(pass_groups * np * kFrameFloats + 16);
  const auto addr = reinterpret_cast<std::uintptr_t>(ws.frames.data());
  float* frames = ws.frames.data() + ((64 - addr % 64) % 64) / sizeof(float);
  if (fast && ws.positions.size() < std::size_t{body.node_count} * 3 * pass_groups * kLanes)
    ws.positions.resize(std::size_t{body.node_count} * 3 * pass_groups * kLanes);
  float* tpos = ws.positions.data();
  // The nodes whose positions the frames read: the used polygons' corners.
  std::vector<std::uint32_t> nodes;
  if (fast) {
    std::vector<std::uint8_t> used(body.node_count, 0);
    for (const std::uint32_t p : dec.used_polygons_)
      for (std::uint32_t k = body.face_offsets[p]; k < body.face_offsets[p + 1]; ++k) used[body.face_nodes[k]] = 1;
    for (std::uint32_t n = 0; n < body.node_count; ++n)
      if (used[n]) nodes.push_back(n);
  }
  const std::size_t tiles = (nv + DetailDecoder::kTile - 1) / DetailDecoder::kTile;
  for (std::size_t g0 = 0; g0 < count; g0 += pass_groups * kLanes) {
    const std::size_t nb = std::min(pass_groups * kLanes, count - g0);
    const std::size_t groups = wide ? kGroups : (nb + kLanes - 1) / kLanes;
    // Frames of every body of the pass, written straight into the lanes,
    // 8 bodies per vector. Lanes past the last body repeat it (never output).
    const float* col[kGroups * kLanes];
    for (std::size_t i = 0; i < groups * kLanes; ++i) col[i] = bodies.x(first + g0 + std::min(i, nb - 1)).data();
    const std::size_t stride = bodies.node_count(), lanes = groups * kLanes;
    if (fast) {
      // The bodies' columns transposed node-major, so a polygon corner's
      // coordinate for 8 bodies is one load (a body set is body-major: 48
      // columns read at once would defeat the hardware prefetchers). Only
      // the used nodes (not a body's helper geometry or the skin a garment
      // does not reach), in sub-blocks of 128 whose 24 KB of transposed
      // rows stay in L1 while the columns are read into them.
      ExecContext tc = ctx;
      tc.grain = 2048;
      par::for_each_block(tc, nodes.size(), [&](std::size_t b0, std::size_t b1) {
        for (std::size_t j0 = b0; j0 < b1; j0 += 128) {
          const std::size_t j1 = std::min(b1, j0 + 128);
          for (std::size_t i = 0; i < lanes; ++i)
            for (std::size_t d = 0; d < 3; ++d) {
              const float* src = col[i] + d * stride;
              for (std::size_t j = j0; j < j1; ++j) tpos[(nodes[j] * std::size_t{3} + d) * lanes + i] = src[nodes[j]];
            }
        }
      });
    }
    ExecContext fc = ctx;
    fc.grain = 256;  // 13k polygons: enough blocks to balance 2 threads
    par::for_each_n(fc, dec.used_polygons_.size(), [&](std::size_t u) {
      const std::size_t p = dec.used_polygons_[u];
      const bool small = body.face_offsets[p + 1] - body.face_offsets[p] <= kMaxCorners;
      for (std::size_t g = 0; g < groups; ++g) {
        float* f = frame_of(frames, g, p);
        if (fast && small) {
          polygon_frame_x8(body, tpos, lanes, g * kLanes, p, dec.reference_corners_, f, row);
          continue;
        }
        for (std::size_t l = 0; l < kLanes; ++l) {
          const float* cl = col[g * kLanes + l];
          const SetPos pos{cl, cl + stride, cl + 2 * stride};
          const FrameD fr = polygon_frame(body, pos, p, dec.reference_corners_);
          const Vec3d* v[4] = {&fr.c, &fr.x, &fr.y, &fr.z};
          for (std::size_t j = 0; j < 4; ++j)
            for (std::size_t k = 0; k < 3; ++k)
              f[(3 * j + k) * row + l] = static_cast<float>((*v[j])[static_cast<int>(k)]);
        }
      }
    });
    ExecContext c = ctx;
    c.grain = 2;
    c.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 4);
    par::for_each_block(c, tiles, [&](std::size_t t0, std::size_t t1) {
      alignas(64) float acc[DetailDecoder::kTile * 3 * kGroups * kLanes];
      for (std::size_t t = t0; t < t1; ++t) {
        const std::size_t v0 = t * DetailDecoder::kTile, v1 = std::min(nv, v0 + DetailDecoder::kTile);
        if (wide || (fast && groups == 2)) {
          // Both groups in one pass: acc is [vertex][x, y, z][16 lanes]
          // (AVX-512) or [vertex][group][x, y, z][8 lanes] (AVX2).
          std::fill(acc, acc + (v1 - v0) * 6 * kLanes, 0.0f);
          if (wide)
            decode_tile_avx512(dec.run_polygon_.data(), dec.run_entry_.data(), dec.tile_run_[t], dec.tile_run_[t + 1],
                               dec.vertex_.data(), dec.coef_.data(), frames, acc);
          else
            decode_tile2_avx2(dec.run_polygon_.data(), dec.run_entry_.data(), dec.tile_run_[t], dec.tile_run_[t + 1],
                              dec.vertex_.data(), dec.coef_.data(), frames, frames + np * kFrameFloats, acc);
          for (std::size_t g = 0; g * kLanes < nb; ++g) {
            const std::size_t lanes = std::min(kLanes, nb - g * kLanes);
            for (std::size_t v = v0; v < v1; ++v) {
              const float* r =
                  wide ? acc + (v - v0) * 3 * kWideLanes + g * kLanes : acc + ((v - v0) * 2 + g) * 3 * kLanes;
              for (std::size_t w = 0; w < lanes; ++w)
                out[(g0 + g * kLanes + w) * nv + v] = Vec3f(r[w], r[row + w], r[2 * row + w]);
            }
          }
          continue;
        }
        for (std::size_t g = 0; g < groups; ++g) {
          std::fill(acc, acc + (v1 - v0) * 3 * kLanes, 0.0f);
          const float* fg = frames + g * np * kFrameFloats;
          if (fast)
            decode_tile_avx2(dec.run_polygon_.data(), dec.run_entry_.data(), dec.tile_run_[t], dec.tile_run_[t + 1],
                             dec.vertex_.data(), dec.coef_.data(), fg, acc);
          else
            decode_tile_scalar(dec.run_polygon_.data(), dec.run_entry_.data(), dec.tile_run_[t], dec.tile_run_[t + 1],
                               dec.vertex_.data(), dec.coef_.data(), fg, acc);
          const std::size_t lanes = std::min(kLanes, nb - g * kLanes);
          for (std::size_t v = v0; v < v1; ++v) {
            const float* r = acc + (v - v0) * 3 * kLanes;
            for (std::size_t w = 0; w < lanes; ++w)
              out[(g0 + g * kLanes + w) * nv + v] = Vec3f(r[w], r[kLanes + w], r[2 * kLanes + w]);
          }
        }
      }
    });
    if (ctx.cancelled()) return {ErrorCode::kCancelled, "decode_detail_batch cancelled"};
  }
  return {};
}

Status decode_detail_batch(const DetailEncoding& enc, const BodyPolygons& body, const BodySet& bodies,
                           std::size_t first, std::size_t count, std::span<Vec3f> out, const ExecContext& ctx) {
  if (Status s = check_topology(enc, body); !s) return s;
  return decode_detail_batch(DetailDecoder(enc, ctx), body, bodies, first, count, out, ctx);
}

// -------------------------------------------------------------------- files

namespace {
constexpr char kMagic[8] = {'A', 'T', 'L', 'D', 'E', 'T', 'L', '1'};
constexpr std::uint32_t kVersion = 1;

template <class T>
void put(std::string& s, const T& v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof v);
}
template <class T>
void put_vec(std::string& s, const std::vector<T>& v) {
  s.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}
}  // namespace

void write_detail(const DetailEncoding& enc, const std::filesystem::path& path) {
  std::string s(kMagic, 8);
  put(s, kVersion);
  put(s, enc.polygon_count);
  put(s, enc.body_node_count);
  put(s, enc.topology_hash);
  put(s, static_cast<std::uint64_t>(enc.vertex_count()));
  put(s, static_cast<std::uint64_t>(enc.entries()));
  put(s, static_cast<std::uint64_t>(enc.reference_corners.size()));
  put_vec(s, enc.row);
  put_vec(s, enc.polygon);
  put_vec(s, enc.a);
  put_vec(s, enc.b);
  put_vec(s, enc.c);
  put_vec(s, enc.d);
  put_vec(s, enc.reference_corners);
  const std::uint64_t sum = fnv1a(0xcbf29ce484222325ull, s.data(), s.size());
  put(s, sum);
  // Atomic: temporary file in the same folder, then rename.
  std::filesystem::path tmp = path;
  tmp += ".tmp";
  {
    std::ofstream o(tmp, std::ios::binary | std::ios::trunc);
    if (!o) throw Error(Status(ErrorCode::kIo, path.string() + ": cannot write"));
    o.write(s.data(), static_cast<std::streamsize>(s.size()));
    o.flush();
    if (!o) {
      std::filesystem::remove(tmp);
      throw Error(Status(ErrorCode::kIo, path.string() + ": write failed"));
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp);
    throw Error(Status(ErrorCode::kIo, path.string() + ": " + ec.message()));
  }
}

DetailEncoding read_detail(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(Status(ErrorCode::kIo, path.string() + ": cannot open"));
  std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto fail = [&](const std::string& what) { throw Error(Status(ErrorCode::kParse, path.string() + ": " + what)); };
  std::size_t pos = 0;
  auto get = [&](void* dst, std::size_t n, const char* what) {
    if (pos + n > s.size()) fail(std::string("truncated file (while reading ") + what + ")");
    std::memcpy(dst, s.data() + pos, n);
    pos += n;
  };
  char magic[8];
  get(magic, 8, "magic");
  if (std::memcmp(magic, kMagic, 8) != 0) fail("not an Atelier detail template (bad magic)");
  std::uint32_t version;
  get(&version, 4, "version");
  if (version != kVersion) fail("unsupported version " + std::to_string(version));
  DetailEncoding e;
  std::uint64_t nv, ne, nc;
  get(&e.polygon_count, 4, "header");
  get(&e.body_node_count, 4, "header");
  get(&e.topology_hash, 8, "header");
  get(&nv, 8, "header");
  get(&ne, 8, "header");
  get(&nc, 8, "header");
  if (nv > s.size() || ne > s.size() || nc > s.size() || s.size() < pos + (nv + 1) * 4 + ne * 20 + nc * 8 + 8)
    fail("truncated file (sizes in the header exceed the file)");
  e.row.resize(nv + 1);
  e.polygon.resize(ne);
  for (auto* v : {&e.a, &e.b, &e.c, &e.d}) v->resize(ne);
  get(e.row.data(), e.row.size() * 4, "rows");
  get(e.polygon.data(), ne * 4, "polygons");
  for (auto* v : {&e.a, &e.b, &e.c, &e.d}) get(v->data(), ne * 4, "coefficients");
  e.reference_corners.resize(nc);
  get(e.reference_corners.data(), nc * 8, "reference corners");
  const std::uint64_t want = fnv1a(0xcbf29ce484222325ull, s.data(), pos);
  std::uint64_t sum;
  get(&sum, 8, "checksum");
  if (sum != want) fail("checksum mismatch (corrupted file)");
  if (e.row.front() != 0 || e.row.back() != ne) fail("row offsets do not cover the entries");
  for (std::size_t v = 0; v < nv; ++v)
    if (e.row[v] > e.row[v + 1]) fail("row offsets decrease at vertex " + std::to_string(v));
  for (std::size_t i = 0; i < ne; ++i)
    if (e.polygon[i] >= e.polygon_count) fail("entry " + std::to_string(i) + " names polygon out of range");
  return e;
}

}  // namespace atelier
