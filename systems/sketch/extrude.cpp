// Why this file is long: the five steps of seed 002 (base curve, plane, sweep
// with its fold check, sewing, optimisation call) and the two additions
// beyond the paper (the body push, the part as its own surface) share one
// transactional run(); the optimisation itself lives in optimise_region.cpp,
// the body push and the passes around it in extrude_body.cpp, the part's
// surface in extrude_surface.cpp.
#include <atelier/storage/topology.h>
#include <atelier/storage/validate.h>
#include <atelier/systems/sketch/cut.h>
#include <atelier/systems/sketch/extrude.h>
#include <atelier/systems/sketch/optimise_region.h>
#include <atelier/systems/sketch/paint.h>
#include <atelier/systems/spatial/collision_body.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "extrude_detail.h"

namespace atelier {

namespace extrude_detail {
Status fail(ErrorCode c, const std::string& what) {
  return Status(c, "extrude: " + what);
}
}  // namespace extrude_detail
using extrude_detail::fail;

namespace {

/// At least 2 distinct points, all finite.
Status check_stroke(std::span<const Vec2d> s, const std::string& name) {
  for (std::size_t i = 0; i < s.size(); ++i)
    if (!s[i].allFinite())
      return fail(ErrorCode::kInvalidArgument, name + " point " + std::to_string(i) + " is not finite");
  std::size_t distinct = s.empty() ? 0 : 1;
  for (std::size_t i = 1; i < s.size(); ++i) distinct += s[i] != s[i - 1];
  if (distinct < 2)
    return fail(ErrorCode::kInvalidArgument,
                name + " needs at least 2 distinct points (found " + std::to_string(s.size()) + ")");
  return {};
}

Vec2d screen(const Camera& c, const Vec3d& p) {
  return c.project(p).head<2>();
}

/// Screen distance from q to the polyline.
double distance_to(std::span<const Vec2d> line, const Vec2d& q) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 1 < line.size(); ++i) {
    const Vec2d a = line[i], d = line[i + 1] - a;
    const double dd = d.squaredNorm();
    const double t = dd > 0 ? std::clamp((q - a).dot(d) / dd, 0.0, 1.0) : 0.0;
    best = std::min(best, (a + t * d - q).norm());
  }
  if (line.size() == 1) best = (line[0] - q).norm();
  return best;
}

/// The point of B nearest on screen to pixel q (section 3.2, constraint 1):
/// on B's segments, linearly interpolated in 3D. Returns the screen distance.
double nearest_on_base(const Model& m, const Camera& cam, std::span<const NodeIdx> base, bool ring, const Vec2d& q,
                       Vec3d& out, std::uint32_t& seg, double& at) {
  double best = std::numeric_limits<double>::infinity();
  const std::size_t segs = ring ? base.size() : base.size() - 1;
  for (std::size_t i = 0; i < segs; ++i) {
    const Vec3d A = m.position(base[i]), B = m.position(base[(i + 1) % base.size()]);
    const Vec2d a = screen(cam, A), b = screen(cam, B);
    if (!a.allFinite() || !b.allFinite()) continue;
    const Vec2d d = b - a;
    const double dd = d.squaredNorm();
    const double t = dd > 0 ? std::clamp((q - a).dot(d) / dd, 0.0, 1.0) : 0.0;
    const double dist = (a + t * d - q).norm();
    if (dist < best) {
      best = dist;
      out = A + t * (B - A);  // the recipe's P* = B[s] + t (B[s+1] - B[s]), bit for bit
      seg = static_cast<std::uint32_t>(i);
      at = t;
    }
  }
  return best;
}

bool in_surfaces(const Model& m, NodeIdx v, std::span<const SurfaceIdx> only) {
  if (only.empty()) return true;
  return std::find(only.begin(), only.end(), m.nodes.surface[v.value]) != only.end();
}

/// The unique faceless outgoing halfedge of v with a face on its twin.
Expected<HalfedgeIdx> boundary_out(const Model& m, NodeIdx v) {
  HalfedgeIdx found;
  int count = 0;
  m.for_each_outgoing(v, [&](HalfedgeIdx h) {
    if (!m.face(h).valid() && m.face(twin(h)).valid()) {
      found = h;
      ++count;
    }
  });
  if (count > 1)
    return fail(ErrorCode::kNonManifold,
                "boundary node " + std::to_string(v.value) + " starts " + std::to_string(count) + " boundary arcs");
  if (count == 0) return fail(ErrorCode::kInvalidArgument, "node " + std::to_string(v.value) + " is not on a boundary");
  return found;
}

/// Nodes from s along the boundary (faceless halfedges) to t; empty when the
/// loop returns to s first. s == t walks the whole loop (s not repeated).
Expected<std::vector<NodeIdx>> walk_boundary(const Model& m, NodeIdx s, NodeIdx t) {
  std::vector<NodeIdx> out{s};
  NodeIdx v = s;
  for (std::size_t steps = 0; steps <= m.num_edges(); ++steps) {
    auto h = boundary_out(m, v);
    if (!h) return h.status();
    v = m.head(*h);
    if (v == t) {
      if (t != s) out.push_back(v);
      return out;
    }
    if (v == s) return std::vector<NodeIdx>{};
    out.push_back(v);
  }
  return fail(ErrorCode::kInternal, "boundary walk did not end");
}

struct Base {
  std::vector<NodeIdx> nodes;  // along the faceless halfedges
  bool ring = false;
  std::size_t faces_removed = 0;
};

/// Closed base stroke: paint, cut away the enclosed side, read B off the curve.
Expected<Base> closed_base(Model& m, const ExtrudeStrokes& in, const ExtrudeOptions& opt, const ExecContext& ctx) {
  PaintOptions po;
  po.surfaces = opt.surfaces;
  auto pr = paint_stroke(m, in.base_camera, in.base, po, ctx);
  if (!pr) return fail(pr.status().code(), "base stroke: " + pr.status().message());
  if (pr->curves.size() != 1 || !pr->curves[0].closed)
    return fail(ErrorCode::kInvalidArgument, "the closed base stroke must paint one closed curve (got " +
                                                 std::to_string(pr->curves.size()) + " curve(s)" +
                                                 (pr->curves.size() == 1 ? ", open" : "") + ")");
  if (pr->curves[0].edges.size() != 1) return fail(ErrorCode::kUnsupported, "the base curve crosses several surfaces");
  const AttribEdge curve = pr->curves[0].edges[0];
  CutOptions co;
  co.retriangulate = opt.retriangulate;
  auto cr = cut_along_curves(m, pr->curves[0].edges, co, ctx);
  if (!cr) return fail(cr.status().code(), "base cut: " + cr.status().message());
  Base b;
  b.ring = true;
  b.faces_removed = cr->faces_removed;
  if (!m.alive(curve)) return fail(ErrorCode::kInternal, "the base curve did not survive the cut");
  for (AttribNodeIdx a : m.attrib_edges.nodes.row(curve.idx.value)) {
    if (m.attrib_nodes.kind[a.value] != AttribNodeKind::kVertex)
      return fail(ErrorCode::kInternal, "a base curve node is not on a mesh node after the cut");
    const NodeIdx v{m.attrib_nodes.element[a.value]};
    if (b.nodes.empty() || b.nodes.back() != v) b.nodes.push_back(v);
  }
  if (b.nodes.size() > 1 && b.nodes.front() == b.nodes.back()) b.nodes.pop_back();
  if (b.nodes.size() < 3) return fail(ErrorCode::kDegenerate, "the base ring has fewer than 3 nodes");
  // Orient B along its faceless halfedges (the side the new faces go on).
  int forward = 0, backward = 0;
  for (std::size_t i = 0; i < b.nodes.size(); ++i) {
    const HalfedgeIdx h = m.find_halfedge(b.nodes[i], b.nodes[(i + 1) % b.nodes.size()]);
    if (!h.valid()) return fail(ErrorCode::kInternal, "consecutive base nodes share no edge");
    forward += !m.face(h).valid();
    backward += !m.face(twin(h)).valid();
  }
  const int n = static_cast<int>(b.nodes.size());
  if (backward == n && forward == 0)
    std::reverse(b.nodes.begin(), b.nodes.end());
  else if (!(forward == n && backward == 0))
    return fail(ErrorCode::kTopology, "the cut did not leave the base curve as one boundary ring");
  return b;
}

/// Open base stroke: the boundary arc it follows on screen.
Expected<Base> open_base(const Model& m, const ExtrudeStrokes& in, const ExtrudeOptions& opt,
                         const extrude_detail::BaseSide* only) {
  const Camera& cam = in.base_camera;
  const Vec2d first = in.base.front(), last = in.base.back();
  NodeIdx s, t;
  double ds = opt.pick_radius, dt = opt.pick_radius;
  std::vector<Vec2d> px(m.nodes.slots.capacity(), Vec2d::Constant(std::numeric_limits<double>::quiet_NaN()));
  for (std::uint32_t e = 0; e < m.edges.slots.capacity(); ++e) {
    if (!m.alive(EdgeIdx{e}) || !m.is_boundary(EdgeIdx{e})) continue;
    for (unsigned side = 0; side < 2; ++side) {
      const NodeIdx v = m.tail(halfedge_of(EdgeIdx{e}, side));
      if (!in_surfaces(m, v, opt.surfaces)) continue;
      if (only && !(only->sign * (m.position(v) - only->point).dot(only->normal) > 0)) continue;
      const Vec2d p = px[v.value] = screen(cam, m.position(v));
      if (!p.allFinite()) continue;
      if (const double d = (p - first).norm(); d < ds || (d == ds && s.valid() && v.value < s.value)) ds = d, s = v;
      if (const double d = (p - last).norm(); d < dt || (d == dt && t.valid() && v.value < t.value)) dt = d, t = v;
    }
  }
  if (!s.valid() || !t.valid())
    return fail(ErrorCode::kInvalidArgument, std::string("the open base stroke's ") + (s.valid() ? "last" : "first") +
                                                 " point is not within " + std::to_string(opt.pick_radius) +
                                                 " pixels of a boundary node");
  Base b;
  auto score = [&](const std::vector<NodeIdx>& arc) {
    double worst = 0;
    for (NodeIdx v : arc) worst = std::max(worst, distance_to(in.base, px[v.value]));
    return arc.empty() ? std::numeric_limits<double>::infinity() : worst;
  };
  if (s == t) {
    auto loop = walk_boundary(m, s, s);
    if (!loop) return loop.status();
    if ((first - last).norm() > opt.pick_radius || score(*loop) > opt.pick_radius)
      return fail(ErrorCode::kInvalidArgument, "the open base stroke selects a single node");
    b.nodes = std::move(*loop);
    b.ring = true;
  } else {
    auto a1 = walk_boundary(m, s, t);
    if (!a1) return a1.status();
    auto a2 = walk_boundary(m, t, s);
    if (!a2) return a2.status();
    const double s1 = score(*a1), s2 = score(*a2);
    if (std::min(s1, s2) > opt.pick_radius)
      return fail(ErrorCode::kInvalidArgument,
                  "the open base stroke does not follow a boundary between its ends (within " +
                      std::to_string(opt.pick_radius) + " pixels)");
    b.nodes = s1 <= s2 ? std::move(*a1) : std::move(*a2);
  }
  if (b.nodes.size() < 2 || (b.ring && b.nodes.size() < 3))
    return fail(ErrorCode::kDegenerate, "the base curve has too few nodes");
  return b;
}

/// Pixel ray cut with the plane through o with normal n.
Expected<Vec3d> cast(const Camera& cam, const Vec2d& px, const Vec3d& o, const Vec3d& n, const std::string& name) {
  const auto [origin, dir] = cam.ray(px);
  const double den = n.dot(dir);
  if (!(std::abs(den) > 1e-9))
    return fail(ErrorCode::kDegenerate, name + ": a ray runs parallel to the projection plane (seen edge-on)");
  const Vec3d p = origin + (n.dot(o - origin) / den) * dir;
  if (!p.allFinite()) return fail(ErrorCode::kDegenerate, name + ": a projected point is not finite");
  return p;
}

/// Consecutive repeats removed.
std::vector<Vec3d> dedupe(std::vector<Vec3d> v) {
  std::vector<Vec3d> out;
  for (const Vec3d& p : v)
    if (out.empty() || p != out.back()) out.push_back(p);
  return out;
}

/// A (left, right) pair of the sweep (eq. 2): the ends of one copy of P1*P2*.
struct Pair {
  Vec3d left, right;
};

/// Backwards motion of a point of B between consecutive copies that counts
/// as a fold, in B's mean edge lengths: less is a sliver the optimisation
/// removes.
constexpr double kFoldTolerance = 0.1;

/// Where a pair of the sweep puts B's points: the similarity of eq. 2 that
/// maps P1*P2* onto (left, right) (rotation by the frames [n_p, e, n_p x e],
/// scale by the length ratio), as run() places the copies.
struct CopyOfBase {
  std::span<const Vec3d> base;
  Vec3d p1, np;
  Mat3d f_star;
  double chord = 1, tolerance = 0;  // backwards motion allowed: a fraction of B's mean edge

  /// False when the pair's segment has no length (no copy).
  [[nodiscard]] bool place(const Pair& q, std::vector<Vec3d>& out) const {
    Vec3d e = q.right - q.left;
    e -= e.dot(np) * np;
    const double len = e.norm();
    if (!(len > 1e-9 * chord)) return false;
    const Vec3d u = e / len;
    Mat3d f;
    f << np, u, np.cross(u);
    const Mat3d rot = (len / chord) * (f * f_star.transpose());
    out.resize(base.size());
    for (std::size_t t = 0; t < base.size(); ++t) out[t] = q.left + rot * (base[t] - p1);
    return true;
  }
  /// A step folds when a point of B moves backwards (against the motion of
  /// the pair's midpoint) by more than the tolerance: the new strip then
  /// lies over the previous one. This is what eq. 2's one-sided cases do to
  /// a non-planar B: the copy turns about the stationary end, and B's points
  /// off the plane of the turn move back.
  [[nodiscard]] bool folds(const Pair& from, const std::vector<Vec3d>& cf, const Pair& to,
                           const std::vector<Vec3d>& ct) const {
    const Vec3d d = 0.5 * (to.left + to.right) - 0.5 * (from.left + from.right);
    const double dn = d.norm();
    if (!(dn > 0)) return false;
    for (std::size_t t = 0; t < cf.size(); ++t)
      if ((ct[t] - cf[t]).dot(d) < -tolerance * dn) return true;
    return false;
  }
};

/// The paper's greedy sweep (eq. 2) on strokes a (left) and b (right): every
/// step the case with the shortest new segment; ties to the lower case.
std::vector<std::array<std::size_t, 2>> greedy_path(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b) {
  std::vector<std::array<std::size_t, 2>> out;
  std::size_t i = 0, j = 0;
  while (i + 1 < a.size() || j + 1 < b.size()) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t ni = i, nj = j;
    auto consider = [&](std::size_t ci, std::size_t cj) {
      const double l = (a[ci] - b[cj]).norm();
      if (l < best) best = l, ni = ci, nj = cj;
    };
    if (i + 1 < a.size()) consider(i + 1, j);                          // case 1
    if (j + 1 < b.size()) consider(i, j + 1);                          // case 2
    if (i + 1 < a.size() && j + 1 < b.size()) consider(i + 1, j + 1);  // case 3
    i = ni, j = nj;
    out.push_back({i, j});
  }
  return out;
}

/// The sweep of two strokes. Eq. 2's greedy path when none of its steps
/// folds (see CopyOfBase::folds); otherwise (a departure from seed 002,
/// docs/glossary.md) the monotone path over the same stroke points with the
/// fewest folding steps, then the smallest sum of segment lengths (eq. 2's
/// goodness 1/l summed), found by dynamic programming over the (i, j) grid.
std::vector<Pair> sweep_two(const std::vector<Vec3d>& a, const std::vector<Vec3d>& b, const CopyOfBase& cob) {
  std::vector<std::array<std::size_t, 2>> path = greedy_path(a, b);
  std::vector<Vec3d> cf, ct;
  const auto folding = [&](std::size_t i0, std::size_t j0, std::size_t i1, std::size_t j1) {
    const Pair from{a[i0], b[j0]}, to{a[i1], b[j1]};
    if (!cob.place(from, cf) || !cob.place(to, ct)) return false;  // run() refuses a collapsed copy
    return cob.folds(from, cf, to, ct);
  };
  bool any = false;
  for (std::size_t k = 0; k < path.size() && !any; ++k)
    any = folding(k ? path[k - 1][0] : 0, k ? path[k - 1][1] : 0, path[k][0], path[k][1]);
  if (any) {
    // Cost to reach (i, j): (folding steps, sum of segment lengths), the
    // grid in row-major order so that every predecessor comes first.
    const std::size_t na = a.size(), nb = b.size();
    struct Cell {
      std::size_t folds = std::numeric_limits<std::size_t>::max();
      double length = 0;
      std::uint8_t from = 0;  // 1: (i-1, j), 2: (i, j-1), 3: (i-1, j-1)
    };
    std::vector<Cell> grid(na * nb);
    grid[0].folds = 0;
    // The copies of the grid's rows i - 1 and i (two rows: a grid of copies
    // would hold na nb |B| points).
    std::vector<std::vector<Vec3d>> row_prev(nb), row_cur(nb);
    std::vector<char> placed_prev(nb, 0), placed_cur(nb, 0);
    for (std::size_t i = 0; i < na; ++i) {
      for (std::size_t j = 0; j < nb; ++j) placed_cur[j] = cob.place({a[i], b[j]}, row_cur[j]);
      for (std::size_t j = 0; j < nb; ++j) {
        Cell& cell = grid[i * nb + j];
        if ((i || j) && !placed_cur[j]) continue;  // no copy here: the path avoids it
        const double l = (a[i] - b[j]).norm();
        for (std::uint8_t cs = 1; cs <= 3; ++cs) {
          if ((cs & 1) && i == 0) continue;
          if ((cs & 2) && j == 0) continue;
          const std::size_t pi = i - (cs & 1 ? 1 : 0), pj = j - (cs & 2 ? 1 : 0);
          const Cell& prev = grid[pi * nb + pj];
          if (prev.folds == std::numeric_limits<std::size_t>::max()) continue;
          const bool prev_placed = pi == i ? placed_cur[pj] : placed_prev[pj];
          const std::vector<Vec3d>& prev_copy = pi == i ? row_cur[pj] : row_prev[pj];
          const std::size_t f =
              prev.folds + (prev_placed && cob.folds({a[pi], b[pj]}, prev_copy, {a[i], b[j]}, row_cur[j]));
          const double len = prev.length + l;
          if (f < cell.folds || (f == cell.folds && len < cell.length)) cell = {f, len, cs};
        }
      }
      row_prev.swap(row_cur);
      placed_prev.swap(placed_cur);
    }
    if (grid.back().folds != std::numeric_limits<std::size_t>::max()) {
      path.clear();
      for (std::size_t i = na - 1, j = nb - 1; i || j;) {
        path.push_back({i, j});
        const std::uint8_t cs = grid[i * nb + j].from;
        i -= cs & 1 ? 1 : 0;
        j -= cs & 2 ? 1 : 0;
      }
      std::reverse(path.begin(), path.end());
    }
  }
  std::vector<Pair> out;
  for (const auto& ij : path) out.push_back({a[ij[0]], b[ij[1]]});
  return out;
}
/// One stroke q: left from q.front(), right from q.back(), towards each
/// other; the last pair is the meeting point (left == right).
std::vector<Pair> sweep_one(const std::vector<Vec3d>& q) {
  std::vector<Pair> out;
  std::size_t i = 0, j = q.size() - 1;
  while (j > i + 2) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t ni = i, nj = j;
    auto consider = [&](std::size_t ci, std::size_t cj) {
      const double l = (q[ci] - q[cj]).norm();
      if (l < best) best = l, ni = ci, nj = cj;
    };
    consider(i + 1, j);
    consider(i, j - 1);
    consider(i + 1, j - 1);  // j >= i + 3: the pair stays apart
    i = ni, j = nj;
    out.push_back({q[i], q[j]});
  }
  const Vec3d apex = j == i + 2 ? q[i + 1] : 0.5 * (q[i] + q[j]);
  out.push_back({apex, apex});
  return out;
}

}  // namespace

namespace extrude_detail {

/// Signed volume of the model's faces (fan triangles about the origin).
double signed_volume(const Model& m) {
  double v = 0;
  std::vector<NodeIdx> f;
  for (std::uint32_t i = 0; i < m.faces.slots.capacity(); ++i) {
    if (!m.alive(FaceIdx{i})) continue;
    m.face_nodes(FaceIdx{i}, f);
    for (std::size_t k = 1; k + 1 < f.size(); ++k)
      v += m.position(f[0]).dot(m.position(f[k]).cross(m.position(f[k + 1]))) / 6.0;
  }
  return v;
}

/// Nodes that are not old (by slot) and alive.
std::vector<NodeIdx> new_nodes(const Model& m, const std::vector<char>& old) {
  std::vector<NodeIdx> out;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v}) && !(v < old.size() && old[v])) out.push_back(NodeIdx{v});
  return out;
}

/// refine_outside's edges: at least this long (in L; the splits of a
/// crease halve edges round after round), at most this many rounds (on the
/// garment sleeve the count of edges dipping into the body stops falling
/// after 4-6).
constexpr double kRefineShortest = 0.25;
constexpr int kRefineRounds = 6;

Expected<HalfedgeIdx> halfedge_for(Model& m, NodeIdx a, NodeIdx b) {
  HalfedgeIdx h = m.find_halfedge(a, b);
  if (!h.valid()) h = halfedge_of(m.new_edge(a, b), 0);
  if (m.face(h).valid())
    return fail(ErrorCode::kTopology, "edge " + std::to_string(a.value) + "-" + std::to_string(b.value) +
                                          " already has a face on the side to sew");
  return h;
}

Expected<ExtrudeReport> finish(Model& m, ExtrudeReport rep, bool ring, const std::vector<std::vector<Vec3d>>& copies,
                               const ExtrudeOptions& opt, const ExecContext& ctx, RunOut* out, double volume_before) {
  const std::vector<NodeIdx>& B = rep.base;
  const std::size_t n = B.size();
  const SurfaceIdx surface = m.nodes.surface[B[0].value];
  // Step 4: sewing (Figs. 7-8).
  const std::size_t faces0 = m.num_faces(), nodes0 = m.num_nodes();
  std::vector<char> old_node(m.nodes.slots.capacity()), old_face(m.faces.slots.capacity());
  for (std::uint32_t v = 0; v < old_node.size(); ++v) old_node[v] = m.alive(NodeIdx{v});
  for (std::uint32_t f = 0; f < old_face.size(); ++f) old_face[f] = m.alive(FaceIdx{f});
  if (out) {
    out->ring = ring;
    out->old_node = old_node;
    out->old_face = old_face;
  }
  std::vector<FaceIdx> swept;
  std::vector<NodeIdx> prev = B;
  const std::size_t segs = ring ? n : n - 1;
  auto tri = [&](NodeIdx a, NodeIdx b, NodeIdx c) -> Status {
    std::array<HalfedgeIdx, 3> cyc;
    const NodeIdx v[3] = {a, b, c};
    for (int s = 0; s < 3; ++s) {
      auto h = halfedge_for(m, v[s], v[(s + 1) % 3]);
      if (!h) return h.status();
      cyc[s] = *h;
    }
    swept.push_back(m.new_face(surface, cyc));
    return {};
  };
  extrude_detail::CopyAxes axes;
  for (const auto& row : copies) {
    std::vector<NodeIdx> cur;
    for (const Vec3d& p : row) cur.push_back(m.new_node(surface, p));
    if (opt.body && ring && row.size() >= 3) {
      // The copy's centre and (Newell) normal: the sweep's axis at it.
      Vec3d centre = Vec3d::Zero(), normal = Vec3d::Zero();
      for (std::size_t t = 0; t < row.size(); ++t) {
        centre += row[t];
        normal += row[t].cross(row[(t + 1) % row.size()]);
      }
      centre /= static_cast<double>(row.size());
      if (normal.norm() > 0) {
        axes.centre.resize(m.nodes.slots.capacity(), Vec3d::Zero());
        axes.normal.resize(m.nodes.slots.capacity(), Vec3d::Zero());
        for (NodeIdx v : cur) axes.centre[v.value] = centre, axes.normal[v.value] = normal.normalized();
      }
    }
    for (std::size_t t = 0; t < segs; ++t) {
      const std::size_t u = (t + 1) % n;
      // Rule 2: prev[t] -> prev[u] is B's faceless direction (or negative
      // in the previous strip), so it runs the same way in this face.
      if (cur.size() == 1) {
        if (Status s = tri(prev[t], prev[u], cur[0]); !s) return s;
      } else {
        if (Status s = tri(prev[t], prev[u], cur[u]); !s) return s;
        if (Status s = tri(prev[t], cur[u], cur[t]); !s) return s;
      }
    }
    prev = std::move(cur);
  }
  rep.swept_nodes = m.num_nodes() - nodes0;
  rep.swept_faces = m.num_faces() - faces0;
  m.complex_holes = count_topology(m).implied_holes();

  std::vector<char> pushed;
  if (opt.body) {
    push_out(m, old_node, *opt.body, opt.clearance, opt.push_rounds, pushed, &axes);
    if (opt.optimise) {
      extrude_detail::smooth_pushed(m, old_node, pushed, *opt.body, opt.clearance, opt.push_rounds, opt.body_smoothing);
      // The surface the optimisation keeps to, outside the body between the
      // nodes too (extrude_body.cpp); its new faces join the region.
      auto splits = extrude_detail::refine_outside(m, old_node, *opt.body, opt.clearance,
                                                   kRefineShortest * rep.base_mean_edge, kRefineRounds, pushed);
      if (!splits) return fail(splits.status().code(), splits.status().message());
      if (*splits > 0) {
        swept.clear();
        for (std::uint32_t f = 0; f < m.faces.slots.capacity(); ++f)
          if (m.alive(FaceIdx{f}) && !(f < old_face.size() && old_face[f])) swept.push_back(FaceIdx{f});
      }
    }
  }

  // Step 5: optimisation (Fig. 9).
  std::vector<HalfedgeIdx> chain;
  for (std::size_t t = 0; t < segs; ++t) chain.push_back(m.find_halfedge(B[t], B[(t + 1) % n]));
  RegionOptimiseOptions oo = opt.optimisation;
  oo.target = rep.base_mean_edge;
  if (!opt.optimise) oo.passes = 0, oo.repair_budget = 0, oo.relax = false;
  auto oc = optimise_region(m, swept, B, chain, oo, ctx);
  if (!oc) return fail(oc.status().code(), oc.status().message());
  rep.splits = oc->splits;
  rep.collapses = oc->collapses;
  rep.swaps = oc->swaps;
  rep.before = oc->before;
  rep.after = opt.optimise ? oc->after : oc->before;
  rep.max_deviation = oc->max_deviation;
  if (opt.body) {
    push_out(m, old_node, *opt.body, opt.clearance, opt.push_rounds, pushed);
    if (opt.optimise && opt.settle_rounds > 0) {
      auto ops = extrude_detail::settle(m, old_node, old_face, B, chain, oo, *opt.body, opt.clearance, opt.push_rounds,
                                        opt.settle_rounds, kRefineShortest, kRefineRounds, pushed, ctx);
      if (!ops) return fail(ops.status().code(), ops.status().message());
      rep.settle_ops = *ops;
      // The bounds as they end, after the last push.
      rep.after = extrude_detail::new_edge_stats(m, old_node, oo.target, oo.low, oo.high);
    }
    rep.min_body_distance = std::numeric_limits<double>::infinity();
    for (NodeIdx v : new_nodes(m, old_node)) {
      rep.pushed += v.value < pushed.size() && pushed[v.value];
      const double d = opt.body->query(m.position(v)).distance;
      rep.min_body_distance = std::min(rep.min_body_distance, d);
      rep.inside_after += d < 0;
    }
  }
  rep.nodes_added = m.num_nodes() - nodes0;
  rep.faces_added = m.num_faces() - faces0;
  rep.volume_change = signed_volume(m) - volume_before;
  if (opt.as_surface)
    if (Status s = split_off(m, B, ring, rep, ctx); !s) return s;
  for (std::uint32_t v = 0; v < m.nodes.slots.capacity(); ++v)
    if (m.alive(NodeIdx{v}) && !m.nodes.position[v].allFinite())
      return fail(ErrorCode::kInternal, "node " + std::to_string(v) + " has a non-finite position");
  if (Status s = validate(m); !s) return fail(ErrorCode::kInternal, "the result does not validate: " + s.message());
  return rep;
}

Expected<ExtrudeReport> run(Model& m, const ExtrudeStrokes& in, const ExtrudeOptions& opt, const ExecContext& ctx,
                            Stop stop, RunOut* out, const BaseSide* only) {
  if (!(opt.pick_radius > 0) || !std::isfinite(opt.pick_radius))
    return fail(ErrorCode::kInvalidArgument, "pick_radius must be positive and finite");
  for (const Camera* c : {&in.base_camera, &in.sweep_camera})
    if (Status s = c->check(); !s) return fail(ErrorCode::kInvalidArgument, s.message());
  if (Status s = check_stroke(in.base, "base stroke"); !s) return s;
  if (in.sweep.empty() || in.sweep.size() > 2)
    return fail(ErrorCode::kInvalidArgument,
                "one (closed extrusion) or two (open extrusion) extruding strokes needed, found " +
                    std::to_string(in.sweep.size()));
  for (std::size_t k = 0; k < in.sweep.size(); ++k)
    if (Status s = check_stroke(in.sweep[k], "extruding stroke " + std::to_string(k)); !s) return s;
  if (opt.body && (!(opt.clearance >= 0) || !std::isfinite(opt.clearance) || opt.push_rounds < 1))
    return fail(ErrorCode::kInvalidArgument, "the clearance must be finite and >= 0, push_rounds >= 1");
  if (opt.body && opt.body->empty()) return fail(ErrorCode::kInvalidArgument, "the body is empty");
  for (SurfaceIdx s : opt.surfaces)
    if (!m.alive(s)) return fail(ErrorCode::kStaleHandle, "surface " + std::to_string(s.value) + " is dead");

  ExtrudeReport rep;
  const double volume_before = signed_volume(m);
  const bool closed_stroke = in.base.size() > 2 && in.base.front() == in.base.back();
  const bool capped = in.sweep.size() == 1;
  // Step 1: base curve. A closed stroke on an open boundary loop is the
  // loop (open_base); on the surface it is painted and cut (closed_base).
  Expected<Base> base = open_base(m, in, opt, only);
  if (!base && closed_stroke) base = closed_base(m, in, opt, ctx);
  if (!base) return base.status();
  rep.base = base->nodes;
  rep.base_ring = base->ring;
  rep.capped = capped;
  rep.faces_removed = base->faces_removed;
  if (stop == Stop::kAfterBase) return rep;
  if (capped && !base->ring)
    return fail(ErrorCode::kInvalidArgument, "a closed extrusion (one extruding stroke) needs a closed base ring");
  const std::vector<NodeIdx>& B = rep.base;
  const std::size_t n = B.size();
  {
    double sum = 0;
    const std::size_t segs = base->ring ? n : n - 1;
    for (std::size_t i = 0; i < segs; ++i) sum += (m.position(B[(i + 1) % n]) - m.position(B[i])).norm();
    rep.base_mean_edge = sum / static_cast<double>(segs);
  }

  // Step 2: projection plane (eq. 1).
  Vec3d centroid = Vec3d::Zero();
  for (NodeIdx v : B) centroid += m.position(v);
  centroid /= static_cast<double>(n);
  Mat3d cov = Mat3d::Zero();
  for (NodeIdx v : B) cov += (m.position(v) - centroid) * (m.position(v) - centroid).transpose();
  Eigen::SelfAdjointEigenSolver<Mat3d> eig(cov);
  const Vec3d ev = eig.eigenvalues();
  if (!(ev[2] > 0) || !(ev[1] > 1e-12 * ev[2]))
    return fail(ErrorCode::kDegenerate, "the base curve's least-squares plane has no area (B is straight)");
  rep.base_normal = eig.eigenvectors().col(0).normalized();
  const Camera& cam = in.sweep_camera;
  const Vec2d end1 = in.sweep[0].front(), end2 = capped ? in.sweep[0].back() : in.sweep[1].front();
  const double d1 = nearest_on_base(m, cam, B, base->ring, end1, rep.p1, rep.recipe.p1_segment, rep.recipe.p1_t);
  const double d2 = nearest_on_base(m, cam, B, base->ring, end2, rep.p2, rep.recipe.p2_segment, rep.recipe.p2_t);
  if (!(d1 <= opt.pick_radius) || !(d2 <= opt.pick_radius)) {
    std::ostringstream o;
    o << (capped ? "the extruding stroke's " : "extruding stroke ")
      << (!(d1 <= opt.pick_radius) ? (capped ? "first point" : "0") : (capped ? "last point" : "1"))
      << " does not start near the base curve (" << (!(d1 <= opt.pick_radius) ? d1 : d2) << " pixels from it, at most "
      << opt.pick_radius << ")";
    return fail(ErrorCode::kInvalidArgument, o.str());
  }
  const Vec3d e_star = rep.p2 - rep.p1;
  const double chord = e_star.norm();
  if (!(chord > 1e-12 * (1 + centroid.norm())))
    return fail(ErrorCode::kDegenerate, "P1* and P2* coincide: the strokes' ends meet B at one point");
  Vec3d np = e_star.cross(rep.base_normal);
  if (!(np.norm() > 1e-6 * chord)) return fail(ErrorCode::kDegenerate, "P1*P2* is parallel to the normal of B");
  np.normalize();
  const Vec3d view = cam.ray(screen(cam, rep.p1)).second;
  if (np.dot(view) > 0) np = -np;
  if (!(std::abs(np.dot(view)) > 1e-3))
    return fail(ErrorCode::kDegenerate, "the projection plane is seen edge-on from the extruding strokes' camera");
  rep.plane_normal = np;

  std::vector<std::vector<Vec3d>> proj(in.sweep.size());
  for (std::size_t k = 0; k < in.sweep.size(); ++k) {
    for (const Vec2d& px : in.sweep[k]) {
      auto p = cast(cam, px, rep.p1, np, "extruding stroke " + std::to_string(k));
      if (!p) return p.status();
      proj[k].push_back(*p);
    }
    // The sweep starts on B itself: the stroke's first point becomes P*.
    proj[k].front() = k == 0 ? rep.p1 : rep.p2;
    if (capped) proj[k].back() = rep.p2;
    proj[k] = dedupe(std::move(proj[k]));
  }

  // Step 3: sweep (Figs. 5-6, eq. 2).
  const Vec3d u_star = e_star / chord;
  Mat3d f_star;
  f_star << np, u_star, np.cross(u_star);
  std::vector<Vec3d> base_points;
  for (NodeIdx v : B) base_points.push_back(m.position(v));
  const CopyOfBase cob{base_points, rep.p1, np, f_star, chord, kFoldTolerance * rep.base_mean_edge};
  const std::vector<Pair> pairs = capped ? sweep_one(proj[0]) : sweep_two(proj[0], proj[1], cob);
  if (pairs.empty()) return fail(ErrorCode::kDegenerate, "the extruding stroke is too short for one copy of B");
  std::vector<std::vector<Vec3d>> copies;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    Vec3d e = pairs[k].right - pairs[k].left;
    e -= e.dot(np) * np;  // the pair lies in the plane up to rounding
    const double len = e.norm();
    const bool apex = capped && k + 1 == pairs.size();
    if (!apex && !(len > 1e-9 * chord))
      return fail(ErrorCode::kDegenerate, "copy " + std::to_string(k + 1) +
                                              " collapses to a point (the extruding strokes cross or meet early)");
    Mat3d rot = Mat3d::Identity();
    double scale = 0;
    if (!apex) {
      const Vec3d u = e / len;
      Mat3d f;
      f << np, u, np.cross(u);
      rot = f * f_star.transpose();
      scale = len / chord;
    }
    const Vec3d trans = pairs[k].left - scale * (rot * rep.p1);
    rep.scales.push_back(scale);
    rep.rotations.push_back(rot);
    rep.translations.push_back(trans);
  }
  // The copies through B's frame (extrude_recipe.h): the recipe holds the
  // similarities relative to B, and the copies are placed from it, exactly
  // as replay_extrusion places them (a replay on this B repeats them bit for
  // bit; they differ from the direct similarities above by rounding).
  rep.recipe.ring = base->ring;
  rep.recipe.capped = capped;
  for (NodeIdx v : B) rep.recipe.base.push_back(v.value);
  if (Status s = extrude_detail::localise(m, rep.recipe, rep); !s) return s;
  if (Status s = extrude_detail::place_copies(m, rep.recipe, rep, copies); !s) return s;
  if (ctx.cancelled()) return fail(ErrorCode::kCancelled, "cancelled");

  return finish(m, std::move(rep), base->ring, copies, opt, ctx, out, volume_before);
}

}  // namespace extrude_detail

Expected<ExtrudeStrokes> extrusion_from_file(const StrokeFile& file, std::size_t first) {
  std::size_t j = first;
  while (j < file.strokes.size() && file.strokes[j].tool == StrokeTool::kExtrude) ++j;
  if (j - first < 2 || j - first > 3)
    return fail(ErrorCode::kInvalidArgument, "stroke " + std::to_string(first) +
                                                 ": expected a run of 2 or 3 extrude strokes, found " +
                                                 std::to_string(j - first));
  ExtrudeStrokes in;
  in.base_camera = file.strokes[first].camera.value_or(file.camera);
  in.base = file.strokes[first].points;
  in.sweep_camera = file.strokes[first + 1].camera.value_or(file.camera);
  for (std::size_t k = first + 1; k < j; ++k) in.sweep.push_back(file.strokes[k].points);
  return in;
}

Expected<ExtrudeReport> extrude(Model& model, const ExtrudeStrokes& strokes, const ExtrudeOptions& options,
                                const ExecContext& ctx) {
  Model backup = model;  // transactional: every error path restores it
  Expected<ExtrudeReport> r = options.mirror ? extrude_detail::run_mirrored(model, strokes, options, ctx)
                                             : extrude_detail::run(model, strokes, options, ctx,
                                                                   extrude_detail::Stop::kNever, nullptr, nullptr);
  if (!r) model = std::move(backup);
  return r;
}

}  // namespace atelier
