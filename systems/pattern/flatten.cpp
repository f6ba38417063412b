// The Model side of the flattening: a surface's checks and local topology,
// the rest state, distortion, placement, Flattener and flatten_surfaces
// (flatten.h). The numerics are in flatten_solver.cpp.
// Why this file is long: the piece checks (manifold, disk, components) and
// the Flattener / ModelFlattener plumbing share the local topology and
// read the same Model tables; splitting them would only export more detail.
#include <atelier/engine/parallel.h>
#include <atelier/systems/pattern/flatten.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <numeric>

#include "flatten_detail.h"

namespace atelier {

using namespace pattern_detail;

namespace {

/// Phase 2 from a warm start is given up after this many step-limited
/// iterations in a row from its start (SolverParams::stall_window).
constexpr int kWarmStallWindow = 24;
/// A warm start whose seams end further than this (relative) from their
/// lengths is given up too; cold flattenings end within 1.2e-4.
constexpr double kWarmSeamTolerance = 1e-3;

[[nodiscard]] std::string surface_label(const Model& m, SurfaceIdx s) {
  return "surface '" + m.surfaces.name[s.value] + "' (" + std::to_string(s.value) + ")";
}

[[nodiscard]] Status topo_error(ErrorCode c, const Model& m, SurfaceIdx s, const std::string& what) {
  return {c, surface_label(m, s) + " " + what};
}

}  // namespace

Expected<PieceTopology> pattern_detail::build_topology(const Model& m, SurfaceIdx s, bool allow_holes, bool check) {
  if (!m.alive(s)) return Status(ErrorCode::kStaleHandle, "surface " + std::to_string(s.value) + " is not alive");
  PieceTopology t;
  std::vector<FaceIdx> faces;
  for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f)
    if (m.alive(FaceIdx{f}) && m.faces.surface[f] == s) faces.push_back(FaceIdx{f});
  if (faces.empty()) return topo_error(ErrorCode::kTopology, m, s, "has no faces: nothing to flatten");
  const std::size_t cap = m.nodes.slots.capacity();
  std::vector<std::uint32_t> local(cap, kNone);
  std::vector<HalfedgeIdx> cyc;
  for (FaceIdx f : faces) {
    m.face_halfedges(f, cyc);
    for (HalfedgeIdx h : cyc) local[m.tail(h).value] = 0;
  }
  for (std::uint32_t v = 0; v < cap; ++v)
    if (local[v] == 0) {
      local[v] = static_cast<std::uint32_t>(t.node.size());
      t.node.push_back(NodeIdx{v});
    } else {
      local[v] = kNone;
    }
  // Fan each face from its first corner; sides between consecutive corners
  // are model edges, the others fan diagonals.
  struct Side {
    std::uint64_t key;
    std::uint32_t slot;  // 3 * triangle + side
    bool edge;
  };
  std::vector<Side> sides;
  for (FaceIdx f : faces) {
    m.face_halfedges(f, cyc);
    const std::size_t k = cyc.size();
    for (std::size_t j = 1; j + 1 < k; ++j) {
      const std::array<std::uint32_t, 3> c{local[m.tail(cyc[0]).value], local[m.tail(cyc[j]).value],
                                           local[m.tail(cyc[j + 1]).value]};
      const auto ti = static_cast<std::uint32_t>(t.tri.size());
      t.tri.push_back(c);
      t.tri_face.push_back(f);
      const bool edge[3] = {j == 1, true, j + 2 == k};
      for (int e = 0; e < 3; ++e) {
        const std::uint32_t a = c[e], b = c[(e + 1) % 3];
        sides.push_back({(std::uint64_t{std::min(a, b)} << 32) | std::max(a, b), 3 * ti + e, edge[e]});
      }
    }
  }
  std::sort(sides.begin(), sides.end(),
            [](const Side& x, const Side& y) { return x.key != y.key ? x.key < y.key : x.slot < y.slot; });
  t.tri_adj.assign(t.tri.size(), {kNone, kNone, kNone});
  t.tri_spring.resize(t.tri.size());
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i;
    bool edge = false;
    for (; j < sides.size() && sides[j].key == sides[i].key; ++j) edge = edge || sides[j].edge;
    const auto sp = static_cast<std::uint32_t>(t.spring.size());
    t.spring.push_back({static_cast<std::uint32_t>(sides[i].key >> 32), static_cast<std::uint32_t>(sides[i].key)});
    t.spring_is_edge.push_back(edge ? 1 : 0);
    if (j - i > 2) {
      return topo_error(ErrorCode::kNonManifold, m, s,
                        "has a side shared by " + std::to_string(j - i) + " triangles (nodes " +
                            std::to_string(t.node[t.spring.back()[0]].value) + ", " +
                            std::to_string(t.node[t.spring.back()[1]].value) +
                            "): a polygon's fan diagonal coincides with an edge; triangulate it first");
    }
    for (std::size_t x = i; x < j; ++x) t.tri_spring[sides[x].slot / 3][sides[x].slot % 3] = sp;
    if (j - i == 2) {
      t.tri_adj[sides[i].slot / 3][sides[i].slot % 3] = sides[i + 1].slot / 3;
      t.tri_adj[sides[i + 1].slot / 3][sides[i + 1].slot % 3] = sides[i].slot / 3;
    }
    i = j;
  }
  const std::size_t n = t.node.size();
  // CSR: vertex -> springs (in spring order), vertex -> triangles.
  t.vs_off.assign(n + 1, 0);
  for (const auto& sp : t.spring) ++t.vs_off[sp[0] + 1], ++t.vs_off[sp[1] + 1];
  std::partial_sum(t.vs_off.begin(), t.vs_off.end(), t.vs_off.begin());
  t.vs_spring.resize(t.vs_off[n]);
  t.vs_other.resize(t.vs_off[n]);
  {
    std::vector<std::uint32_t> fill(t.vs_off.begin(), t.vs_off.end() - 1);
    for (std::uint32_t sp = 0; sp < t.spring.size(); ++sp)
      for (int e = 0; e < 2; ++e) {
        const std::uint32_t v = t.spring[sp][e];
        t.vs_spring[fill[v]] = sp;
        t.vs_other[fill[v]++] = t.spring[sp][1 - e];
      }
  }
  t.vt_off.assign(n + 1, 0);
  for (const auto& c : t.tri)
    for (std::uint32_t v : c) ++t.vt_off[v + 1];
  std::partial_sum(t.vt_off.begin(), t.vt_off.end(), t.vt_off.begin());
  t.vt_tri.resize(t.vt_off[n]);
  {
    std::vector<std::uint32_t> fill(t.vt_off.begin(), t.vt_off.end() - 1);
    for (std::uint32_t f = 0; f < t.tri.size(); ++f)
      for (std::uint32_t v : t.tri[f]) t.vt_tri[fill[v]++] = f;
  }

  if (check) {
    for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) {
      const EdgeIdx ei{e};
      if (m.alive(ei) && m.is_wire(ei) && m.surface_of(ei) == s)
        return topo_error(ErrorCode::kNonManifold, m, s,
                          "has a wire edge " + std::to_string(e) + " (nodes " +
                              std::to_string(m.tail(halfedge_of(ei, 0)).value) + ", " +
                              std::to_string(m.head(halfedge_of(ei, 0)).value) + ") with no face");
    }
    for (std::uint32_t lv = 0; lv < n; ++lv) {
      const NodeIdx v = t.node[lv];
      if (m.nodes.in_face[v.value].valid())
        return topo_error(ErrorCode::kNonManifold, m, s, "has a ring node " + std::to_string(v.value));
      // One fan of faces around v: walk it from the corner after the
      // boundary halfedge (or any corner) and count the corners reached.
      std::size_t corners = 0, open = 0;
      HalfedgeIdx start;
      m.for_each_outgoing(v, [&](HalfedgeIdx h) {
        if (m.face(h).valid()) {
          ++corners;
          if (!start.valid()) start = h;
        } else {
          ++open;
        }
      });
      if (open > 1)
        return topo_error(ErrorCode::kNonManifold, m, s,
                          "has a non-manifold vertex: node " + std::to_string(v.value) + " joins " +
                              std::to_string(open) + " fans of faces at one point");
      if (open == 1)
        m.for_each_outgoing(v, [&](HalfedgeIdx h) {
          if (!m.face(h).valid()) start = m.next(twin(h));
        });
      std::size_t reached = 0;
      HalfedgeIdx h = start;
      do {
        ++reached;
        const HalfedgeIdx back = twin(h);
        if (!m.face(back).valid()) break;
        h = m.next(back);
      } while (h != start && reached <= corners);
      if (reached != corners)
        return topo_error(
            ErrorCode::kNonManifold, m, s,
            "has a non-manifold vertex: node " + std::to_string(v.value) + " joins several fans of faces at one point");
    }
    std::vector<std::uint32_t> comp(t.tri.size(), kNone), stack;
    std::size_t components = 0;
    for (std::uint32_t f0 = 0; f0 < t.tri.size(); ++f0) {
      if (comp[f0] != kNone) continue;
      comp[f0] = static_cast<std::uint32_t>(components);
      stack.assign(1, f0);
      while (!stack.empty()) {
        const std::uint32_t f = stack.back();
        stack.pop_back();
        for (std::uint32_t g : t.tri_adj[f])
          if (g != kNone && comp[g] == kNone) comp[g] = static_cast<std::uint32_t>(components), stack.push_back(g);
      }
      ++components;
    }
    if (components > 1)
      return topo_error(ErrorCode::kTopology, m, s,
                        "has " + std::to_string(components) + " separate parts: make each part its own surface");
  }
  // Boundary loops: faceless halfedges of the piece, chained head to tail.
  std::vector<std::uint8_t> seen(m.halfedges.tail.size(), 0);
  for (std::uint32_t lv = 0; lv < n; ++lv) {
    m.for_each_outgoing(t.node[lv], [&](HalfedgeIdx h0) {
      if (m.face(h0).valid() || !m.face(twin(h0)).valid() || seen[h0.value]) return;
      std::vector<std::uint32_t> loop;
      std::vector<HalfedgeIdx> hs;
      HalfedgeIdx h = h0;
      while (h.valid() && !seen[h.value]) {
        seen[h.value] = 1;
        loop.push_back(local[m.tail(h).value]);
        hs.push_back(h);
        HalfedgeIdx nxt;
        m.for_each_outgoing(m.head(h), [&](HalfedgeIdx o) {
          if (!nxt.valid() && !m.face(o).valid() && m.face(twin(o)).valid() && !seen[o.value]) nxt = o;
        });
        h = nxt;
      }
      t.loops.push_back(std::move(loop));
      t.loop_halfedges.push_back(std::move(hs));
    });
  }
  if (check) {
    const std::int64_t chi = static_cast<std::int64_t>(n) - static_cast<std::int64_t>(t.spring.size()) +
                             static_cast<std::int64_t>(t.tri.size());
    const auto b = static_cast<std::int64_t>(t.loops.size());
    if (b == 0)
      return topo_error(ErrorCode::kTopology, m, s,
                        "is closed (it has no boundary): cut it along a seam before flattening");
    const std::int64_t genus = (2 - chi - b) / 2;
    if (genus > 0)
      return topo_error(ErrorCode::kTopology, m, s,
                        "has " + std::to_string(genus) + " handle(s) (genus): cut it along seams before flattening");
    if (b > 1 && !allow_holes)
      return topo_error(ErrorCode::kTopology, m, s,
                        "has " + std::to_string(b) +
                            " boundary loops (a tube such as a sleeve or a skirt, or a piece with holes): cut it "
                            "along a seam first, or allow holes");
  }
  return t;
}

namespace {

/// l_ij, C_ij and 3D triangle areas from the positions; errors name the node
/// or face.
Expected<RestState> rest_state(const std::string& label, const PieceTopology& t, std::span<const Vec3d> pos,
                               const FlattenOptions& opt) {
  auto fail = [&](const std::string& what) { return Status(ErrorCode::kDegenerate, label + " " + what); };
  RestState r;
  for (NodeIdx v : t.node)
    if (!pos[v.value].allFinite()) return fail("has a non-finite position at node " + std::to_string(v.value));
  r.length.resize(t.spring.size());
  double sum = 0, sum2 = 0;
  for (std::size_t i = 0; i < t.spring.size(); ++i) {
    const NodeIdx a = t.node[t.spring[i][0]], b = t.node[t.spring[i][1]];
    const double l = (pos[a.value] - pos[b.value]).norm();
    if (!(l > 0) || !std::isfinite(l))
      return fail("has a zero-length edge between nodes " + std::to_string(a.value) + " and " +
                  std::to_string(b.value));
    r.length[i] = l;
    sum += l;
    sum2 += l * l;
  }
  const double mean = sum / static_cast<double>(t.spring.size());
  r.stiffness.resize(t.spring.size());
  for (std::size_t i = 0; i < t.spring.size(); ++i)
    r.stiffness[i] = opt.stiffness == SpringStiffness::kUniform ? 1.0 : mean / r.length[i];
  if (!(opt.boundary_stiffness > 0) || !std::isfinite(opt.boundary_stiffness))
    return Status(ErrorCode::kInvalidArgument, label + ": boundary_stiffness must be positive and finite");
  if (opt.boundary_stiffness != 1)
    for (const auto& loop : t.loops)
      for (std::size_t k = 0; k < loop.size(); ++k) {
        const std::uint32_t a = loop[k], b = loop[(k + 1) % loop.size()];
        for (std::uint32_t x = t.vs_off[a]; x < t.vs_off[a + 1]; ++x)
          if (t.vs_other[x] == b) r.stiffness[t.vs_spring[x]] = opt.boundary_stiffness * r.stiffness[t.vs_spring[x]];
      }
  r.area.resize(t.tri.size());
  const double floor = opt.degenerate_area * sum2 / static_cast<double>(t.spring.size());
  for (std::size_t f = 0; f < t.tri.size(); ++f) {
    const auto& c = t.tri[f];
    const Vec3d &p0 = pos[t.node[c[0]].value], &p1 = pos[t.node[c[1]].value], &p2 = pos[t.node[c[2]].value];
    r.area[f] = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    if (!(r.area[f] > floor))
      return fail("has a degenerate face " + std::to_string(t.tri_face[f].value) + " (triangle of nodes " +
                  std::to_string(t.node[c[0]].value) + ", " + std::to_string(t.node[c[1]].value) + ", " +
                  std::to_string(t.node[c[2]].value) + " has area " + std::to_string(r.area[f]) + ")");
  }
  return r;
}

/// The 3D -> 2D map of triangle f: J = [q1 - q0, q2 - q0] [P1, P2]^-1 with
/// P the triangle in its own plane (P0 at the origin, P1 on +x).
Eigen::Matrix2d triangle_map(const PieceTopology& t, std::span<const Vec3d> pos, std::span<const Vec2d> uv,
                             std::size_t f) {
  const auto& c = t.tri[f];
  const Vec3d p0 = pos[t.node[c[0]].value], e1 = pos[t.node[c[1]].value] - p0, e2 = pos[t.node[c[2]].value] - p0;
  const double l1 = e1.norm();
  const Vec3d x = e1 / l1;
  const double px = e2.dot(x), py = (e2 - px * x).norm();
  Eigen::Matrix2d P, Q;
  P << l1, px, 0, py;
  Q.col(0) = uv[c[1]] - uv[c[0]];
  Q.col(1) = uv[c[2]] - uv[c[0]];
  return Q * P.inverse();
}

/// Singular values of a 2x2 matrix, the second negative when it reflects.
Vec2d signed_singular_values(const Eigen::Matrix2d& J) {
  const double E = 0.5 * (J(0, 0) + J(1, 1)), F = 0.5 * (J(0, 0) - J(1, 1));
  const double G = 0.5 * (J(1, 0) + J(0, 1)), H = 0.5 * (J(1, 0) - J(0, 1));
  const double q = std::hypot(E, H), r = std::hypot(F, G);
  return {q + r, q - r};
}

/// Distortion (flatten.h) of the local pattern `uv` (indexed locally).
PatternDistortion distortion(const PieceTopology& t, std::span<const Vec3d> pos, std::span<const Vec2d> uv,
                             std::vector<Vec2d>* stretch, const ExecContext& ctx) {
  PatternDistortion d;
  std::vector<Vec2d> sv(t.tri.size());
  std::vector<double> a3(t.tri.size()), a2(t.tri.size());
  par::for_each_n(ctx, t.tri.size(), [&](std::size_t f) {
    const Eigen::Matrix2d J = triangle_map(t, pos, uv, f);
    sv[f] = signed_singular_values(J);
    const auto& c = t.tri[f];
    const Vec3d p0 = pos[t.node[c[0]].value];
    a3[f] = 0.5 * (pos[t.node[c[1]].value] - p0).cross(pos[t.node[c[2]].value] - p0).norm();
    const Vec2d q1 = uv[c[1]] - uv[c[0]], q2 = uv[c[2]] - uv[c[0]];
    a2[f] = 0.5 * (q1.x() * q2.y() - q1.y() * q2.x());
  });
  double da = 0, sa = 0;
  for (std::size_t f = 0; f < t.tri.size(); ++f) {
    da += std::abs(a2[f] - a3[f]);
    sa += a3[f];
    if (!(a2[f] > 0)) ++d.flipped;
    d.min_stretch = std::min(d.min_stretch, sv[f].y());
    d.max_stretch = std::max(d.max_stretch, sv[f].x());
  }
  d.area_error = da / sa;
  double dl = 0, sl = 0;
  for (std::size_t s = 0; s < t.spring.size(); ++s) {
    if (!t.spring_is_edge[s]) continue;
    const auto& sp = t.spring[s];
    const double l = (pos[t.node[sp[0]].value] - pos[t.node[sp[1]].value]).norm();
    const double l2 = (uv[sp[0]] - uv[sp[1]]).norm();
    dl += std::abs(l2 - l);
    sl += l;
    d.max_edge_strain = std::max(d.max_edge_strain, std::abs(l2 - l) / l);
  }
  d.length_error = dl / sl;
  d.boundary_crossings = count_boundary_crossings(t, uv);
  if (stretch) *stretch = std::move(sv);
  return d;
}

/// Turns the pattern so the grain runs along +v and moves its bounding box to
/// start at the origin (a rigid motion).
void place(const PieceTopology& t, std::span<const Vec3d> pos, std::vector<Vec2d>& uv, const Vec3d& grain) {
  const std::size_t n = uv.size();
  Vec2d dir = Vec2d::Zero();
  double area = 0;
  if (grain.squaredNorm() > 0) {
    // The grain's image, area-weighted over the triangles: J (g projected on
    // the triangle's plane) in the triangle's own 2D frame.
    const Vec3d g = grain.normalized();
    for (std::size_t f = 0; f < t.tri.size(); ++f) {
      const auto& c = t.tri[f];
      const Vec3d p0 = pos[t.node[c[0]].value], e1 = pos[t.node[c[1]].value] - p0, e2 = pos[t.node[c[2]].value] - p0;
      const Vec3d x = e1.normalized(), nrm = e1.cross(e2);
      const double area2 = nrm.norm();
      const Vec3d y = nrm.normalized().cross(x);
      dir += 0.5 * area2 * triangle_map(t, pos, uv, f) * Vec2d(g.dot(x), g.dot(y));
      area += 0.5 * area2;
    }
  }
  Vec2d centroid = Vec2d::Zero();
  for (const Vec2d& q : uv) centroid += q;
  centroid /= static_cast<double>(n);
  // A grain (nearly) normal to the whole piece has no usable image.
  if (!(dir.norm() > 1e-6 * area)) {
    // Principal axis of the vertices; its sign from the third moment, then
    // from the first vertex, so it does not depend on how the piece lies in 3D.
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (const Vec2d& q : uv) cov += (q - centroid) * (q - centroid).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
    dir = es.eigenvectors().col(1);
    double m3 = 0;
    for (const Vec2d& q : uv) m3 += std::pow(dir.dot(q - centroid), 3);
    const double scale = std::pow(std::max(cov.trace() / static_cast<double>(n), 1e-300), 1.5);
    if (std::abs(m3) > 1e-9 * scale * static_cast<double>(n) ? m3 < 0 : dir.dot(uv[0] - centroid) < 0) dir = -dir;
  }
  dir.normalize();
  // Rotation taking dir to +v: rows (v-perp, v).
  Eigen::Matrix2d R;
  R << dir.y(), -dir.x(), dir.x(), dir.y();
  Vec2d lo(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity());
  for (Vec2d& q : uv) {
    q = R * (q - centroid);
    lo = lo.cwiseMin(q);
  }
  for (Vec2d& q : uv) q -= lo;
}

}  // namespace

// ------------------------------------------------------------------ Flattener

struct Flattener::Impl {
  SurfaceIdx surface;
  std::string name;
  FlattenOptions opt;
  PieceTopology topo;
  Phase2Solver solver;
  PieceSeams seams;                // FlattenOptions::seam_lengths
  std::uint32_t seed_tri = kNone;  // from FlattenOptions::seed_faces, else chosen per flatten
  std::size_t model_nodes = 0;
  std::string label;
};

Flattener::Flattener() = default;
Flattener::~Flattener() = default;
Flattener::Flattener(Flattener&&) noexcept = default;
Flattener& Flattener::operator=(Flattener&&) noexcept = default;

bool Flattener::built() const noexcept {
  return impl_ != nullptr;
}
SurfaceIdx Flattener::surface() const noexcept {
  return impl_ ? impl_->surface : SurfaceIdx{};
}

Status Flattener::warm_from(const Flattener& other) {
  if (!impl_ || !other.impl_) return {ErrorCode::kInvalidArgument, "Flattener::warm_from: not built"};
  Impl& I = *impl_;
  const Impl& O = *other.impl_;
  if (I.topo.node != O.topo.node || I.seams.lengths.sides != O.seams.lengths.sides)
    return {ErrorCode::kInvalidArgument,
            "Flattener::warm_from: " + I.label + " and " + O.label + " are not the same piece topology"};
  I.seams.lengths.lambda = O.seams.lengths.lambda;
  // Fanned otherwise (a polygon's fan starts at another corner: open_seams
  // picks it from the geometry), the springs differ: no factor to share,
  // phase 2 factors its own.
  I.solver.set_factor(I.topo.tri == O.topo.tri ? O.solver.factor() : nullptr);
  return {};
}

Status Flattener::build(const Model& m, SurfaceIdx s, const FlattenOptions& opt) {
  impl_.reset();
  if (opt.max_iterations < 0 || opt.relax_rings < 0 || opt.relax_sweeps < 0 || opt.lbfgs_memory < 1 ||
      !(opt.tolerance >= 0) || !(opt.degenerate_area >= 0) || !opt.grain.allFinite())
    return {ErrorCode::kInvalidArgument, "flatten: an option is out of range"};
  auto topo = build_topology(m, s, opt.allow_holes, true);
  if (!topo) return topo.status();
  auto impl = std::make_unique<Impl>();
  impl->surface = s;
  impl->name = m.surfaces.name[s.value];
  impl->label = surface_label(m, s);
  impl->opt = opt;
  impl->topo = std::move(*topo);
  impl->model_nodes = m.nodes.slots.capacity();
  for (FaceIdx f : opt.seed_faces) {
    if (!m.alive(f) || m.faces.surface[f.value] != s) continue;
    const auto it = std::find(impl->topo.tri_face.begin(), impl->topo.tri_face.end(), f);
    impl->seed_tri = static_cast<std::uint32_t>(it - impl->topo.tri_face.begin());
    break;
  }
  if (opt.seam_lengths) impl->seams = collect_seams(m, s, impl->topo);
  impl->solver.analyze(impl->topo);
  impl_ = std::move(impl);
  return {};
}

Expected<PieceFlattening> Flattener::flatten(std::span<const Vec3d> positions, std::span<Vec2d> uv, bool warm_start,
                                             const ExecContext& ctx) {
  if (!impl_) return Status(ErrorCode::kInvalidArgument, "Flattener::flatten: build() was not called");
  Impl& I = *impl_;
  if (positions.size() < I.model_nodes || uv.size() < I.model_nodes)
    return Status(ErrorCode::kInvalidArgument, "Flattener::flatten: " + I.label + " needs " +
                                                   std::to_string(I.model_nodes) + " positions and uv entries");
  const auto t0 = std::chrono::steady_clock::now();
  const PieceTopology& t = I.topo;
  auto rest = rest_state(I.label, t, positions, I.opt);
  if (!rest) return rest.status();
  if (!I.seams.lengths.sides.empty())
    if (Status st = set_seam_targets(I.seams, positions, I.label); !st) return st;
  SolverParams prm;
  prm.relax_rings = I.opt.relax_rings;
  prm.relax_sweeps = I.opt.relax_sweeps;
  prm.max_iterations = I.opt.max_iterations;
  prm.tolerance = I.opt.tolerance;
  prm.memory = I.opt.lbfgs_memory;
  SolverStats stats;
  PieceFlattening out;
  std::vector<Vec2d> q(t.vertex_count());
  bool warm = false;
  if (warm_start) {
    bool finite = true;
    for (std::size_t v = 0; v < q.size(); ++v) {
      q[v] = uv[t.node[v].value];
      finite = finite && q[v].allFinite();
    }
    // The start fitted to this body's lengths (another body's pattern is
    // off by the change of size), then checked: an affine map with det > 0
    // keeps a flip-free, crossing-free start so, up to rounding.
    if (finite && count_flipped(t, q, ctx) == 0 && count_boundary_crossings(t, q) == 0) {
      fit_warm_start(t, *rest, q);
      warm = count_flipped(t, q, ctx) == 0 && count_boundary_crossings(t, q) == 0;
    }
  }
  std::uint32_t seed = I.seed_tri;
  if (seed == kNone) {
    seed = 0;
    for (std::uint32_t f = 1; f < t.tri.size(); ++f)
      if (rest->area[f] > rest->area[seed]) seed = f;
  }
  // The cold start: phase 1, or Tutte's embedding where it leaves a flip or
  // a crossing; multipliers carry over only with the pattern they belong to.
  auto cold_start = [&] {
    run_phase1(t, *rest, seed, prm, q, stats);
    if (count_flipped(t, q, ctx) > 0 || count_boundary_crossings(t, q) > 0) {
      tutte_embedding(t, *rest, q);
      stats.tutte_fallback = true;
    }
    std::fill(I.seams.lengths.lambda.begin(), I.seams.lengths.lambda.end(), 0.0);
  };
  if (!warm) cold_start();
  prm.stall_window = warm ? kWarmStallWindow : 0;
  if (!I.solver.run(t, *rest, prm, q, stats, ctx, warm, &I.seams.lengths))
    return Status(ErrorCode::kInternal, "flatten: " + I.label + ": the spring Laplacian could not be factored");
  // A warm start that stalled (it pressed triangles into a flip on every
  // step), or that ended with a seam off its length by more than
  // kWarmSeamTolerance of the shortest target (its line search gave up: a
  // leg on some bodies), is given up: the piece starts again cold, as if
  // there had been no warm start (the same bits).
  double shortest = std::numeric_limits<double>::infinity();
  for (double target : I.seams.lengths.target) shortest = std::min(shortest, target);
  if (stats.stalled || (warm && stats.seam_residual > kWarmSeamTolerance * shortest)) {
    out.warm_abandoned_iterations = stats.iterations;
    stats = SolverStats{};
    prm.stall_window = 0;
    warm = false;
    cold_start();
    if (!I.solver.run(t, *rest, prm, q, stats, ctx, false, &I.seams.lengths))
      return Status(ErrorCode::kInternal, "flatten: " + I.label + ": the spring Laplacian could not be factored");
  }
  place(t, positions, q, I.opt.grain);
  out.distortion = distortion(t, positions, q, &out.stretch, ctx);
  for (const Vec2d& x : q)
    if (!x.allFinite())
      return Status(ErrorCode::kInternal, "flatten: " + I.label + ": the pattern has non-finite coordinates");
  for (std::size_t v = 0; v < q.size(); ++v) uv[t.node[v].value] = q[v];
  out.surface = I.surface;
  out.name = I.name;
  out.nodes = t.vertex_count();
  out.triangles = t.tri.size();
  out.springs = t.spring.size();
  out.boundary_loops = t.loops.size();
  out.seed_face = t.tri_face[seed];
  out.triangle_face = t.tri_face;
  out.triangle_nodes.resize(t.tri.size());
  for (std::size_t f = 0; f < t.tri.size(); ++f)
    for (int k = 0; k < 3; ++k) out.triangle_nodes[f][k] = t.node[t.tri[f][k]];
  out.energy_phase1 = stats.energy_phase1;
  out.energy = stats.energy;
  out.closures = stats.closures;
  out.iterations = stats.iterations;
  out.rejected_steps = stats.rejected_steps;
  out.warm_started = warm;
  out.tutte_fallback = stats.tutte_fallback;
  out.reused_factor = stats.reused_factor;
  out.seam_constraints = I.seams.lengths.size();
  out.seam_rounds = stats.seam_rounds;
  out.seam_projections = stats.seam_projections;
  out.seam_residual = stats.seam_residual;
  out.phase1_ms = stats.phase1_ms;
  out.factor_ms = stats.factor_ms;
  out.phase2_ms = stats.phase2_ms;
  out.total_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

// ------------------------------------------------------------- ModelFlattener

Status ModelFlattener::build(const Model& m, const FlattenOptions& opt) {
  pieces_.clear();
  surfaces_ = opt.surfaces;
  if (surfaces_.empty()) {
    std::vector<std::uint8_t> has(m.surfaces.slots.capacity(), 0);
    for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f)
      if (m.alive(FaceIdx{f})) has[m.faces.surface[f].value] = 1;
    for (std::uint32_t s = 0; s < has.size(); ++s)
      if (has[s] && m.alive(SurfaceIdx{s})) surfaces_.push_back(SurfaceIdx{s});
  }
  if (surfaces_.empty()) return {ErrorCode::kTopology, "flatten: the model has no surface with faces"};
  pieces_.resize(surfaces_.size());
  for (std::size_t i = 0; i < surfaces_.size(); ++i)
    if (Status st = pieces_[i].build(m, surfaces_[i], opt); !st) {
      pieces_.clear();
      return st;
    }
  node_slots_ = m.nodes.slots.capacity();
  return {};
}

Status ModelFlattener::warm_from(const ModelFlattener& other) {
  if (pieces_.size() != other.pieces_.size() || surfaces_ != other.surfaces_)
    return {ErrorCode::kInvalidArgument, "ModelFlattener::warm_from: the two have different pieces"};
  for (std::size_t i = 0; i < pieces_.size(); ++i)
    if (Status st = pieces_[i].warm_from(other.pieces_[i]); !st) return st;
  return {};
}

Expected<FlattenReport> ModelFlattener::flatten(std::span<const Vec3d> positions, std::span<Vec2d> uv, bool warm_start,
                                                const ExecContext& ctx) {
  if (pieces_.empty()) return Status(ErrorCode::kInvalidArgument, "ModelFlattener::flatten: build() was not called");
  if (uv.size() < node_slots_)
    return Status(ErrorCode::kInvalidArgument, "ModelFlattener::flatten: uv needs one entry per node slot");
  // Pieces in parallel, one task each (their nodes are disjoint); into a
  // copy, committed when every piece succeeded.
  std::vector<Vec2d> out(uv.begin(), uv.begin() + static_cast<std::ptrdiff_t>(node_slots_));
  std::vector<Expected<PieceFlattening>> done(pieces_.size(), Status(ErrorCode::kCancelled, "flatten: cancelled"));
  ExecContext outer = ctx;
  outer.sequential_threshold = 2;
  outer.grain = 1;
  std::mutex report_mutex;  // ctx.progress is called from one thread at a time
  std::size_t finished = 0;
  ctx.report("flatten: pieces", 0, pieces_.size());
  par::for_each_n(outer, pieces_.size(), [&](std::size_t i) {
    if (ctx.cancelled()) return;
    done[i] = pieces_[i].flatten(positions, out, warm_start, ctx);
    const std::lock_guard<std::mutex> lock(report_mutex);
    ctx.report("flatten: pieces", ++finished, pieces_.size());
  });
  FlattenReport rep;
  for (auto& d : done) {
    if (!d) return d.status();
    rep.pieces.push_back(std::move(*d));
  }
  std::copy(out.begin(), out.end(), uv.begin());
  return rep;
}

Expected<FlattenReport> flatten_surfaces(Model& m, const FlattenOptions& opt, const ExecContext& ctx) {
  ModelFlattener fl;
  if (Status st = fl.build(m, opt); !st) return st;
  std::vector<Vec2d> uv = m.nodes.uv;
  uv.resize(m.nodes.slots.capacity(), Vec2d::Zero());
  auto rep = fl.flatten(m.nodes.position, uv, false, ctx);
  if (rep) m.nodes.uv = std::move(uv);
  return rep;
}

Expected<PatternDistortion> measure_pattern(const Model& m, SurfaceIdx s, std::span<const Vec3d> positions,
                                            std::span<const Vec2d> uv, const ExecContext& ctx) {
  auto topo = build_topology(m, s, true, false);
  if (!topo) return topo.status();
  const std::size_t cap = m.nodes.slots.capacity();
  if (positions.size() < cap || uv.size() < cap)
    return Status(ErrorCode::kInvalidArgument, "measure_pattern: positions and uv need one entry per node slot");
  FlattenOptions opt;
  opt.degenerate_area = 0;
  auto rest = rest_state(surface_label(m, s), *topo, positions, opt);
  if (!rest) return rest.status();
  std::vector<Vec2d> q(topo->vertex_count());
  for (std::size_t v = 0; v < q.size(); ++v) q[v] = uv[topo->node[v].value];
  return distortion(*topo, positions, q, nullptr, ctx);
}

}  // namespace atelier
