#include "systems/collision_pass.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include "engine/parallel.h"

namespace atelier {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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

// ------------------------------------------------------------ body

Status CollisionBody::build(std::shared_ptr<const CollisionTopology> topology, std::span<const Vec3d> positions,
                            const CollisionBodyParams& params, const ExecContext& ctx) {
  topo_.reset();
  if (!topology) return Status(ErrorCode::kInvalidArgument, "collision body: no topology");
  if (positions.size() != topology->point_count())
    return Status(ErrorCode::kMismatch, "collision body: " + std::to_string(positions.size()) +
                                            " positions for a topology of " + std::to_string(topology->point_count()) +
                                            " points");
  if (!(params.cell >= 0) || !(params.margin >= 0))
    return Status(ErrorCode::kInvalidArgument, "collision body: negative cell or margin");
  const auto tris = topology->triangles();
  const std::size_t nt = tris.size();
  // Bounds and mean edge length (one edge per triangle) in one reduction.
  struct Acc {
    Box3d box;
    double len = 0;
    bool finite = true;
  };
  const Acc acc = par::transform_reduce(
      ctx, nt, Acc{},
      [&](std::size_t t) {
        Acc a;
        for (std::uint32_t c : tris[t]) {
          a.finite = a.finite && is_finite(positions[c]);
          a.box.extend(positions[c]);
        }
        a.len = (positions[tris[t][1]] - positions[tris[t][0]]).norm();
        return a;
      },
      [](Acc x, const Acc& y) {
        x.box.extend(y.box.lo);
        x.box.extend(y.box.hi);
        x.len += y.len;
        x.finite = x.finite && y.finite;
        return x;
      });
  if (!acc.finite) return Status(ErrorCode::kDegenerate, "collision body: non-finite position");
  double h = params.cell > 0 ? params.cell : 4.0 * acc.len / static_cast<double>(nt);
  if (!(h > 0)) return Status(ErrorCode::kDegenerate, "collision body: all triangles are degenerate");
  Box3d box = params.roi.empty() ? acc.box : params.roi;
  box.lo -= Vec3d::Constant(params.margin);
  box.hi += Vec3d::Constant(params.margin);
  // Queries whose search ball stays in this box are answered from the grid:
  // the grid itself stops at the body's box, beyond which there is nothing.
  valid_lo_ = box.lo;
  valid_hi_ = box.hi;
  box.lo = box.lo.cwiseMax(acc.box.lo - Vec3d::Constant(h));  // nothing to bin beyond the body
  box.hi = box.hi.cwiseMin(acc.box.hi + Vec3d::Constant(h));
  pos_ = positions;
  topo_ = std::move(topology);
  start_.clear();
  ids_.clear();
  nx_ = ny_ = nz_ = 0;
  // Bounding sphere per triangle (centroid, farthest corner): a cheap lower
  // bound on its distance, tested before the exact one.
  sphere_.resize(nt);
  par::for_each_n(ctx, nt, [&](std::size_t t) {
    const Vec3d c = (pos_[tris[t][0]] + pos_[tris[t][1]] + pos_[tris[t][2]]) / 3.0;
    double r = 0;
    for (std::uint32_t k : tris[t]) r = std::max(r, (pos_[k] - c).norm());
    sphere_[t] << c, r * (1 + 1e-12) + 1e-15;  // rounding: the bound must stay a bound
  });
  if (box.empty()) {  // ROI away from the body: every query scans all triangles
    lo_ = hi_ = Vec3d::Zero();
    return Status::ok();
  }
  // Coarse cells: at most ~2M cells whatever the ROI (a finer grid costs
  // more to fill than it saves).
  const Vec3d ext = box.hi - box.lo;
  while ((std::ceil(ext.x() / h) * std::ceil(ext.y() / h) * std::ceil(ext.z() / h)) > 2e6) h *= 1.25;
  h_ = h;
  inv_h_ = 1.0 / h;
  nx_ = std::max(1, static_cast<int>(std::ceil(ext.x() * inv_h_)));
  ny_ = std::max(1, static_cast<int>(std::ceil(ext.y() * inv_h_)));
  nz_ = std::max(1, static_cast<int>(std::ceil(ext.z() * inv_h_)));
  lo_ = box.lo;
  hi_ = lo_ + h * Vec3d(nx_, ny_, nz_);
  // Cell range of every triangle's box (empty when outside the grid), then
  // counting sort into CSR: deterministic, triangles ascending per cell.
  std::vector<std::array<int, 6>> range(nt);
  par::for_each_n(ctx, nt, [&](std::size_t t) {
    Box3d b;
    for (std::uint32_t c : tris[t]) b.extend(pos_[c]);

    auto& r = range[t];
    const Vec3d l = (b.lo - lo_) * inv_h_, u = (b.hi - lo_) * inv_h_;
    const int dims[3] = {nx_, ny_, nz_};
    for (int a = 0; a < 3; ++a) {
      r[a] = std::max(0, static_cast<int>(std::floor(l[a])));
      r[a + 3] = std::min(dims[a] - 1, static_cast<int>(std::floor(u[a])));
    }
  });
  const std::size_t ncell = static_cast<std::size_t>(nx_) * ny_ * nz_;
  start_.assign(ncell + 1, 0);
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& r = range[t];
    for (int z = r[2]; z <= r[5]; ++z)
      for (int y = r[1]; y <= r[4]; ++y)
        for (int x = r[0]; x <= r[3]; ++x) ++start_[(static_cast<std::size_t>(z) * ny_ + y) * nx_ + x + 1];
  }
  std::partial_sum(start_.begin(), start_.end(), start_.begin());
  ids_.resize(start_.back());
  // Float spheres, widened by 1 um so that the rounding of the centre
  // (< 0.2 um for coordinates of a few metres) cannot make them too small.
  std::vector<GridEntry> entry(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const Vec4d& sp = sphere_[t];
    entry[t] = {{static_cast<float>(sp[0]), static_cast<float>(sp[1]), static_cast<float>(sp[2])},
                static_cast<float>(sp[3] * (1 + 1e-6) + 1e-6),
                static_cast<std::uint32_t>(t)};
  }
  std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& r = range[t];
    for (int z = r[2]; z <= r[5]; ++z)
      for (int y = r[1]; y <= r[4]; ++y)
        for (int x = r[0]; x <= r[3]; ++x) ids_[fill[(static_cast<std::size_t>(z) * ny_ + y) * nx_ + x]++] = entry[t];
  }
  return Status::ok();
}

Vec3d CollisionBody::face_normal(std::uint32_t t) const noexcept {
  const Triangle& tr = topo_->triangles_[t];
  return (pos_[tr[1]] - pos_[tr[0]]).cross(pos_[tr[2]] - pos_[tr[0]]);
}

BodyDistance CollisionBody::query_triangle(const Vec3d& p, std::uint32_t t) const noexcept {
  const Triangle& tr = topo_->triangles_[t];
  const TrianglePoint r = closest_point_on_triangle(p, pos_[tr[0]], pos_[tr[1]], pos_[tr[2]]);
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

void CollisionBody::scan_cells(const Vec3d& p, double& best2, std::uint32_t& best_t) const noexcept {
  const double r = std::sqrt(best2);
  const Vec3d l = (p - Vec3d::Constant(r) - lo_) * inv_h_, u = (p + Vec3d::Constant(r) - lo_) * inv_h_;
  // Clamp in double before converting: far points must not overflow int.
  auto lo_cell = [](double x, int n) { return static_cast<int>(std::clamp(std::floor(x), 0.0, double(n))); };
  auto hi_cell = [](double x, int n) { return static_cast<int>(std::clamp(std::floor(x), -1.0, double(n - 1))); };
  const int x0 = lo_cell(l.x(), nx_), x1 = hi_cell(u.x(), nx_);
  const int y0 = lo_cell(l.y(), ny_), y1 = hi_cell(u.y(), ny_);
  const int z0 = lo_cell(l.z(), nz_), z1 = hi_cell(u.z(), nz_);
  const auto& tris = topo_->triangles_;
  for (int z = z0; z <= z1; ++z)
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        // Skip cells whose box is no nearer than the best distance so far.
        const Vec3d c0 = lo_ + h_ * Vec3d(x, y, z);
        const Vec3d gap = (c0 - p).cwiseMax(p - c0 - Vec3d::Constant(h_)).cwiseMax(0.0);
        if (gap.squaredNorm() > best2) continue;
        const std::size_t cell = (static_cast<std::size_t>(z) * ny_ + y) * nx_ + x;
        for (std::uint32_t i = start_[cell]; i < start_[cell + 1]; ++i) {
          // Bounding sphere first, stored in the entry (no indirection):
          // most candidates end here.
          const GridEntry& en = ids_[i];
          const double dx = p.x() - en.c[0], dy = p.y() - en.c[1], dz = p.z() - en.c[2];
          const double cd2 = dx * dx + dy * dy + dz * dz;
          if (cd2 > best2) {  // cheap pre-test before the square root
            const double dc = std::sqrt(cd2) - en.r;
            if (dc > 0 && dc * dc > best2) continue;
          }
          const std::uint32_t t = en.t;
          if (t == best_t) continue;
          const Triangle& tr = tris[t];
          const TrianglePoint q = closest_point_on_triangle(p, pos_[tr[0]], pos_[tr[1]], pos_[tr[2]]);
          const double d2 = (p - q.point).squaredNorm();
          if (d2 < best2 || (d2 == best2 && t < best_t)) {
            best2 = d2;
            best_t = t;
          }
        }
      }
}

BodyDistance CollisionBody::query(const Vec3d& p, std::uint32_t hint) const noexcept {
  const auto& tris = topo_->triangles_;
  double best2 = kInf;
  std::uint32_t best_t = kNoTriangle;
  if (hint < tris.size()) {
    // On a body of the same topology the hint's distance bounds the answer.
    const Triangle& tr = tris[hint];
    best2 = (p - closest_point_on_triangle(p, pos_[tr[0]], pos_[tr[1]], pos_[tr[2]]).point).squaredNorm();
    best_t = hint;
    // Greedy walk across edges to a nearer triangle: on a deformed body the
    // closest triangle is usually a few steps from the hint, and a tighter
    // bound shrinks the ball the grid has to certify (cost ~ radius^2).
    for (int step = 0; step < 16; ++step) {
      const std::uint32_t from = best_t;
      for (std::uint32_t o : topo_->across_[from]) {
        const Triangle& q = tris[o];
        const double d2 = (p - closest_point_on_triangle(p, pos_[q[0]], pos_[q[1]], pos_[q[2]]).point).squaredNorm();
        if (d2 < best2) {
          best2 = d2;
          best_t = o;
        }
      }
      if (best_t == from) break;
    }
  }
  auto in_grid = [&](double r) {
    return nx_ > 0 && (p.array() - r >= valid_lo_.array()).all() && (p.array() + r <= valid_hi_.array()).all();
  };
  if (best_t != kNoTriangle) {
    if (in_grid(std::sqrt(best2))) {
      scan_cells(p, best2, best_t);
      return query_triangle(p, best_t);
    }
  } else {
    // No hint: grow the search ball from one cell until it holds a triangle.
    for (double r = h_; in_grid(r); r *= 2) {
      double b2 = r * r;
      std::uint32_t bt = kNoTriangle;
      scan_cells(p, b2, bt);
      if (bt != kNoTriangle) return query_triangle(p, bt);
    }
  }
  // The ball leaves the grid (far from the region of interest): full scan.
  for (std::uint32_t t = 0; t < tris.size(); ++t) {
    const Vec4d& sp = sphere_[t];
    const double dc = (p - sp.head<3>()).norm() - sp[3];
    if (dc > 0 && dc * dc > best2) continue;
    const Triangle& tr = tris[t];
    const double d2 = (p - closest_point_on_triangle(p, pos_[tr[0]], pos_[tr[1]], pos_[tr[2]]).point).squaredNorm();
    if (d2 < best2 || (d2 == best2 && t < best_t)) {
      best2 = d2;
      best_t = t;
    }
  }
  return query_triangle(p, best_t);
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

Expected<NodeAdjacency> adjacency_from_edges(std::size_t vertex_count,
                                             std::span<const std::array<std::uint32_t, 2>> edges) {
  NodeAdjacency adj;
  adj.offset.assign(vertex_count + 1, 0);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const auto [a, b] = edges[e];
    if (a >= vertex_count || b >= vertex_count)
      return Status(ErrorCode::kInvalidArgument,
                    "adjacency_from_edges: edge " + std::to_string(e) + " uses a vertex out of range");
    if (a == b) continue;
    ++adj.offset[a + 1];
    ++adj.offset[b + 1];
  }
  std::partial_sum(adj.offset.begin(), adj.offset.end(), adj.offset.begin());
  adj.neighbor.resize(adj.offset.back());
  std::vector<std::uint32_t> fill(adj.offset.begin(), adj.offset.end() - 1);
  for (const auto& [a, b] : edges) {
    if (a == b) continue;
    adj.neighbor[fill[a]++] = b;
    adj.neighbor[fill[b]++] = a;
  }
  // Duplicate edges would weigh a neighbour twice in the umbrella.
  for (std::size_t v = 0; v < vertex_count; ++v) {
    auto* b = adj.neighbor.data() + adj.offset[v];
    auto* e = adj.neighbor.data() + adj.offset[v + 1];
    std::sort(b, e);
    if (std::adjacent_find(b, e) != e)
      return Status(ErrorCode::kInvalidArgument, "adjacency_from_edges: duplicate edge at vertex " + std::to_string(v));
  }
  return adj;
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
  par::for_each_n(qctx, n, [&](std::size_t v) {
    d[v] = body.query(g[v], enc.triangle.empty() ? kNoTriangle : enc.triangle[v]);
    queries[v] = 1;
    target[v] = std::clamp(static_cast<double>(enc.clearance[v]), prm.min_clearance, prm.max_clearance);
    if (!floor.empty()) target[v] = std::max(target[v], floor_at(floor, body, d[v]) + prm.layer_gap);
  });
  std::vector<std::uint8_t> moved(n, 0);
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
    std::vector<std::uint8_t> need_u(n, 0);
    for (std::uint32_t v : free_nodes) {
      need_u[v] = 1;
      for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) need_u[adj.neighbor[k]] = 1;
    }
    std::vector<std::uint32_t> u_nodes;
    for (std::size_t v = 0; v < n; ++v)
      if (need_u[v] && adj.offset[v + 1] > adj.offset[v]) u_nodes.push_back(static_cast<std::uint32_t>(v));
    auto inv_deg = [&](std::uint32_t v) { return 1.0 / (adj.offset[v + 1] - adj.offset[v]); };
    std::vector<double> inv_nu(free_nodes.size());
    for (std::size_t i = 0; i < free_nodes.size(); ++i) {
      const std::uint32_t v = free_nodes[i];
      double s = 0;
      for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) s += inv_deg(adj.neighbor[k]);
      inv_nu[i] = 1.0 / (1.0 + s * inv_deg(v));
    }
    // Moves are along the body normal n at the closest point x, so to first
    // order the signed distance is (p - x).n + d_x: sub-steps are tested on
    // that tangent plane (no body query per sub-step), and the end state is
    // verified exactly below.
    std::vector<Vec3d> u(n, Vec3d::Zero()), next(free_nodes.size()), start(free_nodes.size());
    std::vector<double> lin(free_nodes.size()), next_lin(free_nodes.size());
    for (std::size_t i = 0; i < free_nodes.size(); ++i) {
      start[i] = g[free_nodes[i]];
      lin[i] = d[free_nodes[i]].distance;
    }
    std::vector<std::uint32_t> refused(free_nodes.size(), 0);
    for (int it = 0; it < prm.fair_iterations; ++it) {
      if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "resolve_collisions cancelled");
      par::for_each_n(ctx, u_nodes.size(), [&](std::size_t i) {
        const std::uint32_t v = u_nodes[i];
        Vec3d s = Vec3d::Zero();
        for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) s += g[adj.neighbor[k]];
        u[v] = s * inv_deg(v) - g[v];
      });
      par::for_each_n(ctx, free_nodes.size(), [&](std::size_t i) {
        const std::uint32_t v = free_nodes[i];
        Vec3d s = Vec3d::Zero();
        for (std::uint32_t k = adj.offset[v]; k < adj.offset[v + 1]; ++k) s += u[adj.neighbor[k]];
        // Half a Jacobi step: U2 is not diagonally dominant, and on the open
        // boundary of a garment (degree 2-3) full Jacobi steps diverge.
        // Only the component along the body normal is kept: the pass smooths
        // the garment's offset from the body (the bump left by the push), and
        // tangential moves would slide open hems along the body (a free
        // boundary shrinks under U2 fairing) and add strain.
        const Vec3d& nrm = d[v].normal;
        const double along = nrm.dot(-0.5 * inv_nu[i] * (s * inv_deg(v) - u[v]));
        next[i] = g[v];
        next_lin[i] = lin[i];
        for (int k = 1; k <= prm.substeps; ++k) {
          const double dk = lin[i] + along * k / prm.substeps;
          if (dk < target[v] && dk < next_lin[i]) {  // entering, or going deeper into, the forbidden zone
            ++refused[i];
            break;
          }
          next[i] = g[v] + nrm * (along * k / prm.substeps);
          next_lin[i] = dk;
        }
      });
      par::for_each_n(ctx, free_nodes.size(), [&](std::size_t i) {
        g[free_nodes[i]] = next[i];
        lin[i] = next_lin[i];
      });
    }
    // Exact check of the faired vertices: one that ended deeper than both
    // its target and its pre-fairing distance (curvature beyond the tangent
    // plane) goes back to where the push left it.
    par::for_each_n(qctx, free_nodes.size(), [&](std::size_t i) {
      const std::uint32_t v = free_nodes[i];
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
