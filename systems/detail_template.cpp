#include "systems/detail_template.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "engine/parallel.h"
#include "systems/body_set.h"

namespace atelier {

// ------------------------------------------------------------- body polygons

namespace {
std::uint64_t fnv1a(std::uint64_t h, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}
}  // namespace

BodyPolygons BodyPolygons::from_model(const Model& body) { return from_model(body, SurfaceIdx{}); }

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
FrameD polygon_frame(const BodyPolygons& b, std::span<const Vec3d> p, std::size_t f) {
  const std::uint32_t s = b.face_offsets[f], e = b.face_offsets[f + 1];
  FrameD fr{};
  Vec3d c = Vec3d::Zero(), n = Vec3d::Zero();
  double scale = 0;
  for (std::uint32_t k = s; k < e; ++k) {
    const Vec3d& a = p[b.face_nodes[k]];
    const Vec3d& q = p[b.face_nodes[k + 1 < e ? k + 1 : s]];
    c += a;
    n += a.cross(q);
    scale = std::max(scale, (q - a).squaredNorm());
  }
  c /= static_cast<double>(e - s);
  fr.c = c;
  const double nn = n.norm();
  Vec3d y = p[b.face_nodes[s]] - c;
  if (!(nn > 1e-12 * scale) || !(scale > 0)) {
    fr.degenerate = true;
    return fr;
  }
  fr.x = n / nn;
  y -= y.dot(fr.x) * fr.x;
  const double yn = y.norm();
  if (!(yn > 1e-9 * std::sqrt(scale))) {
    fr.degenerate = true;
    return fr;
  }
  fr.y = y / yn;
  fr.z = fr.x.cross(fr.y);
  fr.degenerate = false;
  return fr;
}

}  // namespace

namespace {
// Y turned by the best-fit rotation of the polygon's corners onto their
// reference shape (2D Procrustes: the angle maximising sum r_k . R d_k).
void fit_rotation(const BodyPolygons& b, std::span<const Vec3d> p, std::size_t f,
                  std::span<const Eigen::Vector2f> ref, FrameD& fr) {
  double sdot = 0, scross = 0;
  for (std::uint32_t k = b.face_offsets[f]; k < b.face_offsets[f + 1]; ++k) {
    const Vec3d q = p[b.face_nodes[k]] - fr.c;
    const double d1 = q.dot(fr.y), d2 = q.dot(fr.z);
    const double r1 = ref[k].x(), r2 = ref[k].y();
    sdot += r1 * d1 + r2 * d2;
    scross += r1 * d2 - r2 * d1;
  }
  const double phi = std::atan2(scross, sdot);
  const Vec3d y = std::cos(phi) * fr.y + std::sin(phi) * fr.z;
  fr.y = y;
  fr.z = fr.x.cross(y);
}
}  // namespace

void compute_frames(const BodyPolygons& b, std::span<const Vec3d> p, PolygonFrames& out, const ExecContext& ctx,
                    std::span<const Eigen::Vector2f> ref) {
  const std::size_t n = b.size();
  out.centroid.resize(n);
  out.x.resize(n);
  out.y.resize(n);
  out.z.resize(n);
  out.degenerate.resize(n);
  const bool fitted = !ref.empty();
  par::for_each_n(ctx, n, [&](std::size_t f) {
    FrameD fr = polygon_frame(b, p, f);
    if (fitted && !fr.degenerate) fit_rotation(b, p, f, ref, fr);
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
    nx_ = ny_ = nz_ = 1;
    return;
  }
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
    cell = radii[radii.size() / 2] * 0.5;
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
}

void CentroidGrid::nearest(const Vec3d& q, std::size_t k, std::vector<std::uint32_t>& out,
                           std::vector<std::pair<double, std::uint32_t>>& heap) const {
  (void)nearest_bounded(q, k, std::numeric_limits<double>::infinity(), out, heap);
}

double CentroidGrid::nearest_bounded(const Vec3d& q, std::size_t k, double bound, std::vector<std::uint32_t>& out,
                                     std::vector<std::pair<double, std::uint32_t>>& heap) const {
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
    auto box = [&](double c, double l, int n) {
      return std::pair<int, int>{std::clamp(static_cast<int>(std::floor((c - bound - l) / cell_)), 0, n - 1),
                                 std::clamp(static_cast<int>(std::floor((c + bound - l) / cell_)), 0, n - 1)};
    };
    const auto [i_lo, i_hi] = box(q.x(), lo_.x(), nx_);
    const auto [j_lo, j_hi] = box(q.y(), lo_.y(), ny_);
    const auto [k_lo, k_hi] = box(q.z(), lo_.z(), nz_);
    for (int kk = k_lo; kk <= k_hi; ++kk)
      for (int j = j_lo; j <= j_hi; ++j) {
        const std::size_t row = (static_cast<std::size_t>(kk) * ny_ + j) * nx_;
        const std::uint32_t b = start_[row + i_lo], e = start_[row + i_hi + 1];  // cells i_lo..i_hi are contiguous
        for (std::uint32_t s = b; s < e; ++s) {
          const double d2 = (exact_[s] - q).squaredNorm();
          if (d2 <= bound2) heap.emplace_back(d2, ids_[s]);
        }
      }
    if (heap.size() < k) return nearest_bounded(q, k, std::numeric_limits<double>::infinity(), out, heap);
    std::nth_element(heap.begin(), heap.begin() + static_cast<std::ptrdiff_t>(k - 1), heap.end());
    heap.resize(k);
    std::sort(heap.begin(), heap.end());
    for (const auto& c : heap) out.push_back(c.second);
    return std::sqrt(heap.back().first);
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
  par::for_each_n(ctx, np, [&](std::size_t f) { frames[f] = polygon_frame(body, bp, f); });
  std::vector<Vec3d> centroids(np);
  std::vector<std::uint8_t> skip(np);
  std::size_t usable = 0;
  for (std::size_t f = 0; f < np; ++f) {
    centroids[f] = frames[f].c;
    skip[f] = frames[f].degenerate;
    usable += !skip[f];
  }
  std::size_t k = params.single_polygon ? 1
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
        enc.reference_corners[k] = Eigen::Vector2f(static_cast<float>(q.dot(frames[f].y)),
                                                   static_cast<float>(q.dot(frames[f].z)));
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
  ExecContext c = ctx;
  c.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 256);
  c.grain = ctx.grain ? ctx.grain : 64;
  par::for_each_block(c, nv, [&](std::size_t begin, std::size_t end) {
    std::vector<std::uint32_t> near;
    std::vector<std::pair<double, std::uint32_t>> heap;
    std::vector<std::array<double, 5>> coef;
    Vec3d prev_q = Vec3d::Zero();
    double prev_kth = std::numeric_limits<double>::infinity();
    for (std::size_t v = begin; v < end; ++v) {
      if (ctx.cancelled()) return;
      const Vec3d& q = garment[v];
      const bool taper = params.tapered_weights && usable > k;
      // Consecutive vertices are usually neighbours: by the triangle
      // inequality the previous k-th distance plus the step bounds this one.
      const double bound = prev_kth + (q - prev_q).norm();
      prev_kth = grid.nearest_bounded(q, taper ? k + 1 : k, bound * (1 + 1e-12) + 1e-15, near, heap);
      prev_q = q;
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
        coef[i] = {w, dq.dot(fr.x), dq.dot(fr.y), dq.dot(fr.z), 0};      // eq. (9)
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
      << " polygons) differs from the one the detail template was encoded on (" << enc.body_node_count
      << " nodes, " << enc.polygon_count << " polygons)";
    return {ErrorCode::kMismatch, s.str()};
  }
  return {};
}

// ------------------------------------------------------------------ decode

namespace {

// Eqs. (11)-(12) with precombined coefficients. target_clones lets one binary
// use AVX-512/AVX2 where the CPU has them.
__attribute__((target_clones("avx512f", "avx2", "default"))) void decode_rows(
    const DetailEncoding& enc, const PolygonFrames& fr, std::size_t begin, std::size_t end, Vec3d* out) {
  const std::uint32_t* poly = enc.polygon.data();
  const float *A = enc.a.data(), *B = enc.b.data(), *C = enc.c.data(), *D = enc.d.data();
  const Vec3f *pc = fr.centroid.data(), *X = fr.x.data(), *Y = fr.y.data(), *Z = fr.z.data();
  for (std::size_t v = begin; v < end; ++v) {
    float sx = 0, sy = 0, sz = 0;
    for (std::uint32_t e = enc.row[v]; e < enc.row[v + 1]; ++e) {
      const std::uint32_t p = poly[e];
      const float a = A[e], b = B[e], c = C[e], d = D[e];
      sx += a * pc[p].x() + b * X[p].x() + c * Y[p].x() + d * Z[p].x();
      sy += a * pc[p].y() + b * X[p].y() + c * Y[p].y() + d * Z[p].y();
      sz += a * pc[p].z() + b * X[p].z() + c * Y[p].z() + d * Z[p].z();
    }
    out[v] = Vec3d(sx, sy, sz);
  }
}

// Batched kernel over W bodies: frames laid out [polygon][12][W], outputs
// [vertex][3][W]; the inner loops over bodies vectorise.
template <int W>
__attribute__((target_clones("avx512f", "avx2", "default"))) void decode_rows_batch(
    const DetailEncoding& enc, const float* frames, std::size_t begin, std::size_t end, float* out) {
  const std::uint32_t* poly = enc.polygon.data();
  const float *A = enc.a.data(), *B = enc.b.data(), *C = enc.c.data(), *D = enc.d.data();
  for (std::size_t v = begin; v < end; ++v) {
    float acc[3][W] = {};
    for (std::uint32_t e = enc.row[v]; e < enc.row[v + 1]; ++e) {
      const float* f = frames + static_cast<std::size_t>(poly[e]) * 12 * W;
      const float a = A[e], b = B[e], c = C[e], d = D[e];
      for (int k = 0; k < 3; ++k)
        for (int w = 0; w < W; ++w)
          acc[k][w] += a * f[k * W + w] + b * f[(3 + k) * W + w] + c * f[(6 + k) * W + w] + d * f[(9 + k) * W + w];
    }
    float* o = out + v * 3 * W;
    for (int k = 0; k < 3; ++k)
      for (int w = 0; w < W; ++w) o[k * W + w] = acc[k][w];
  }
}

}  // namespace

void decode_detail(const DetailEncoding& enc, const PolygonFrames& frames, std::span<Vec3d> out,
                   const ExecContext& ctx) {
  ExecContext c = ctx;
  c.grain = ctx.grain ? ctx.grain : 256;
  par::for_each_block(c, enc.vertex_count(),
                      [&](std::size_t b, std::size_t e) { decode_rows(enc, frames, b, e, out.data()); });
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

Status decode_detail_batch(const DetailEncoding& enc, const BodyPolygons& body, const BodySet& bodies,
                           std::size_t first, std::size_t count, std::span<Vec3f> out, const ExecContext& ctx) {
  if (Status s = check_topology(enc, body); !s) return s;
  if (bodies.node_count() != body.node_count)
    return {ErrorCode::kMismatch, "decode_detail_batch: the body set has another node count than the template's body"};
  if (first + count > bodies.size()) return {ErrorCode::kInvalidArgument, "decode_detail_batch: body range out of bounds"};
  const std::size_t nv = enc.vertex_count();
  if (out.size() != count * nv) return {ErrorCode::kMismatch, "decode_detail_batch: output has the wrong size"};
  constexpr int W = 16;
  const std::size_t np = body.size();
  std::vector<float> frames(np * 12 * W);
  std::vector<float> res(nv * 3 * W);
  PolygonFrames fr;
  std::vector<Vec3d> pos(bodies.node_count());
  for (std::size_t g = 0; g < count; g += W) {
    const std::size_t n = std::min<std::size_t>(W, count - g);
    std::fill(frames.begin(), frames.end(), 0.0f);
    for (std::size_t w = 0; w < n; ++w) {
      bodies.positions(first + g + w, pos);
      compute_frames(body, pos, fr, ctx, enc.reference_corners);
      par::for_each_n(ctx, np, [&](std::size_t p) {
        float* f = frames.data() + p * 12 * W;
        const Vec3f* v[4] = {&fr.centroid[p], &fr.x[p], &fr.y[p], &fr.z[p]};
        for (int j = 0; j < 4; ++j)
          for (int k = 0; k < 3; ++k) f[(3 * j + k) * W + w] = (*v[j])[k];
      });
    }
    ExecContext c = ctx;
    c.grain = ctx.grain ? ctx.grain : 128;
    par::for_each_block(c, nv, [&](std::size_t b, std::size_t e) { decode_rows_batch<W>(enc, frames.data(), b, e, res.data()); });
    par::for_each_n(ctx, nv, [&](std::size_t v) {
      const float* r = res.data() + v * 3 * W;
      for (std::size_t w = 0; w < n; ++w) out[(g + w) * nv + v] = Vec3f(r[w], r[W + w], r[2 * W + w]);
    });
  }
  return {};
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
  if (nv > s.size() || ne > s.size() || nc > s.size() || s.size() < pos + (nv + 1) * 4 + ne * 20 + nc * 8 + 8) fail("truncated file (sizes in the header exceed the file)");
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
