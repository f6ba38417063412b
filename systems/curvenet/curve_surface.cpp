#include <atelier/systems/curvenet/curve_surface.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <atelier/engine/parallel.h>
#include <atelier/storage/builder.h>
#include <atelier/systems/spatial/body_bvh.h>

namespace atelier {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::vector<Triangle> fan(const PolygonSoupView& s) {
  std::vector<Triangle> t;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const std::uint32_t b = s.face_offsets[f], e = s.face_offsets[f + 1];
    for (std::uint32_t k = b + 1; k + 1 < e; ++k) t.push_back({s.face_nodes[b], s.face_nodes[k], s.face_nodes[k + 1]});
  }
  return t;
}

/// Boundary loops of a polygon soup: edges used by one face, chained.
std::vector<std::vector<std::uint32_t>> boundary_loops(const PolygonSoupView& s) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> use;
  for (std::size_t f = 0; f < s.face_count(); ++f) {
    const std::uint32_t b = s.face_offsets[f], e = s.face_offsets[f + 1];
    for (std::uint32_t k = b; k < e; ++k) {
      const std::uint32_t u = s.face_nodes[k], v = s.face_nodes[k + 1 == e ? b : k + 1];
      ++use[{u, v}];
    }
  }
  std::map<std::uint32_t, std::uint32_t> next;  // boundary halfedge u -> v (its twin is missing)
  for (const auto& [uv, n] : use)
    if (!use.count({uv.second, uv.first})) next[uv.first] = uv.second;
  std::vector<std::vector<std::uint32_t>> loops;
  std::map<std::uint32_t, bool> done;
  for (const auto& [u0, v0] : next) {
    if (done[u0]) continue;
    std::vector<std::uint32_t> loop;
    for (std::uint32_t u = u0; !done[u];) {
      done[u] = true;
      loop.push_back(u);
      const auto it = next.find(u);
      if (it == next.end()) break;
      u = it->second;
    }
    if (loop.size() >= 3) loops.push_back(std::move(loop));
  }
  return loops;
}

/// Closest point on the input curves to p (brute force over segments).
Vec3d closest_on_curves(const PolylineSet& c, const Vec3d& p, double* dist) {
  double best = std::numeric_limits<double>::infinity();
  Vec3d q = p;
  for (std::size_t k = 0; k < c.size(); ++k) {
    const auto pts = c.curve(k);
    for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
      const Vec3d ab = pts[i + 1] - pts[i];
      const double l2 = ab.squaredNorm();
      const double t = l2 > 0 ? std::clamp((p - pts[i]).dot(ab) / l2, 0.0, 1.0) : 0.0;
      const Vec3d x = pts[i] + t * ab;
      const double d = (x - p).norm();
      if (d < best) {
        best = d;
        q = x;
      }
    }
  }
  *dist = best;
  return q;
}

/// A uniform grid of triangles for closest-point queries near the surface
/// (the curve samples lie within a fraction of a face of it): much cheaper
/// to build than a BVH for a one-off batch of nearby queries.
class TriangleGrid {
 public:
  TriangleGrid(std::span<const Vec3d> p, std::span<const Triangle> t) : p_(p), t_(t) {
    Box3d box;
    for (const Triangle& x : t)
      for (std::uint32_t v : x) box.extend(p[v]);
    lo_ = box.lo;
    const Vec3d ext = (box.hi - box.lo).cwiseMax(Vec3d::Constant(1e-12));
    // About one triangle per cell on a surface: cells of the mean triangle size.
    double mean = 0;
    for (const Triangle& x : t) mean += (p[x[1]] - p[x[0]]).norm() + (p[x[2]] - p[x[1]]).norm();
    mean /= std::max<double>(1.0, 2.0 * static_cast<double>(t.size()));
    cell_ = std::max({mean * 2.0, ext.maxCoeff() / 1024.0, 1e-12});
    // At most about 4 cells per triangle (a thin surface in a large box).
    for (;;) {
      for (int k = 0; k < 3; ++k)
        dims_[static_cast<std::size_t>(k)] = std::max(1, static_cast<int>(std::ceil(ext[k] / cell_)));
      if (static_cast<double>(dims_[0]) * dims_[1] * dims_[2] <= 4.0 * static_cast<double>(t.size()) + 64.0) break;
      cell_ *= 1.25;
    }
    const std::size_t n = static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2];
    offsets_.assign(n + 1, 0);
    auto cells_of = [&](const Triangle& x, auto&& f) {
      Box3d b;
      for (std::uint32_t v : x) b.extend(p[v]);
      const auto lo = index(b.lo), hi = index(b.hi);
      for (int k = lo[2]; k <= hi[2]; ++k)
        for (int j = lo[1]; j <= hi[1]; ++j)
          for (int i = lo[0]; i <= hi[0]; ++i) f(flat(i, j, k));
    };
    for (const Triangle& x : t) cells_of(x, [&](std::size_t c) { ++offsets_[c + 1]; });
    for (std::size_t c = 0; c < n; ++c) offsets_[c + 1] += offsets_[c];
    items_.resize(offsets_[n]);
    std::vector<std::uint32_t> fill(offsets_.begin(), offsets_.end() - 1);
    for (std::uint32_t i = 0; i < t.size(); ++i) cells_of(t[i], [&](std::size_t c) { items_[fill[c]++] = i; });
  }
  /// Distance from q to the nearest triangle (searched in growing boxes).
  [[nodiscard]] double distance(const Vec3d& q) const {
    double best = std::numeric_limits<double>::infinity();
    for (double r = cell_;; r *= 2) {
      const auto lo = index(q - Vec3d::Constant(r)), hi = index(q + Vec3d::Constant(r));
      for (int k = lo[2]; k <= hi[2]; ++k)
        for (int j = lo[1]; j <= hi[1]; ++j)
          for (int i = lo[0]; i <= hi[0]; ++i) {
            const std::size_t c = flat(i, j, k);
            for (std::uint32_t e = offsets_[c]; e < offsets_[c + 1]; ++e) {
              const Triangle& x = t_[items_[e]];
              best = std::min(best, (closest_point_on_triangle(q, p_[x[0]], p_[x[1]], p_[x[2]]).point - q).norm());
            }
          }
      const bool all =
          lo == std::array<int, 3>{0, 0, 0} && hi == std::array<int, 3>{dims_[0] - 1, dims_[1] - 1, dims_[2] - 1};
      if (best <= r || all) return best;
    }
  }

 private:
  [[nodiscard]] std::array<int, 3> index(const Vec3d& x) const {
    std::array<int, 3> i{};
    for (int k = 0; k < 3; ++k) {
      const auto d = static_cast<double>(dims_[static_cast<std::size_t>(k)] - 1);
      // Clamped as a double first: a far point must not overflow the cast.
      i[static_cast<std::size_t>(k)] = static_cast<int>(std::clamp(std::floor((x[k] - lo_[k]) / cell_), 0.0, d));
    }
    return i;
  }
  [[nodiscard]] std::size_t flat(int i, int j, int k) const {
    return (static_cast<std::size_t>(k) * static_cast<std::size_t>(dims_[1]) + static_cast<std::size_t>(j)) *
               static_cast<std::size_t>(dims_[0]) +
           static_cast<std::size_t>(i);
  }
  std::span<const Vec3d> p_;
  std::span<const Triangle> t_;
  Vec3d lo_;
  double cell_ = 1;
  std::array<int, 3> dims_{1, 1, 1};
  std::vector<std::uint32_t> offsets_, items_;
};

CurveDistance summarize(const std::vector<double>& dist, double diag) {
  CurveDistance d;
  d.samples = dist.size();
  double sum = 0, sq = 0;
  for (const double x : dist) {
    d.max = std::max(d.max, x);
    sum += x;
    sq += x * x;
  }
  if (!dist.empty()) {
    d.mean = sum / static_cast<double>(dist.size());
    d.rms = std::sqrt(sq / static_cast<double>(dist.size()));
  }
  d.relative_max = diag > 0 ? d.max / diag : 0;
  return d;
}

}  // namespace

Expected<CurveSurface> surface_from_curves(const PolylineSet& curves, const PolygonSoupView& traced,
                                           const CurveSurfaceOptions& opt, const ExecContext& ctx) {
  if (opt.levels < 0 || opt.levels > 6)
    return Status(ErrorCode::kInvalidArgument, "surface: levels must be in [0, 6], got " + std::to_string(opt.levels));
  CurveSurface out;
  CurveSurfaceReport& rep = out.report;
  auto t0 = Clock::now();

  // ---- the traced mesh: BVH, boundary curves.
  const bool has_traced = traced.face_count() > 0;
  rep.has_traced = has_traced;
  BodyBvh traced_bvh;
  std::vector<Triangle> traced_tris;
  PolylineSet all = curves;
  if (has_traced) {
    if (Status s = PolygonSoup{std::vector<Vec3d>(traced.positions.begin(), traced.positions.end()),
                               std::vector<std::uint32_t>(traced.face_offsets.begin(), traced.face_offsets.end()),
                               std::vector<std::uint32_t>(traced.face_nodes.begin(), traced.face_nodes.end())}
                       .check();
        !s)
      return Status(ErrorCode::kInvalidArgument, "traced mesh: " + s.message());
    traced_tris = fan(traced);
    if (Status s = traced_bvh.build(traced.positions, traced_tris, {}, ctx); !s)
      return Status(ErrorCode::kInvalidArgument, "traced mesh: " + s.message());
    // The network's size, for the cover distance.
    Box3d box;
    for (const Vec3d& p : curves.points) box.extend(p);
    const double diag = box.empty() ? 0.0 : (box.hi - box.lo).norm();
    const double cover = opt.boundary_cover * diag;
    // Free curve ends: no other curve (nor another part of their own) near.
    const double tol = opt.treatment.intersection_tolerance * diag;
    std::vector<Vec3d> free_ends;
    for (std::size_t c = 0; c < curves.size(); ++c) {
      const auto pts = curves.curve(c);
      for (const Vec3d& e : {pts.front(), pts.back()}) {
        bool joined = (pts.front() - pts.back()).norm() <= tol;  // a closed curve
        for (std::size_t k = 0; k < curves.size() && !joined; ++k) {
          if (k == c) continue;
          const auto q = curves.curve(k);
          for (std::size_t i = 0; i + 1 < q.size() && !joined; ++i) {
            const Vec3d ab = q[i + 1] - q[i];
            const double l2 = ab.squaredNorm();
            const double t = l2 > 0 ? std::clamp((e - q[i]).dot(ab) / l2, 0.0, 1.0) : 0.0;
            joined = (q[i] + t * ab - e).norm() <= tol;
          }
        }
        if (!joined) free_ends.push_back(e);
      }
    }
    std::size_t added = 0;
    for (const auto& loop : boundary_loops(traced)) {
      const std::size_t n = loop.size();
      // A loop closes the network only where free curve ends reach it.
      bool reached = false;
      for (const Vec3d& e : free_ends)
        for (std::size_t i = 0; i < n && !reached; ++i) {
          const Vec3d& a = traced.positions[loop[i]];
          const Vec3d ab = traced.positions[loop[(i + 1) % n]] - a;
          const double l2 = ab.squaredNorm();
          const double t = l2 > 0 ? std::clamp((e - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
          reached = (a + t * ab - e).norm() <= std::max(tol, 1e-9 * diag);
        }
      if (!reached) continue;
      std::vector<std::uint8_t> near(n, 0);
      std::vector<Vec3d> snap(n);
      for (std::size_t i = 0; i < n; ++i) {
        double d = 0;
        snap[i] = closest_on_curves(curves, traced.positions[loop[i]], &d);
        near[i] = d <= cover;
      }
      std::vector<std::uint8_t> covered(n, 0);  // edge i -> i+1 runs along a curve
      for (std::size_t i = 0; i < n; ++i) covered[i] = near[i] && near[(i + 1) % n];
      const auto first_free = std::find(covered.begin(), covered.end(), 0);
      if (first_free == covered.end()) continue;  // the whole loop is drawn already
      // Chains of uncovered edges, starting after a covered edge (or anywhere
      // when none is covered: one closed chain).
      const bool none_covered = std::find(covered.begin(), covered.end(), 1) == covered.end();
      std::size_t start = 0;
      if (!none_covered)
        while (!(covered[(start + n - 1) % n] && !covered[start])) ++start;
      std::vector<Vec3d> chain;
      auto flush = [&] {
        if (chain.size() >= 2) {
          all.add(-1 - static_cast<std::int64_t>(added), chain);
          ++added;
        }
        chain.clear();
      };
      for (std::size_t k = 0; k < n; ++k) {
        const std::size_t i = (start + k) % n;
        if (covered[i]) {
          flush();
          continue;
        }
        if (chain.empty()) chain.push_back(near[i] ? snap[i] : traced.positions[loop[i]]);
        const std::size_t j = (i + 1) % n;
        chain.push_back(near[j] ? snap[j] : traced.positions[loop[j]]);
      }
      flush();
    }
    rep.boundary_curves = added;
    if (added > 0)
      rep.warnings.push_back("closed the network with " + std::to_string(added) +
                             " piece(s) of the traced mesh's boundary (curve ids -1, -2, ...)");
  }
  rep.seconds["traced mesh"] = seconds_since(t0);
  ctx.report("surface: traced mesh", 1, 7);

  // ---- 1. curve treatment.
  t0 = Clock::now();
  auto treated = treat_curves(all, opt.treatment, ctx);
  if (!treated) return treated.status();
  out.graph = std::move(treated->graph);
  rep.treatment = treated->report;
  rep.warnings.insert(rep.warnings.end(), rep.treatment.warnings.begin(), rep.treatment.warnings.end());
  rep.seconds["curve treatment"] = seconds_since(t0);
  ctx.report("surface: curve treatment", 2, 7);

  // ---- 2. face cycles.
  t0 = Clock::now();
  std::vector<Vec3d> normals;
  FaceCycleOptions fo;
  fo.method = opt.cycles;
  fo.max_cycle_length = opt.max_cycle_length;
  if (has_traced) {
    // The tangent plane of the curves themselves (exact at the node), turned
    // to agree with the traced mesh's normal there: a coarse mesh's normal
    // can be far from the curves' plane and scramble their order, but its
    // side is reliable. The closest triangle's own normal is used (the
    // pseudo-normals at an open mesh's boundary are not).
    normals = curve_node_normals(out.graph);
    for (std::size_t v = 0; v < normals.size(); ++v) {
      const ClosestHit h = traced_bvh.closest_point(out.graph.nodes[v]);
      const Triangle& t = traced_tris[h.triangle];
      const Vec3d n =
          (traced.positions[t[1]] - traced.positions[t[0]]).cross(traced.positions[t[2]] - traced.positions[t[0]]);
      if (n.dot(normals[v]) < 0) normals[v] = -normals[v];
    }
    fo.node_normals = normals;
  }
  auto cycles = find_face_cycles(out.graph, fo, ctx);
  if (!cycles) return cycles.status();
  out.cycles = std::move(cycles).value();
  rep.nodes = out.graph.node_count();
  rep.segments = out.graph.segment_count();
  rep.faces = out.cycles.face_count();
  rep.outer_cycles = out.cycles.outer_count();
  rep.euler = out.cycles.euler();
  rep.faces_by_size = out.cycles.faces_by_size;
  rep.stop_rule_met = out.cycles.stop_rule_met;
  if (!out.cycles.stop_rule_met)
    rep.warnings.push_back("the paper's cycle search stopped with segments in fewer than two cycles");
  rep.seconds["face cycles"] = seconds_since(t0);
  ctx.report("surface: face cycles", 3, 7);

  // ---- 3-4. control mesh (density, parity, quadrangulation, fairing).
  t0 = Clock::now();
  auto control = build_control_mesh(out.graph, out.cycles, opt.control, ctx);
  if (!control) return control.status();
  out.control = std::move(control).value();
  const ControlMesh& cm = out.control;
  rep.control_vertices = cm.mesh.positions.size();
  rep.network_vertices = cm.network_vertices;
  rep.control_quads = cm.mesh.face_count();
  rep.knots_inserted = cm.knots_inserted;
  rep.odd_faces = cm.odd_faces;
  rep.shortest_segment = cm.shortest_segment;
  rep.density_C = cm.C;
  rep.raised_segments = cm.raised_segments;
  rep.max_fit_error = cm.max_fit_error;
  rep.fairing_energy_before = cm.fairing_energy_before;
  rep.fairing_energy_after = cm.fairing_energy_after;
  rep.inverted_quads = cm.inverted_quads;
  if (cm.inverted_quads > 0)
    rep.warnings.push_back(std::to_string(cm.inverted_quads) +
                           " control quad(s) fold against their face cycle (strongly concave cycles)");
  rep.seconds["control mesh"] = seconds_since(t0);
  ctx.report("surface: control mesh", 4, 7);

  // ---- 5. Catmull-Clark with creases.
  t0 = Clock::now();
  CatmullClarkOptions co;
  co.levels = opt.levels;
  auto refiner = CatmullClarkRefiner::create(cm.mesh, cm.mesh.positions.size(), cm.creases, cm.corners, co, ctx);
  if (!refiner) return refiner.status();
  if (Status s = refiner->refine(cm.mesh.positions, out.refined.mesh.positions, ctx); !s) return s;
  const CornerMesh& last = refiner->level(refiner->levels());
  out.refined.mesh.face_offsets = last.face_offsets;
  out.refined.mesh.face_nodes = last.face_verts;
  out.refined.creases = refiner->last_level_creases();
  const auto corner_flags = refiner->corner_vertices(refiner->levels());
  out.refined.corners.assign(corner_flags.begin(), corner_flags.end());
  {
    std::size_t edges = refiner->level(0).edge_count();
    for (int l = 0; l <= refiner->levels(); ++l) {
      const CornerMesh& m = refiner->level(l);
      rep.levels.push_back({m.vertex_count, edges, m.face_count()});
      edges = 2 * edges + m.corner_count();
    }
  }
  for (const Vec3d& p : out.refined.mesh.positions)
    if (!p.allFinite()) return Status(ErrorCode::kDegenerate, "surface: the subdivided surface has non-finite points");
  rep.seconds["subdivision"] = seconds_since(t0);
  ctx.report("surface: subdivision", 5, 7);

  // ---- the Model surface.
  t0 = Clock::now();
  if (opt.build_model) {
    auto s = add_polygon_surface(out.model, "curve_surface", out.refined.mesh, ctx);
    if (!s)
      return Status(ErrorCode::kInternal,
                    "surface: the subdivided mesh was refused as a surface: " + s.status().message());
  }
  rep.seconds["model"] = seconds_since(t0);
  ctx.report("surface: model", 6, 7);

  // ---- distances.
  t0 = Clock::now();
  {
    const auto tris = fan(out.refined.mesh);
    const TriangleGrid grid(out.refined.mesh.positions, tris);
    std::vector<double> d(out.graph.points.size());
    par::for_each_n(ctx, d.size(), [&](std::size_t i) { d[i] = grid.distance(out.graph.points[i]); });
    rep.to_curves = summarize(d, rep.treatment.diagonal);
    if (has_traced) {
      std::vector<ClosestHit> th(out.refined.mesh.positions.size());
      if (Status s = traced_bvh.closest_points(out.refined.mesh.positions, th, ctx); !s) return s;
      std::vector<double> dt(th.size());
      for (std::size_t i = 0; i < th.size(); ++i) dt[i] = th[i].distance;
      rep.to_traced = summarize(dt, rep.treatment.diagonal);
    }
  }
  rep.seconds["distances"] = seconds_since(t0);
  ctx.report("surface: distances", 7, 7);
  return out;
}

}  // namespace atelier
