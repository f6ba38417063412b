#include <atelier/systems/spatial/collision_body.h>

#include <emmintrin.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include <atelier/engine/parallel.h>
#include "collision_body_detail.h"

namespace atelier {

namespace {

using collision_detail::float_bound;
using collision_detail::kInf;

// Squared distances from a query box (qlo, qhi: its corners broadcast, in
// float; a point is a box with qlo == qhi) to four boxes (lo, hi: per axis,
// four lanes each), made conservative: every gap shrunk by `slack` (a bound
// on the rounding of the query to float and of one subtraction; the boxes
// are already rounded outward). Returns the mask of lanes whose distance is
// at most `bound`.
inline unsigned box_within_x4(const __m128 qlo[3], const __m128 qhi[3], const float* const lo[3],
                              const float* const hi[3], __m128 slack, float bound, float out[4]) noexcept {
  const __m128 zero = _mm_setzero_ps();
  __m128 s = zero;
  for (int a = 0; a < 3; ++a) {
    const __m128 gap = _mm_max_ps(_mm_sub_ps(_mm_loadu_ps(lo[a]), qhi[a]), _mm_sub_ps(qlo[a], _mm_loadu_ps(hi[a])));
    const __m128 g = _mm_max_ps(_mm_sub_ps(gap, slack), zero);
    s = _mm_add_ps(s, _mm_mul_ps(g, g));
  }
  _mm_store_ps(out, s);
  return static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(s, _mm_set1_ps(bound))));
}


}  // namespace

// ------------------------------------------------------------ topology

Expected<std::shared_ptr<const CollisionTopology>> CollisionTopology::build(std::span<const Triangle> triangles,
                                                                            std::uint32_t point_count) {
  if (triangles.empty() || point_count == 0) return Status(ErrorCode::kInvalidArgument, "collision body: empty mesh");
  auto topo = TriangleTopology::build(triangles, point_count, ExecContext::sequential());
  if (!topo) return Status(topo.status().code(), "collision body: " + topo.status().message());
  if (!topo->closed())
    return Status(ErrorCode::kTopology, "collision body is not closed: " + topo->open_message() +
                                            " (inside and clearance need a closed, oriented body)");
  auto out = std::make_shared<CollisionTopology>();
  out->topo_ = std::move(*topo);
  return std::shared_ptr<const CollisionTopology>(std::move(out));
}

// ------------------------------------------------------------ hierarchy

void CollisionTopology::build_tree(std::span<const Vec3d> pos) const {
  const auto tris = triangles();
  const std::size_t nt = tris.size();
  std::vector<Vec3d> centre(nt);
  for (std::size_t t = 0; t < nt; ++t) centre[t] = (pos[tris[t][0]] + pos[tris[t][1]] + pos[tris[t][2]]) / 3.0;
  leaf_tri_.resize(nt);
  std::iota(leaf_tri_.begin(), leaf_tri_.end(), 0u);
  // The binary hierarchy, kept only until it is collapsed to wide nodes.
  struct TreeNode {
    std::uint32_t first = 0;  // inner: children first, first + 1; leaf: first leaf slot
    std::uint32_t count = 0;  // 0: inner node; else the leaf's triangle count
  };
  std::vector<TreeNode> tree;
  tree.reserve(nt + 2);
  tree.push_back({});
  // Median split of the centroids on the longest axis, down to leaves of at
  // most 4 triangles; children are appended as a pair after their parent.
  struct Task {
    std::uint32_t node, lo, hi;
  };
  std::vector<Task> open_tasks{{0, 0, static_cast<std::uint32_t>(nt)}};
  while (!open_tasks.empty()) {
    const Task k = open_tasks.back();
    open_tasks.pop_back();
    if (k.hi - k.lo <= 4) {
      tree[k.node] = {k.lo, k.hi - k.lo};
      continue;
    }
    Box3d b;
    for (std::uint32_t i = k.lo; i < k.hi; ++i) b.extend(centre[leaf_tri_[i]]);
    int axis = 0;
    (b.hi - b.lo).maxCoeff(&axis);
    const std::uint32_t mid = k.lo + (k.hi - k.lo) / 2;
    std::nth_element(leaf_tri_.begin() + k.lo, leaf_tri_.begin() + mid, leaf_tri_.begin() + k.hi,
                     [&](std::uint32_t x, std::uint32_t y) {
                       return centre[x][axis] < centre[y][axis] || (centre[x][axis] == centre[y][axis] && x < y);
                     });
    const auto child = static_cast<std::uint32_t>(tree.size());
    tree[k.node] = {child, 0};
    tree.push_back({});
    tree.push_back({});
    open_tasks.push_back({child + 1, mid, k.hi});
    open_tasks.push_back({child, k.lo, mid});
  }
  // Leaves padded to four slots each (slot 4 i + k), so that a leaf's
  // triangle boxes are one contiguous 96-byte block (two cache lines
  // instead of one in each of six columns). Padding slots hold kNoTriangle.
  {
    std::vector<std::uint32_t> padded;
    padded.reserve(nt + nt / 2);
    for (TreeNode& nd : tree) {
      if (nd.count == 0) continue;
      const auto first = static_cast<std::uint32_t>(padded.size());
      for (std::uint32_t k = 0; k < 4; ++k) padded.push_back(k < nd.count ? leaf_tri_[nd.first + k] : kNoTriangle);
      nd.first = first;
    }
    leaf_tri_ = std::move(padded);
  }
  // Wide nodes: the lanes of binary node b are its grandchildren (a child
  // that is a leaf stays a lane itself). Depth-first, so a wide node's
  // subtree is contiguous like the binary one's.
  wide_.clear();
  auto make_wide = [&](auto&& self, std::uint32_t b) -> std::uint32_t {
    const auto w = static_cast<std::uint32_t>(wide_.size());
    wide_.push_back({});
    std::uint32_t lanes[4], nl = 0;
    if (tree[b].count > 0) {
      lanes[nl++] = b;
    } else {
      for (std::uint32_t c : {tree[b].first, tree[b].first + 1}) {
        if (tree[c].count > 0) {
          lanes[nl++] = c;
        } else {
          lanes[nl++] = tree[c].first;
          lanes[nl++] = tree[c].first + 1;
        }
      }
    }
    for (std::uint32_t l = 0; l < 4; ++l) {
      if (l >= nl) {
        wide_[w].child[l] = kEmptyLane;
        wide_[w].count[l] = 0;
        continue;
      }
      const TreeNode nd = tree[lanes[l]];
      wide_[w].count[l] = static_cast<std::uint8_t>(nd.count);
      wide_[w].child[l] = nd.count > 0 ? nd.first : self(self, lanes[l]);
    }
    return w;
  };
  make_wide(make_wide, 0);
  leaf_slot_.assign(nt, 0);
  for (std::size_t i = 0; i < leaf_tri_.size(); ++i)
    if (leaf_tri_[i] != kNoTriangle) leaf_slot_[leaf_tri_[i]] = static_cast<std::uint32_t>(i);
}

// ------------------------------------------------------------ body

Status CollisionBody::build(std::shared_ptr<const CollisionTopology> topology, std::span<const Vec3d> positions,
                            const CollisionBodyParams& params, const ExecContext& ctx) {
  // params.roi: see its comment. A scene lent before goes back to the pool
  // first, so that rebuilding a body reuses it.
  topo_.reset();
  embree_.reset();
  if (!topology) return Status(ErrorCode::kInvalidArgument, "collision body: no topology");
  if (positions.size() != topology->point_count())
    return Status(ErrorCode::kMismatch, "collision body: " + std::to_string(positions.size()) +
                                            " positions for a topology of " + std::to_string(topology->point_count()) +
                                            " points");
  // A nanosecond per point: not worth a parallel loop's start-up.
  if (!std::all_of(positions.begin(), positions.end(), [](const Vec3d& q) { return is_finite(q); }))
    return Status(ErrorCode::kDegenerate, "collision body: non-finite position");
  if (params.backend == CollisionBackend::kEmbree) {
    pos_ = positions;
    topo_ = std::move(topology);
    wide_box_.clear();
    tri_box_.clear();
    if (Status s = build_embree(ctx); !s) {
      topo_.reset();
      return s;
    }
    return Status::ok();
  }
  if (params.backend != CollisionBackend::kHierarchy)
    return Status(ErrorCode::kInvalidArgument, "collision body: unknown backend");
  const CollisionTopology& tp = *topology;
  std::call_once(tp.tree_once_, [&] { tp.build_tree(positions); });
  pos_ = positions;
  topo_ = std::move(topology);
  // Refit, in float rounded outward so that a box never excludes its
  // triangle. At least one float ulp outward whichever way the conversion
  // rounded (|f| 2^-23 >= ulp(f); the float minimum covers zero), without a
  // branch.
  auto down = [](double x) {
    const float f = static_cast<float>(x);
    return f - (std::abs(f) * 0x1p-23f + std::numeric_limits<float>::min());
  };
  auto up = [](double x) {
    const float f = static_cast<float>(x);
    return f + (std::abs(f) * 0x1p-23f + std::numeric_limits<float>::min());
  };
  // Sized, not cleared: the loop below writes every slot of every leaf.
  tri_box_.resize(6 * tp.leaf_tri_.size());
  const auto& wide = tp.wide_;
  wide_box_.resize(wide.size());
  constexpr float kFInf = std::numeric_limits<float>::infinity();
  // One pass over the wide nodes, in parallel: each leaf lane computes its
  // triangles' boxes and its own box; empty lanes are inverted infinite
  // boxes. (The leaves read corners through the positions: a per-body copy
  // of them in leaf order, 1.9 MB for the MakeHuman skin, cost more to
  // write than it saved the queries.) Inner lanes follow in the reverse sweep below (children
  // follow their parents). A wide node is a few hundred nanoseconds of
  // work: split small.
  ExecContext lctx = ctx;
  lctx.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 256);
  if (ctx.grain == 0) lctx.grain = 128;
  par::for_each_n(lctx, wide.size(), [&](std::size_t w) {
    WideBox& wb = wide_box_[w];
    for (int l = 0; l < 4; ++l) {
      const std::uint32_t child = wide[w].child[l];
      const std::uint32_t count = wide[w].count[l];
      if (child != CollisionTopology::kEmptyLane && count == 0) continue;
      float lo[3] = {kFInf, kFInf, kFInf}, hi[3] = {-kFInf, -kFInf, -kFInf};
      if (child != CollisionTopology::kEmptyLane) {
        float* tb = &tri_box_[(child / 4) * 24];  // [lo x, y, z, hi x, y, z][slot]
        for (std::uint32_t k = 0; k < 4; ++k) {
          if (k >= count) {  // padding: an inverted infinite box
            for (int a = 0; a < 3; ++a) tb[4 * a + k] = kFInf, tb[4 * (3 + a) + k] = -kFInf;
            continue;
          }
          const Triangle& t = tp.triangles()[tp.leaf_tri_[child + k]];
          const Vec3d& c0 = pos_[t[0]];
          const Vec3d& c1 = pos_[t[1]];
          const Vec3d& c2 = pos_[t[2]];
          const Vec3d tl = c0.cwiseMin(c1).cwiseMin(c2), th = c0.cwiseMax(c1).cwiseMax(c2);
          for (int a = 0; a < 3; ++a) {
            const float fl = down(tl[a]), fh = up(th[a]);
            tb[4 * a + k] = fl;
            tb[4 * (3 + a) + k] = fh;
            lo[a] = std::min(lo[a], fl);
            hi[a] = std::max(hi[a], fh);
          }
        }
      }
      for (int a = 0; a < 3; ++a) {
        wb.lo[a][l] = lo[a];
        wb.hi[a][l] = hi[a];
      }
    }
  });
  for (std::size_t w = wide.size(); w-- > 0;)
    for (int l = 0; l < 4; ++l) {
      const std::uint32_t child = wide[w].child[l];
      if (child == CollisionTopology::kEmptyLane || wide[w].count[l] > 0) continue;
      const WideBox& cb = wide_box_[child];
      for (int a = 0; a < 3; ++a) {
        wide_box_[w].lo[a][l] = *std::min_element(cb.lo[a], cb.lo[a] + 4);
        wide_box_[w].hi[a][l] = *std::max_element(cb.hi[a], cb.hi[a] + 4);
      }
    }
  extent_ = 0;
  const WideBox& root = wide_box_[0];
  for (int l = 0; l < 4; ++l)
    if (wide[0].child[l] != CollisionTopology::kEmptyLane)
      for (int a = 0; a < 3; ++a)
        extent_ = std::max(
            {extent_, std::abs(static_cast<double>(root.lo[a][l])), std::abs(static_cast<double>(root.hi[a][l]))});
  return Status::ok();
}

BodyDistance CollisionBody::query_triangle(const Vec3d& p, std::uint32_t t) const noexcept {
  const Triangle& tr = topo_->triangles()[t];
  return signed_distance(p, t, closest_point_on_triangle(p, pos_[tr[0]], pos_[tr[1]], pos_[tr[2]]));
}

BodyDistance CollisionBody::signed_distance(const Vec3d& p, std::uint32_t t, const TrianglePoint& r) const noexcept {
  // The pseudo-normal of the closest feature, computed on demand (most
  // queries land on faces), and the sign rule of triangle_query.h.
  const Vec3d pn = pseudo_normal(topo_->triangle_topology(), pos_, t, r.feature);
  BodyDistance out;
  out.closest = r.point;
  out.barycentric = r.barycentric;
  out.triangle = t;
  const Vec3d d = p - r.point;
  const double len = d.norm();
  const double sign = pseudo_normal_sign(p, r.point, pn);
  out.distance = sign * len;
  // Outward direction: the distance gradient off the surface, the
  // pseudo-normal on it.
  const double pl = pn.norm();
  out.normal = len > 1e-12 ? Vec3d(sign * d / len) : (pl > 0 ? Vec3d(pn / pl) : Vec3d::UnitZ());
  return out;
}

// A point broadcast in float for the four-lane box tests, with the slack
// that makes them conservative: a bound on the rounding of the point to
// float and of one subtraction, relative to the largest coordinate in play
// (boxes are already rounded outward).
struct CollisionBody::FloatPoint {
  __m128 lo[3], hi[3];
  __m128 slack;
  FloatPoint(const Vec3d& p, double extent) noexcept : FloatPoint(p, p, extent) {}
  FloatPoint(const Vec3d& a, const Vec3d& b, double extent) noexcept {  // the box [a, b]
    const double scale = extent + std::max({std::abs(a[0]), std::abs(a[1]), std::abs(a[2]), std::abs(b[0]),
                                            std::abs(b[1]), std::abs(b[2])});
    slack = _mm_set1_ps(static_cast<float>(std::ldexp(scale, -21)));
    for (int k = 0; k < 3; ++k) {
      lo[k] = _mm_set1_ps(static_cast<float>(a[k]));
      hi[k] = _mm_set1_ps(static_cast<float>(b[k]));
    }
  }
};

// The lanes of a wide node within `bound` of the query (box_within_x4).
unsigned CollisionBody::lanes_within(const FloatPoint& q, const WideBox& b, float bound, float d2[4]) noexcept {
  const float* const lo[3] = {b.lo[0], b.lo[1], b.lo[2]};
  const float* const hi[3] = {b.hi[0], b.hi[1], b.hi[2]};
  return box_within_x4(q.lo, q.hi, lo, hi, q.slack, bound, d2);
}

CollisionBody::Best CollisionBody::start_from_hint(const Vec3d& p, std::uint32_t hint) const noexcept {
  Best b;
  if (hint < topo_->triangles().size()) {
    // On a body of the same topology the hint's distance bounds the answer.
    // (A greedy walk from the hint to nearer neighbours tightened the bound
    // but cost more than it pruned: 12% slower queries on MakeHuman bodies.)
    const Triangle& tr = topo_->triangles()[hint];
    b.r = closest_point_on_triangle(p, pos_[tr[0]], pos_[tr[1]], pos_[tr[2]]);
    b.d2 = (p - b.r.point).squaredNorm();
    b.d2f = float_bound(b.d2);
    b.t = hint;
  }
  return b;
}

// A leaf's triangles: their own boxes first, four at once, then the exact
// distance of those within the bound.
void CollisionBody::scan_leaf(const Vec3d& p, const FloatPoint& fp, std::uint32_t first, Best& best) const noexcept {
  const float* tb = &tri_box_[(first / 4) * 24];
  const float* const lo[3] = {tb, tb + 4, tb + 8};
  const float* const hi[3] = {tb + 12, tb + 16, tb + 20};
  alignas(16) float d2[4];
  // Padding slots are inverted infinite boxes: never within.
  unsigned m = box_within_x4(fp.lo, fp.hi, lo, hi, fp.slack, best.d2f, d2);
  for (; m != 0; m &= m - 1) {
    const std::uint32_t t = topo_->leaf_tri_[first + static_cast<std::uint32_t>(std::countr_zero(m))];
    if (t == best.t) continue;
    const Triangle& c = topo_->triangles()[t];
    const TrianglePoint r = closest_point_on_triangle(p, pos_[c[0]], pos_[c[1]], pos_[c[2]]);
    best.take((p - r.point).squaredNorm(), t, r);
  }
}

BodyDistance CollisionBody::query(const Vec3d& p, std::uint32_t hint) const noexcept {
  if (embree_) return query_embree(p, hint);
  Best best = start_from_hint(p, hint);
  // Branch and bound over the wide hierarchy, nearer lanes first. Boxes
  // at exactly the best distance are still opened: ties go to the smaller
  // triangle index, so the answer does not depend on the hint. Box
  // distances are computed in float, four lanes at once, made conservative
  // (FloatPoint, float_bound), so a box is never skipped that the exact
  // distance would open.
  const auto& wide = topo_->wide_;
  const FloatPoint fp(p, extent_);
  struct Item {
    std::uint32_t ref;    // wide node, or first leaf slot
    std::uint32_t count;  // 0: wide node
    float d2;
  };
  Item stack[64];
  int top = 0;
  stack[top++] = {0, 0, 0.0f};
  alignas(16) float d2[4];
  while (top > 0) {
    const Item it = stack[--top];
    if (it.d2 > best.d2f) continue;
    if (it.count > 0) {
      scan_leaf(p, fp, it.ref, best);
      continue;
    }
    const CollisionTopology::WideNode& nd = wide[it.ref];
    const WideBox& bx = wide_box_[it.ref];
    // Lanes within the bound (empty lanes are inverted infinite boxes,
    // never within), pushed far to near so the nearest is popped first.
    const int base = top;
    for (unsigned m = lanes_within(fp, bx, best.d2f, d2); m != 0; m &= m - 1) {
      const int l = std::countr_zero(m);
      const float dl = d2[l];
      int k = top++;
      for (; k > base && stack[k - 1].d2 < dl; --k) stack[k] = stack[k - 1];
      stack[k] = {nd.child[l], nd.count[l], dl};
    }
  }
  // The closest point as the leaf test found it.
  return signed_distance(p, best.t, best.r);
}

Status CollisionBody::query_cluster(std::span<const Vec3d> p, std::span<const std::uint32_t> hint,
                                    std::span<BodyDistance> out) const {
  if (empty()) return Status(ErrorCode::kInvalidArgument, "query_cluster: collision body not built");
  if (hint.size() != p.size() || out.size() != p.size())
    return Status(ErrorCode::kMismatch, "query_cluster: " + std::to_string(p.size()) + " points, " +
                                            std::to_string(hint.size()) + " hints and " + std::to_string(out.size()) +
                                            " outputs");
  query_cluster_at(nullptr, p.size(), p, hint, out);
  return Status::ok();
}

// Point i of the cluster is p[at(i)] (idx null: i itself), so query_many
// needs no gathered copies.
void CollisionBody::query_cluster_at(const std::uint32_t* idx, std::size_t n, std::span<const Vec3d> p,
                                     std::span<const std::uint32_t> hint, std::span<BodyDistance> out) const noexcept {
  auto at = [idx](std::size_t i) { return idx ? idx[i] : i; };
  auto one_by_one = [&] {
    for (std::size_t i = 0; i < n; ++i) out[at(i)] = query(p[at(i)], hint[at(i)]);
  };
  if (n == 0) return;
  if (n > kClusterMax) return one_by_one();
  if (embree_) return query_cluster_embree(idx, n, p, hint, out);
  // Every point's hint bounds its answer: a triangle nearer to p_i than
  // r_i lies within r = max r_i of the cluster's bounding box, so one
  // traversal with that box and bound collects every leaf any point needs.
  Best best[kClusterMax];
  Vec3d lo = p[at(0)], hi = p[at(0)];
  double r2 = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (hint[at(i)] >= topo_->triangles().size()) return one_by_one();
    best[i] = start_from_hint(p[at(i)], hint[at(i)]);
    lo = lo.cwiseMin(p[at(i)]);
    hi = hi.cwiseMax(p[at(i)]);
    r2 = std::max(r2, best[i].d2);
  }
  const float bound = float_bound(r2);
  const FloatPoint fc(lo, hi, extent_);
  // The leaves within the bound, with their boxes in four-lane columns.
  constexpr std::size_t kMaxLeaves = 96;
  alignas(16) float leaf_box[6][kMaxLeaves + 4];
  std::uint32_t leaf_first[kMaxLeaves];
  std::size_t leaves = 0;
  const auto& wide = topo_->wide_;
  std::uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  alignas(16) float d2[4];
  while (top > 0) {
    const std::uint32_t w = stack[--top];
    const WideBox& bx = wide_box_[w];
    for (unsigned m = lanes_within(fc, bx, bound, d2); m != 0; m &= m - 1) {
      const int l = std::countr_zero(m);
      if (wide[w].count[l] == 0) {
        stack[top++] = wide[w].child[l];
        continue;
      }
      // A large bound (a point far from the body, a spread-out cluster):
      // single queries prune better.
      if (leaves == kMaxLeaves) return one_by_one();
      for (int a = 0; a < 3; ++a) {
        leaf_box[a][leaves] = bx.lo[a][l];
        leaf_box[3 + a][leaves] = bx.hi[a][l];
      }
      leaf_first[leaves] = wide[w].child[l];
      ++leaves;
    }
  }
  // Pad the last group of four with inverted infinite boxes.
  for (std::size_t j = leaves; j % 4 != 0; ++j)
    for (int a = 0; a < 3; ++a) {
      leaf_box[a][j] = std::numeric_limits<float>::infinity();
      leaf_box[3 + a][j] = -std::numeric_limits<float>::infinity();
    }
  // Per point: the collected leaves' boxes four at once, then the triangles
  // of those within its own bound, exactly as query() would.
  for (std::size_t i = 0; i < n; ++i) {
    const FloatPoint fp(p[at(i)], extent_);
    for (std::size_t j = 0; j < leaves; j += 4) {
      const float* const llo[3] = {&leaf_box[0][j], &leaf_box[1][j], &leaf_box[2][j]};
      const float* const lhi[3] = {&leaf_box[3][j], &leaf_box[4][j], &leaf_box[5][j]};
      for (unsigned m = box_within_x4(fp.lo, fp.hi, llo, lhi, fp.slack, best[i].d2f, d2); m != 0; m &= m - 1) {
        const std::size_t k = j + static_cast<std::size_t>(std::countr_zero(m));
        scan_leaf(p[at(i)], fp, leaf_first[k], best[i]);
      }
    }
    out[at(i)] = signed_distance(p[at(i)], best[i].t, best[i].r);
  }
}

Status CollisionBody::query_many(std::span<const Vec3d> p, std::span<const std::uint32_t> hint,
                                 std::span<BodyDistance> out, const ExecContext& ctx) const {
  const std::size_t n = p.size();
  if (empty()) return Status(ErrorCode::kInvalidArgument, "query_many: collision body not built");
  if (out.size() != n || (!hint.empty() && hint.size() != n))
    return Status(ErrorCode::kMismatch, "query_many: " + std::to_string(n) + " points, " + std::to_string(hint.size()) +
                                            " hints and " + std::to_string(out.size()) + " outputs");
  ExecContext qctx = ctx;
  qctx.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 256);
  if (ctx.grain == 0) qctx.grain = 64;
  if (hint.empty()) {
    par::for_each_n(qctx, n, [&](std::size_t v) { out[v] = query(p[v]); });
    return Status::ok();
  }
  // Counting sort by the hint's leaf slot (points without a usable hint
  // last): neighbours in the hierarchy's leaf order are neighbours on the
  // body, so consecutive points form compact clusters.
  // (Embree's layout is not ours to read: its bodies order points by the
  // hint's index, neighbours too on bodies whose triangles are numbered in
  // rows, as MakeHuman's and the mannequin's are.)
  const std::size_t nt = topo_->triangles().size(), slots = embree_ ? nt : topo_->leaf_tri_.size();
  auto key = [&](std::size_t v) -> std::uint32_t {
    if (hint[v] >= nt) return static_cast<std::uint32_t>(slots);
    return embree_ ? hint[v] : topo_->leaf_slot_[hint[v]];
  };
  std::vector<std::uint32_t> start(slots + 2, 0), order(n);
  for (std::size_t v = 0; v < n; ++v) ++start[key(v) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  for (std::size_t v = 0; v < n; ++v) order[start[key(v)]++] = static_cast<std::uint32_t>(v);
  constexpr std::size_t kCluster = 8;
  ExecContext cctx = ctx;
  cctx.sequential_threshold = std::min<std::size_t>(ctx.sequential_threshold, 16);
  if (ctx.grain == 0) cctx.grain = 4;
  par::for_each_n(cctx, (n + kCluster - 1) / kCluster, [&](std::size_t k) {
    const std::size_t i0 = k * kCluster;
    query_cluster_at(order.data() + i0, std::min(kCluster, n - i0), p, hint, out);
  });
  return Status::ok();
}

}  // namespace atelier
