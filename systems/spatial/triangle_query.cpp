#include <atelier/systems/spatial/triangle_query.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include <atelier/engine/parallel.h>

namespace atelier {

namespace {

TrianglePoint segment_point(const Vec3d& p, const Vec3d& a, const Vec3d& b) noexcept {
  const Vec3d ab = b - a;
  const double len2 = ab.squaredNorm();
  double t = len2 > 0.0 ? (p - a).dot(ab) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  TrianglePoint r;
  r.point = a + t * ab;
  r.barycentric = {1.0 - t, t, 0.0};
  return r;
}

}  // namespace

TrianglePoint closest_point_on_triangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) noexcept {
  // Ericson 5.1.5: test the Voronoi regions of the vertices, then the edges,
  // then the face. The region tests are sign tests on dot products, so the
  // reported feature is the one whose region holds p up to rounding.
  TrianglePoint r;
  const Vec3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {a, {1, 0, 0}, TriFeature::kVertex0};
  const Vec3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return {b, {0, 1, 0}, TriFeature::kVertex1};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return {a + v * ab, {1.0 - v, v, 0.0}, TriFeature::kEdge01};
  }
  const Vec3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return {c, {0, 0, 1}, TriFeature::kVertex2};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return {a + w * ac, {1.0 - w, 0.0, w}, TriFeature::kEdge20};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {b + w * (c - b), {0.0, 1.0 - w, w}, TriFeature::kEdge12};
  }
  const double sum = va + vb + vc;
  if (!(sum > 0.0) || !std::isfinite(sum)) {
    // Degenerate (zero-area) triangle: its closest point is on an edge.
    TrianglePoint e0 = segment_point(p, a, b);
    TrianglePoint e1 = segment_point(p, b, c);
    TrianglePoint e2 = segment_point(p, c, a);
    const double q0 = (p - e0.point).squaredNorm(), q1 = (p - e1.point).squaredNorm(),
                 q2 = (p - e2.point).squaredNorm();
    if (q0 <= q1 && q0 <= q2) {
      e0.feature = TriFeature::kEdge01;
      return e0;
    }
    if (q1 <= q2) {
      e1.barycentric = {0.0, e1.barycentric[0], e1.barycentric[1]};
      e1.feature = TriFeature::kEdge12;
      return e1;
    }
    e2.barycentric = {e2.barycentric[1], 0.0, e2.barycentric[0]};
    e2.feature = TriFeature::kEdge20;
    return e2;
  }
  const double denom = 1.0 / sum;
  const double v = vb * denom, w = vc * denom;
  r.point = a + ab * v + ac * w;
  r.barycentric = {1.0 - v - w, v, w};
  r.feature = TriFeature::kFace;
  return r;
}

// ------------------------------------------------------------------ topology

Expected<TriangleTopology> TriangleTopology::build(std::span<const Triangle> triangles, std::uint32_t point_count,
                                                   const ExecContext& ctx) {
  TriangleTopology topo;
  topo.point_count_ = point_count;
  const std::size_t n = triangles.size();
  for (std::size_t t = 0; t < n; ++t)
    for (std::uint32_t c : triangles[t])
      if (c >= point_count)
        return Status(ErrorCode::kInvalidArgument, "triangle " + std::to_string(t) + " uses point " +
                                                       std::to_string(c) + " of " + std::to_string(point_count));
  topo.triangles_.assign(triangles.begin(), triangles.end());
  // Edge adjacency by sorting (lo, hi, triangle, slot) keys: deterministic,
  // O(n log n). An edge is closed when exactly two triangles use it in
  // opposite directions.
  struct Key {
    std::uint32_t lo, hi, tri, slot;
  };
  std::vector<Key> keys(3 * n);
  par::for_each_n(ctx, n, [&](std::size_t t) {
    const Triangle& tr = triangles[t];
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t a = tr[k], b = tr[(k + 1) % 3];
      keys[3 * t + k] = {std::min(a, b), std::max(a, b), static_cast<std::uint32_t>(t), k};
    }
  });
  par::sort(ctx, keys.begin(), keys.end(), [](const Key& x, const Key& y) {
    if (x.lo != y.lo) return x.lo < y.lo;
    if (x.hi != y.hi) return x.hi < y.hi;
    if (x.tri != y.tri) return x.tri < y.tri;
    return x.slot < y.slot;
  });
  topo.across_.assign(n, {kNoTriangle, kNoTriangle, kNoTriangle});
  topo.closed_ = n > 0;
  if (n == 0) topo.open_message_ = "the mesh has no triangles";
  auto fail = [&](const Key& k, const char* why) {
    if (!topo.closed_) return;
    topo.closed_ = false;
    topo.open_message_ = "edge (" + std::to_string(k.lo) + ", " + std::to_string(k.hi) + ") of triangle " +
                         std::to_string(k.tri) + " " + why;
  };
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i + 1;
    while (j < keys.size() && keys[j].lo == keys[i].lo && keys[j].hi == keys[i].hi) ++j;
    if (keys[i].lo == keys[i].hi) {
      fail(keys[i], "is degenerate (repeated vertex)");
    } else if (j - i == 1) {
      fail(keys[i], "is a boundary edge (the mesh is not closed)");
    } else if (j - i > 2) {
      fail(keys[i], "is shared by more than two triangles (non-manifold)");
    } else {
      const Key& x = keys[i];
      const Key& y = keys[i + 1];
      const bool x_forward = triangles[x.tri][x.slot] == x.lo;
      const bool y_forward = triangles[y.tri][y.slot] == y.lo;
      if (x_forward == y_forward) fail(x, "is used twice in the same direction (inconsistent orientation)");
      topo.across_[x.tri][x.slot] = y.tri;
      topo.across_[y.tri][y.slot] = x.tri;
    }
    i = j;
  }
  // Point -> triangles (CSR), each ring in increasing triangle order.
  topo.ring_offset_.assign(std::size_t{point_count} + 1, 0);
  for (const Triangle& tr : triangles)
    for (std::uint32_t c : tr) ++topo.ring_offset_[c + 1];
  std::partial_sum(topo.ring_offset_.begin(), topo.ring_offset_.end(), topo.ring_offset_.begin());
  topo.ring_.resize(3 * n);
  std::vector<std::uint32_t> fill(topo.ring_offset_.begin(), topo.ring_offset_.end() - 1);
  for (std::uint32_t t = 0; t < n; ++t)
    for (std::uint32_t c : triangles[t]) topo.ring_[fill[c]++] = t;
  return topo;
}

// ------------------------------------------------------------ pseudo-normals

Vec3d vertex_pseudo_normal(const TriangleTopology& topo, std::span<const Vec3d> pos, std::uint32_t v) noexcept {
  Vec3d n = Vec3d::Zero();
  for (const std::uint32_t f : topo.triangles_around(v)) {
    const Triangle& q = topo.triangles()[f];
    const int c = q[0] == v ? 0 : (q[1] == v ? 1 : 2);
    const Vec3d e1 = pos[q[(c + 1) % 3]] - pos[v], e2 = pos[q[(c + 2) % 3]] - pos[v];
    const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
    n += angle * unit_face_normal(q, pos);
  }
  return n;
}

Vec3d pseudo_normal(const TriangleTopology& topo, std::span<const Vec3d> pos, std::uint32_t t,
                    TriFeature feature) noexcept {
  switch (feature) {
    case TriFeature::kFace:
      return unit_face_normal(topo.triangles()[t], pos);
    case TriFeature::kEdge01:
    case TriFeature::kEdge12:
    case TriFeature::kEdge20:
      return edge_pseudo_normal(topo, pos, t, static_cast<int>(feature) - static_cast<int>(TriFeature::kEdge01));
    default:
      return vertex_pseudo_normal(topo, pos, topo.triangles()[t][static_cast<int>(feature)]);
  }
}

}  // namespace atelier
