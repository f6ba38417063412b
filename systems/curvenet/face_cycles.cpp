#include <atelier/engine/math.h>
#include <atelier/systems/curvenet/face_cycles.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <set>
#include <tuple>

namespace atelier {

namespace {


[[nodiscard]] std::uint32_t origin(const CurveGraph& g, std::uint32_t d) {
  return g.segment_nodes[d >> 1][d & 1u];
}
[[nodiscard]] std::uint32_t target(const CurveGraph& g, std::uint32_t d) {
  return g.segment_nodes[d >> 1][(d & 1u) ^ 1u];
}

/// Direction leaving origin(d) along its segment: towards the point at a
/// fifth of the segment's length (robust to tiny first polyline steps).
Vec3d leaving(const CurveGraph& g, std::uint32_t d) {
  const auto p = g.polyline(d >> 1);
  const double h = 0.2 * g.length(d >> 1);
  const bool rev = (d & 1u) != 0;
  const std::size_t n = p.size();
  auto pt = [&](std::size_t i) { return rev ? p[n - 1 - i] : p[i]; };
  double acc = 0;
  for (std::size_t i = 1; i < n; ++i) {
    const double l = (pt(i) - pt(i - 1)).norm();
    if (acc + l >= h && l > 0) {
      const Vec3d q = pt(i - 1) + (h - acc) / l * (pt(i) - pt(i - 1));
      return (q - pt(0)).normalized();
    }
    acc += l;
  }
  return (pt(n - 1) - pt(0)).normalized();
}

/// Darts leaving each node (CSR).
struct Incidence {
  std::vector<std::uint32_t> offset, dart;
};
Incidence incidence(const CurveGraph& g) {
  Incidence inc;
  inc.offset.assign(g.node_count() + 1, 0);
  for (std::uint32_t d = 0; d < 2 * g.segment_count(); ++d) ++inc.offset[origin(g, d) + 1];
  for (std::size_t v = 0; v < g.node_count(); ++v) inc.offset[v + 1] += inc.offset[v];
  inc.dart.resize(2 * g.segment_count());
  std::vector<std::uint32_t> fill(inc.offset.begin(), inc.offset.end() - 1);
  for (std::uint32_t d = 0; d < 2 * g.segment_count(); ++d) inc.dart[fill[origin(g, d)]++] = d;
  return inc;
}

/// Newell vector area of a cycle through all its polyline points.
Vec3d vector_area(const CurveGraph& g, std::span<const std::uint32_t> cycle, Vec3d* centroid = nullptr,
                  double* mean_radius = nullptr) {
  std::vector<Vec3d> pts;
  for (std::uint32_t d : cycle) {
    const auto p = g.polyline(d >> 1);
    if (d & 1u)
      for (std::size_t i = p.size() - 1; i > 0; --i) pts.push_back(p[i]);
    else
      for (std::size_t i = 0; i + 1 < p.size(); ++i) pts.push_back(p[i]);
  }
  Vec3d c = Vec3d::Zero();
  for (const Vec3d& p : pts) c += p;
  c /= static_cast<double>(pts.size());
  Vec3d a = Vec3d::Zero();
  for (std::size_t i = 0; i < pts.size(); ++i) a += (pts[i] - c).cross(pts[(i + 1) % pts.size()] - c);
  if (centroid) *centroid = c;
  if (mean_radius) {
    double r = 0;
    for (const Vec3d& p : pts) r += (p - c).norm();
    *mean_radius = r / static_cast<double>(pts.size());
  }
  return 0.5 * a;
}

/// Mean cosine between a cycle's vector area and the normals at its nodes.
double orientation(const CurveGraph& g, std::span<const std::uint32_t> cycle, std::span<const Vec3d> normals) {
  const Vec3d a = vector_area(g, cycle);
  const double an = a.norm();
  if (!(an > 0)) return 0;
  double s = 0;
  for (std::uint32_t d : cycle) s += normals[origin(g, d)].dot(a) / an;
  return s / static_cast<double>(cycle.size());
}

void count_usage(const CurveGraph& g, FaceCycles& fc) {
  std::vector<std::uint32_t> use(g.segment_count(), 0);
  for (std::uint32_t d : fc.darts) ++use[d >> 1];
  fc.faces_by_size.clear();
  for (std::size_t f = 0; f < fc.face_count(); ++f) ++fc.faces_by_size[fc.face(f).size()];
  fc.segments_in_two_faces = fc.segments_in_one_face = fc.segments_in_no_face = 0;
  for (std::uint32_t u : use) {
    if (u >= 2)
      ++fc.segments_in_two_faces;
    else if (u == 1)
      ++fc.segments_in_one_face;
    else
      ++fc.segments_in_no_face;
  }
  fc.nodes = g.node_count();
  fc.segments = g.segment_count();
}

/// Faces by the rotation system; cycles with negative orientation (the
/// outer boundary) are set aside.
FaceCycles angular_faces(const CurveGraph& g, std::span<const Vec3d> normals) {
  const Incidence inc = incidence(g);
  const std::size_t nd = 2 * g.segment_count();
  std::vector<std::uint32_t> rot(nd), pos(nd);  // darts sorted counter-clockwise about each node's normal
  for (std::uint32_t v = 0; v < g.node_count(); ++v) {
    const Vec3d& n = normals[v];
    Vec3d u = n.unitOrthogonal();
    const Vec3d w = n.cross(u);
    std::vector<std::pair<double, std::uint32_t>> a;
    for (std::uint32_t k = inc.offset[v]; k < inc.offset[v + 1]; ++k) {
      const std::uint32_t d = inc.dart[k];
      const Vec3d t = leaving(g, d);
      a.emplace_back(std::atan2(t.dot(w), t.dot(u)), d);
    }
    std::sort(a.begin(), a.end());
    for (std::uint32_t k = inc.offset[v]; k < inc.offset[v + 1]; ++k) {
      rot[k] = a[k - inc.offset[v]].second;
      pos[rot[k]] = k;
    }
  }
  // next(d): at target(d), the dart clockwise after the reverse of d (the
  // face stays on the left).
  auto next = [&](std::uint32_t d) {
    const std::uint32_t r = d ^ 1u;
    const std::uint32_t v = origin(g, r);
    const std::uint32_t k = pos[r];
    return rot[k == inc.offset[v] ? inc.offset[v + 1] - 1 : k - 1];
  };
  FaceCycles fc;
  std::vector<std::uint8_t> seen(nd, 0);
  std::vector<std::uint32_t> cyc;
  for (std::uint32_t d0 = 0; d0 < nd; ++d0) {
    if (seen[d0]) continue;
    cyc.clear();
    for (std::uint32_t d = d0; !seen[d]; d = next(d)) {
      seen[d] = 1;
      cyc.push_back(d);
    }
    // Set aside: the outer boundary (clockwise about the normals) and walks
    // that enclose nothing (zero vector area, e.g. along a lone segment).
    const bool set_aside = orientation(g, cyc, normals) <= 0;
    auto& off = set_aside ? fc.outer_offsets : fc.offsets;
    auto& dst = set_aside ? fc.outer_darts : fc.darts;
    dst.insert(dst.end(), cyc.begin(), cyc.end());
    off.push_back(static_cast<std::uint32_t>(dst.size()));
  }
  return fc;
}

/// The paper's search (5.1-5.3), deterministic.
FaceCycles paper_faces(const CurveGraph& g, std::span<const Vec3d> normals, const FaceCycleOptions& opt,
                       const ExecContext& ctx) {
  const Incidence inc = incidence(g);
  const std::size_t ns = g.segment_count();
  std::vector<std::uint8_t> uses(ns, 0), exhausted(ns, 0);
  std::set<std::vector<std::uint32_t>> validated;
  FaceCycles fc;

  // Components of the network without the given segments, ignoring
  // isolated nodes (eq. 2's m).
  std::vector<std::uint32_t> parent(g.node_count());
  std::vector<std::uint8_t> skip(ns, 0), touched(g.node_count(), 0);
  auto components_without = [&](const std::vector<std::uint32_t>& cycle) {
    std::iota(parent.begin(), parent.end(), 0u);
    std::fill(touched.begin(), touched.end(), 0);
    for (std::uint32_t s : cycle) skip[s] = 1;
    auto find = [&](std::uint32_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    for (std::uint32_t s = 0; s < ns; ++s) {
      if (skip[s]) continue;
      const std::uint32_t a = find(g.segment_nodes[s][0]), b = find(g.segment_nodes[s][1]);
      touched[g.segment_nodes[s][0]] = touched[g.segment_nodes[s][1]] = 1;
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
    for (std::uint32_t s : cycle) skip[s] = 0;
    std::size_t m = 0;
    for (std::uint32_t v = 0; v < g.node_count(); ++v) m += touched[v] && find(v) == v;
    return m;
  };
  auto bbox_volume = [&](const std::vector<std::uint32_t>& darts) {
    Box3d b;
    for (std::uint32_t d : darts)
      for (const Vec3d& p : g.polyline(d >> 1)) b.extend(p);
    const Vec3d e = b.hi - b.lo;
    return e.x() * e.y() * e.z();
  };

  struct Candidate {
    std::vector<std::uint32_t> darts;     // in order, starting with the free edge
    std::vector<std::uint32_t> segments;  // sorted
  };
  std::vector<std::uint8_t> on_path(g.node_count(), 0);
  std::vector<std::uint32_t> path;
  for (std::size_t iter = 0; !ctx.cancelled(); ++iter) {
    std::uint32_t e = kNone;
    for (std::uint32_t s = 0; s < ns && e == kNone; ++s)
      if (uses[s] < 2 && !exhausted[s]) e = s;
    if (e == kNone) break;
    const std::uint32_t a = g.segment_nodes[e][0], b = g.segment_nodes[e][1];
    std::vector<Candidate> cands;
    auto emit = [&](const std::vector<std::uint32_t>& darts) {
      Candidate c;
      c.darts = darts;
      for (std::uint32_t d : darts) c.segments.push_back(d >> 1);
      std::sort(c.segments.begin(), c.segments.end());
      if (std::adjacent_find(c.segments.begin(), c.segments.end()) != c.segments.end()) return;
      if (!validated.count(c.segments)) cands.push_back(std::move(c));
    };
    if (a == b) {
      emit({2 * e});
    } else {
      // Depth-first over free segments from b back to a.
      path.assign(1, 2 * e);
      on_path[a] = on_path[b] = 1;
      auto dfs = [&](auto&& self, std::uint32_t v) -> void {
        if (path.size() >= opt.max_cycle_length) return;
        for (std::uint32_t k = inc.offset[v]; k < inc.offset[v + 1]; ++k) {
          const std::uint32_t d = inc.dart[k];
          const std::uint32_t s = d >> 1;
          if (s == e || uses[s] >= 2) continue;
          const std::uint32_t w = target(g, d);
          if (w == a) {
            path.push_back(d);
            emit(path);
            path.pop_back();
            continue;
          }
          if (on_path[w]) continue;
          on_path[w] = 1;
          path.push_back(d);
          self(self, w);
          path.pop_back();
          on_path[w] = 0;
        }
      };
      dfs(dfs, b);
      on_path[a] = on_path[b] = 0;
    }
    if (cands.empty()) {
      exhausted[e] = 1;
      continue;
    }
    std::sort(cands.begin(), cands.end(), [](const Candidate& x, const Candidate& y) {
      return std::make_tuple(x.segments.size(), x.segments) < std::make_tuple(y.segments.size(), y.segments);
    });
    // k = n m >= n: only candidates with n below the best k so far can win.
    std::size_t best = 0;
    std::size_t best_k = std::numeric_limits<std::size_t>::max();
    double best_vol = 0;
    for (std::size_t i = 0; i < cands.size(); ++i) {
      const std::size_t n = cands[i].segments.size();
      if (n > best_k) break;
      const std::size_t k = n + n * (components_without(cands[i].segments) - 1);
      const double vol = bbox_volume(cands[i].darts);
      if (k < best_k || (k == best_k && vol < best_vol)) {
        best = i;
        best_k = k;
        best_vol = vol;
      }
    }
    Candidate& c = cands[best];
    validated.insert(c.segments);
    for (std::uint32_t s : c.segments) ++uses[s];
    // Orient the cycle counter-clockwise about the normals.
    if (orientation(g, c.darts, normals) < 0) {
      std::reverse(c.darts.begin(), c.darts.end());
      for (std::uint32_t& d : c.darts) d ^= 1u;
    }
    fc.darts.insert(fc.darts.end(), c.darts.begin(), c.darts.end());
    fc.offsets.push_back(static_cast<std::uint32_t>(fc.darts.size()));
    if (iter > 4 * ns + 16) break;  // cannot happen: each round validates a new cycle or exhausts an edge
  }
  fc.stop_rule_met = std::all_of(uses.begin(), uses.end(), [](std::uint8_t u) { return u == 2; });
  return fc;
}

}  // namespace

std::vector<Vec3d> curve_node_normals(const CurveGraph& g) {
  const Incidence inc = incidence(g);
  const std::size_t nv = g.node_count();
  std::vector<Vec3d> n(nv, Vec3d::Zero());
  std::vector<std::uint8_t> known(nv, 0);
  for (std::uint32_t v = 0; v < nv; ++v) {
    Mat3d cov = Mat3d::Zero();
    std::vector<Vec3d> ts;
    for (std::uint32_t k = inc.offset[v]; k < inc.offset[v + 1]; ++k) {
      const Vec3d t = leaving(g, inc.dart[k]);
      ts.push_back(t);
      cov += t * t.transpose();
    }
    if (ts.size() < 2) continue;
    Eigen::SelfAdjointEigenSolver<Mat3d> es(cov);
    // A plane needs two independent tangents: the middle eigenvalue.
    if (es.eigenvalues()(1) < 1e-6 * es.eigenvalues()(2)) continue;
    n[v] = es.eigenvectors().col(0).normalized();
    // Tangents far from any plane (a cube's corner) all leave on the inside
    // of the surface: the normal is the opposite of their mean.
    Vec3d mean = Vec3d::Zero();
    for (const Vec3d& t : ts) mean += t;
    mean /= static_cast<double>(ts.size());
    if (es.eigenvalues()(0) > 0.25 * es.eigenvalues()(1) && mean.norm() > 0.25) n[v] = -mean.normalized();
    known[v] = 1;
  }
  // Consistent signs (and missing normals) by breadth-first search along
  // segments from the lowest-numbered known node of each component. The
  // test compares the directions across the segment in the two tangent
  // planes (n x t at one end, n x the continued t at the other), which stay
  // close along a curve on a smooth surface even where the normals turn by
  // 90 degrees or more between two nodes (a coarse torus grid).
  std::vector<std::uint8_t> done(nv, 0);
  for (std::uint32_t s0 = 0; s0 < nv; ++s0) {
    if (done[s0] || !known[s0]) continue;
    std::vector<std::uint32_t> queue{s0};
    done[s0] = 1;
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const std::uint32_t v = queue[q];
      for (std::uint32_t k = inc.offset[v]; k < inc.offset[v + 1]; ++k) {
        const std::uint32_t d = inc.dart[k];
        const std::uint32_t w = target(g, d);
        if (done[w]) continue;
        if (!known[w]) {
          n[w] = n[v];
        } else {
          const Vec3d bv = n[v].cross(leaving(g, d)), bw = n[w].cross(-leaving(g, d ^ 1u));
          const double across = bv.dot(bw);
          const bool flip = std::abs(across) > 1e-3 * bv.norm() * bw.norm() ? across < 0 : n[w].dot(n[v]) < 0;
          if (flip) n[w] = -n[w];
        }
        done[w] = 1;
        queue.push_back(w);
      }
    }
  }
  Vec3d c = Vec3d::Zero();
  for (const Vec3d& p : g.nodes) c += p;
  c /= static_cast<double>(std::max<std::size_t>(nv, 1));
  double s = 0;
  for (std::uint32_t v = 0; v < nv; ++v) s += n[v].dot(g.nodes[v] - c);
  if (s < 0)
    for (Vec3d& x : n) x = -x;
  for (std::uint32_t v = 0; v < nv; ++v)
    if (n[v].isZero(0.0)) n[v] = Vec3d::UnitZ();  // a component without any plane: any normal orders two darts
  return n;
}

Expected<FaceCycles> find_face_cycles(const CurveGraph& g, const FaceCycleOptions& opt, const ExecContext& ctx) {
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "find_face_cycles: cancelled");
  if (g.segment_count() == 0) return Status(ErrorCode::kTopology, "the curve network has no segment");
  std::vector<Vec3d> own;
  std::span<const Vec3d> normals = opt.node_normals;
  if (normals.empty()) {
    own = curve_node_normals(g);
    normals = own;
  }
  if (normals.size() != g.node_count())
    return Status(ErrorCode::kInvalidArgument, "find_face_cycles: " + std::to_string(normals.size()) + " normals for " +
                                                   std::to_string(g.node_count()) + " nodes");
  for (std::size_t v = 0; v < normals.size(); ++v)
    if (!normals[v].allFinite() || !(normals[v].norm() > 0))
      return Status(ErrorCode::kInvalidArgument,
                    "find_face_cycles: the normal of node " + std::to_string(v) + " is zero or not finite");
  FaceCycles fc =
      opt.method == FaceCycleMethod::kAngular ? angular_faces(g, normals) : paper_faces(g, normals, opt, ctx);
  if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "find_face_cycles: cancelled");
  count_usage(g, fc);
  if (fc.face_count() == 0) return Status(ErrorCode::kTopology, "the curve network has no face cycle");
  return fc;
}

}  // namespace atelier
