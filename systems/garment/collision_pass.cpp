#include <atelier/systems/garment/collision_pass.h>

#include <emmintrin.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include <atelier/engine/parallel.h>

namespace atelier {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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

std::string vec_str(const Vec3d& p) {
  std::ostringstream s;
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

}  // namespace

// ------------------------------------------------------------ topology

Expected<std::shared_ptr<const CollisionTopology>> CollisionTopology::build(std::span<const Triangle> triangles,
                                                                            std::uint32_t point_count) {
  if (triangles.empty() || point_count == 0) return Status(ErrorCode::kInvalidArgument, "collision body: empty mesh");
  auto topo = std::make_shared<CollisionTopology>();
  topo->triangles_.assign(triangles.begin(), triangles.end());
  topo->point_count_ = point_count;
  const std::size_t n = triangles.size();
  for (std::size_t t = 0; t < n; ++t)
    for (std::uint32_t c : triangles[t])
      if (c >= point_count)
        return Status(ErrorCode::kInvalidArgument, "collision body: triangle " + std::to_string(t) + " uses point " +
                                                       std::to_string(c) + " of " + std::to_string(point_count));
  // Edge adjacency by sorting (lo, hi, triangle, corner) keys: deterministic.
  struct Key {
    std::uint32_t lo, hi, t, k;
  };
  std::vector<Key> keys(3 * n);
  for (std::uint32_t t = 0; t < n; ++t)
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t a = triangles[t][k], b = triangles[t][(k + 1) % 3];
      keys[3 * t + k] = {std::min(a, b), std::max(a, b), t, k};
    }
  std::sort(keys.begin(), keys.end(),
            [](const Key& x, const Key& y) { return std::tie(x.lo, x.hi, x.t, x.k) < std::tie(y.lo, y.hi, y.t, y.k); });
  topo->across_.assign(n, {kNoTriangle, kNoTriangle, kNoTriangle});
  auto open = [&](const Key& k, const char* why) {
    return Status(ErrorCode::kTopology, "collision body is not closed: edge (" + std::to_string(k.lo) + ", " +
                                            std::to_string(k.hi) + ") of triangle " + std::to_string(k.t) + " " + why +
                                            " (inside and clearance need a closed, oriented body)");
  };
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    while (j < keys.size() && keys[j].lo == keys[i].lo && keys[j].hi == keys[i].hi) ++j;
    if (j - i == 1) return open(keys[i], "has one triangle (boundary)");
    if (j - i > 2) return open(keys[i], "has more than two triangles");
    const Key &x = keys[i], &y = keys[i + 1];
    if (triangles[x.t][x.k] == triangles[y.t][y.k]) return open(x, "is used twice in the same direction");
    topo->across_[x.t][x.k] = y.t;
    topo->across_[y.t][y.k] = x.t;
    i = j;
  }
  topo->vt_offset_.assign(point_count + 1, 0);
  for (const auto& tr : triangles)
    for (std::uint32_t c : tr) ++topo->vt_offset_[c + 1];
  std::partial_sum(topo->vt_offset_.begin(), topo->vt_offset_.end(), topo->vt_offset_.begin());
  topo->vt_tri_.resize(3 * n);
  std::vector<std::uint32_t> fill(topo->vt_offset_.begin(), topo->vt_offset_.end() - 1);
  for (std::uint32_t t = 0; t < n; ++t)
    for (std::uint32_t c : triangles[t]) topo->vt_tri_[fill[c]++] = t;
  return std::shared_ptr<const CollisionTopology>(std::move(topo));
}

// ------------------------------------------------------------ hierarchy

void CollisionTopology::build_tree(std::span<const Vec3d> pos) const {
  const std::size_t nt = triangles_.size();
  std::vector<Vec3d> centre(nt);
  for (std::size_t t = 0; t < nt; ++t)
    centre[t] = (pos[triangles_[t][0]] + pos[triangles_[t][1]] + pos[triangles_[t][2]]) / 3.0;
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
                            const CollisionBodyParams& /*params: see its comment*/, const ExecContext& ctx) {
  topo_.reset();
  if (!topology) return Status(ErrorCode::kInvalidArgument, "collision body: no topology");
  if (positions.size() != topology->point_count())
    return Status(ErrorCode::kMismatch, "collision body: " + std::to_string(positions.size()) +
                                            " positions for a topology of " + std::to_string(topology->point_count()) +
                                            " points");
  // A nanosecond per point: not worth a parallel loop's start-up.
  if (!std::all_of(positions.begin(), positions.end(), [](const Vec3d& q) { return is_finite(q); }))
    return Status(ErrorCode::kDegenerate, "collision body: non-finite position");
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
          const Triangle& t = tp.triangles_[tp.leaf_tri_[child + k]];
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

Vec3d CollisionBody::face_normal(std::uint32_t t) const noexcept {
  const Triangle& tr = topo_->triangles_[t];
  return (pos_[tr[1]] - pos_[tr[0]]).cross(pos_[tr[2]] - pos_[tr[0]]);
}

BodyDistance CollisionBody::query_triangle(const Vec3d& p, std::uint32_t t) const noexcept {
  const Triangle& tr = topo_->triangles_[t];
  return signed_distance(p, t, closest_point_on_triangle(p, pos_[tr[0]], pos_[tr[1]], pos_[tr[2]]));
}

BodyDistance CollisionBody::signed_distance(const Vec3d& p, std::uint32_t t, const TrianglePoint& r) const noexcept {
  const Triangle& tr = topo_->triangles_[t];
  // Angle-weighted pseudo-normal of the closest feature (Baerentzen & Aanaes
  // 2005): the face normal, the sum of the two unit face normals of an edge,
  // or the incident unit face normals weighted by their angles at a vertex.
  auto unit_face = [&](std::uint32_t f) {
    const Vec3d n = face_normal(f);
    const double l = n.norm();
    return l > 0 ? Vec3d(n / l) : Vec3d::Zero();
  };
  Vec3d pn;
  switch (r.feature) {
    case TriFeature::kFace:
      pn = unit_face(t);
      break;
    case TriFeature::kEdge01:
    case TriFeature::kEdge12:
    case TriFeature::kEdge20: {
      const int k = static_cast<int>(r.feature) - static_cast<int>(TriFeature::kEdge01);
      pn = unit_face(t) + unit_face(topo_->across_[t][k]);
      break;
    }
    default: {
      const std::uint32_t v = tr[static_cast<int>(r.feature)];
      pn = Vec3d::Zero();
      for (std::uint32_t i = topo_->vt_offset_[v]; i < topo_->vt_offset_[v + 1]; ++i) {
        const std::uint32_t f = topo_->vt_tri_[i];
        const Triangle& q = topo_->triangles_[f];
        const int c = q[0] == v ? 0 : (q[1] == v ? 1 : 2);
        const Vec3d e1 = pos_[q[(c + 1) % 3]] - pos_[v], e2 = pos_[q[(c + 2) % 3]] - pos_[v];
        const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
        pn += angle * unit_face(f);
      }
    }
  }
  BodyDistance out;
  out.closest = r.point;
  out.barycentric = r.barycentric;
  out.triangle = t;
  const Vec3d d = p - r.point;
  const double len = d.norm();
  const double sign = d.dot(pn) < 0 ? -1.0 : 1.0;
  out.distance = sign * len;
  // Outward direction: the distance gradient off the surface, the
  // pseudo-normal on it.
  const double pl = pn.norm();
  out.normal = len > 1e-12 ? Vec3d(sign * d / len) : (pl > 0 ? Vec3d(pn / pl) : Vec3d::UnitZ());
  return out;
}

namespace {

// A squared bound in float for the lane tests, rounded up with a relative
// margin (2e-6, far above float rounding): a lane is opened when its
// conservative box distance is at most the bound, so every box the exact
// test would open is opened (ties included).
inline float float_bound(double b2) noexcept {
  return static_cast<float>(std::min(b2 * (1.0 + 2e-6), static_cast<double>(std::numeric_limits<float>::max())));
}

}  // namespace

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

struct CollisionBody::Best {
  double d2 = kInf;
  float d2f = std::numeric_limits<float>::max();
  std::uint32_t t = kNoTriangle;
  TrianglePoint r;
  void take(double d, std::uint32_t tri, const TrianglePoint& at) noexcept {
    if (d < d2 || (d == d2 && tri < t)) {
      d2 = d;
      d2f = float_bound(d);
      t = tri;
      r = at;
    }
  }
};

CollisionBody::Best CollisionBody::start_from_hint(const Vec3d& p, std::uint32_t hint) const noexcept {
  Best b;
  if (hint < topo_->triangles_.size()) {
    // On a body of the same topology the hint's distance bounds the answer.
    // (A greedy walk from the hint to nearer neighbours tightened the bound
    // but cost more than it pruned: 12% slower queries on MakeHuman bodies.)
    const Triangle& tr = topo_->triangles_[hint];
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
    const Triangle& c = topo_->triangles_[t];
    const TrianglePoint r = closest_point_on_triangle(p, pos_[c[0]], pos_[c[1]], pos_[c[2]]);
    best.take((p - r.point).squaredNorm(), t, r);
  }
}

BodyDistance CollisionBody::query(const Vec3d& p, std::uint32_t hint) const noexcept {
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
  // Every point's hint bounds its answer: a triangle nearer to p_i than
  // r_i lies within r = max r_i of the cluster's bounding box, so one
  // traversal with that box and bound collects every leaf any point needs.
  Best best[kClusterMax];
  Vec3d lo = p[at(0)], hi = p[at(0)];
  double r2 = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (hint[at(i)] >= topo_->triangles_.size()) return one_by_one();
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
  const std::size_t nt = topo_->triangles_.size(), slots = topo_->leaf_tri_.size();
  auto key = [&](std::size_t v) {
    return hint[v] < nt ? topo_->leaf_slot_[hint[v]] : static_cast<std::uint32_t>(slots);
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
    if (!floor.empty()) target[v] = std::max(target[v], floor_at(floor, body, d[v]) + prm.layer_gap);
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
    constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
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
