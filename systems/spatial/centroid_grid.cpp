#include <atelier/systems/spatial/centroid_grid.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <atelier/engine/parallel.h>

namespace atelier {

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

}  // namespace atelier
