#include <atelier/systems/curvenet/catmull_clark.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <atelier/engine/parallel.h>

namespace atelier {

namespace {

// Corner arithmetic of a quad level (every face has 4 corners, face f owns
// corners 4f .. 4f+3): no offset lookups in the hot loops.
struct QuadCorners {
  static std::uint32_t face(const CornerMesh&, std::uint32_t c) noexcept { return c >> 2; }
  static std::uint32_t next(const CornerMesh&, std::uint32_t c) noexcept { return (c & ~3u) | ((c + 1) & 3u); }
  static std::uint32_t prev(const CornerMesh&, std::uint32_t c) noexcept { return (c & ~3u) | ((c + 3) & 3u); }
};
struct AnyCorners {
  static std::uint32_t face(const CornerMesh& m, std::uint32_t c) noexcept { return m.corner_face[c]; }
  static std::uint32_t next(const CornerMesh& m, std::uint32_t c) noexcept { return m.next_corner(c); }
  static std::uint32_t prev(const CornerMesh& m, std::uint32_t c) noexcept { return m.prev_corner(c); }
};

bool all_quads(const CornerMesh& m) {
  if (m.quads) return true;
  for (std::size_t f = 0; f < m.face_count(); ++f)
    if (m.face_offsets[f + 1] - m.face_offsets[f] != 4) return false;
  return true;
}

/// Level l + 1's topology from level l (see the header for the numbering).
template <class C>
CornerMesh child_topology(const CornerMesh& p, bool full, const ExecContext& ctx) {
  const std::uint32_t V = p.vertex_count;
  const auto E = static_cast<std::uint32_t>(p.edge_count());
  const auto F = static_cast<std::uint32_t>(p.face_count());
  const auto NC = static_cast<std::uint32_t>(p.corner_count());
  CornerMesh c;
  c.vertex_count = V + E + F;
  c.face_offsets.resize(std::size_t{NC} + 1);
  c.face_verts.resize(4 * std::size_t{NC});
  c.quads = true;  // corner arithmetic: no corner_face column
  par::for_each_n(ctx, NC + 1, [&](std::size_t i) { c.face_offsets[i] = static_cast<std::uint32_t>(4 * i); });
  par::for_each_n(ctx, NC, [&](std::size_t ci) {
    const auto k = static_cast<std::uint32_t>(ci);
    const std::uint32_t pc = C::prev(p, k);
    std::uint32_t* fv = c.face_verts.data() + 4 * ci;
    fv[0] = p.face_verts[k];
    fv[1] = V + p.corner_edge[k];
    fv[2] = V + E + C::face(p, k);
    fv[3] = V + p.corner_edge[pc];
  });
  if (!full) return c;

  const std::uint32_t E2 = 2 * E;
  c.corner_edge.resize(4 * std::size_t{NC});
  c.edge_verts.resize(std::size_t{E2} + NC);
  c.edge_corners.resize(std::size_t{E2} + NC);
  par::for_each_n(ctx, NC, [&](std::size_t ci) {
    const auto k = static_cast<std::uint32_t>(ci);
    const std::uint32_t v = p.face_verts[k];
    const std::uint32_t pc = C::prev(p, k);
    const std::uint32_t eo = p.corner_edge[k], ei = p.corner_edge[pc];
    std::uint32_t* ce = c.corner_edge.data() + 4 * ci;
    ce[0] = p.edge_verts[eo][0] == v ? 2 * eo : 2 * eo + 1;
    ce[1] = E2 + k;
    ce[2] = E2 + pc;
    ce[3] = p.edge_verts[ei][0] == v ? 2 * ei : 2 * ei + 1;
    c.edge_verts[E2 + k] = {V + eo, V + E + C::face(p, k)};
    c.edge_corners[E2 + k] = {4 * k + 1, 4 * C::next(p, k) + 2};
  });
  par::for_each_n(ctx, E, [&](std::size_t ei) {
    const auto e = static_cast<std::uint32_t>(ei);
    const auto [a, b] = p.edge_verts[e];
    const auto [c0, c1] = p.edge_corners[e];  // c0 runs a -> b
    c.edge_verts[2 * e] = {a, V + e};
    c.edge_verts[2 * e + 1] = {V + e, b};
    c.edge_corners[2 * e] = {4 * c0, c1 == kNoCorner ? kNoCorner : 4 * C::next(p, c1) + 3};
    c.edge_corners[2 * e + 1] = {4 * C::next(p, c0) + 3, c1 == kNoCorner ? kNoCorner : 4 * c1};
  });
  // Vertex incidence: vertex points keep their corners (x4), edge points
  // have 2 per face of the edge, face points one per corner of the face.
  c.vert_offsets.resize(std::size_t{c.vertex_count} + 1);
  c.vert_corners.resize(4 * std::size_t{NC});
  std::vector<std::uint32_t> edge_base(E);
  par::for_each_n(ctx, E, [&](std::size_t e) { edge_base[e] = p.edge_corners[e][1] == kNoCorner ? 2u : 4u; });
  const std::uint32_t edge_total = par::exclusive_scan_inplace(ctx, edge_base);
  (void)edge_total;
  par::for_each_n(ctx, std::size_t{V} + 1, [&](std::size_t v) { c.vert_offsets[v] = p.vert_offsets[v]; });
  par::for_each_n(ctx, E, [&](std::size_t e) { c.vert_offsets[V + e] = NC + edge_base[e]; });
  par::for_each_n(ctx, std::size_t{F} + 1,
                  [&](std::size_t f) { c.vert_offsets[V + E + f] = 3 * NC + p.face_offsets[f]; });
  par::for_each_n(ctx, NC, [&](std::size_t k) { c.vert_corners[k] = 4 * p.vert_corners[k]; });
  par::for_each_n(ctx, E, [&](std::size_t ei) {
    const auto e = static_cast<std::uint32_t>(ei);
    std::uint32_t* out = c.vert_corners.data() + NC + edge_base[e];
    std::uint32_t n = 0;
    for (std::uint32_t pc : p.edge_corners[e]) {
      if (pc == kNoCorner) continue;
      out[n++] = 4 * pc + 1;
      out[n++] = 4 * C::next(p, pc) + 3;
    }
    std::sort(out, out + n);
  });
  par::for_each_n(ctx, NC, [&](std::size_t k) { c.vert_corners[3 * NC + k] = 4 * static_cast<std::uint32_t>(k) + 2; });
  return c;
}

/// The rule of each vertex point, decided once per level (topology only):
/// kSmooth (interior, or a dart), kCrease with its two crease neighbours,
/// kFixed (corner, 3+ creases, non-manifold, isolated).
enum VertexRule : std::uint8_t { kSmooth = 0, kCrease = 1, kFixed = 2 };

template <class C>
void vertex_rules(const CornerMesh& p, std::span<const std::uint8_t> sharp, std::span<const std::uint8_t> corner,
                  std::vector<std::uint8_t>& rule, std::vector<std::array<std::uint32_t, 2>>& crease_nb,
                  const ExecContext& ctx) {
  rule.assign(p.vertex_count, kSmooth);
  crease_nb.assign(p.vertex_count, {0, 0});
  par::for_each_n(ctx, p.vertex_count, [&](std::size_t vi) {
    const auto v = static_cast<std::uint32_t>(vi);
    const std::uint32_t b = p.vert_offsets[v], e = p.vert_offsets[v + 1];
    if (b == e || corner[v]) {
      rule[v] = kFixed;
      return;
    }
    std::uint32_t creases = 0;
    std::array<std::uint32_t, 2> nb{0, 0};
    for (std::uint32_t k = b; k < e; ++k) {
      const std::uint32_t c = p.vert_corners[k];
      const std::uint32_t eo = p.corner_edge[c];
      if (sharp[eo]) {  // sharp includes the boundary
        if (creases < 2) nb[creases] = p.face_verts[C::next(p, c)];
        ++creases;
      }
      const std::uint32_t pc = C::prev(p, c);
      if (p.edge_corners[p.corner_edge[pc]][1] == kNoCorner) {  // a boundary edge reaching v: no corner starts it at v
        if (creases < 2) nb[creases] = p.face_verts[pc];
        ++creases;
      }
    }
    if (creases > 2)
      rule[v] = kFixed;
    else if (creases == 2) {
      rule[v] = kCrease;
      crease_nb[v] = nb;
    }
  });
}

/// Positions of level l + 1 (vertex points, edge points, face points).
/// Smooth vertices are interior (the boundary is sharp), so their edges
/// are exactly the outgoing edges of their corners.
template <class C>
void refine_positions(const CornerMesh& p, std::span<const std::uint8_t> sharp, std::span<const std::uint8_t> rule,
                      std::span<const std::array<std::uint32_t, 2>> crease_nb, const Vec3d* in, Vec3d* out,
                      const ExecContext& ctx) {
  const std::uint32_t V = p.vertex_count;
  const auto E = static_cast<std::uint32_t>(p.edge_count());
  const auto F = static_cast<std::uint32_t>(p.face_count());
  Vec3d* vp = out;
  Vec3d* ep = out + V;
  Vec3d* fp = out + V + E;
  const std::uint32_t* fv = p.face_verts.data();
  par::for_each_n(ctx, F, [&](std::size_t f) {
    const std::uint32_t b = p.face_offsets[f], e = p.face_offsets[f + 1];
    Vec3d s = in[fv[b]];
    for (std::uint32_t k = b + 1; k < e; ++k) s += in[fv[k]];
    fp[f] = s / static_cast<double>(e - b);
  });
  par::for_each_n(ctx, E, [&](std::size_t e) {
    const auto [a, b] = p.edge_verts[e];
    if (sharp[e]) {
      ep[e] = 0.5 * (in[a] + in[b]);
    } else {
      const auto [c0, c1] = p.edge_corners[e];
      ep[e] = 0.25 * ((in[a] + in[b]) + (fp[C::face(p, c0)] + fp[C::face(p, c1)]));
    }
  });
  par::for_each_n(ctx, V, [&](std::size_t vi) {
    const auto v = static_cast<std::uint32_t>(vi);
    switch (rule[v]) {
      case kFixed:
        vp[v] = in[v];
        return;
      case kCrease:
        vp[v] = 0.125 * (in[crease_nb[v][0]] + 6.0 * in[v] + in[crease_nb[v][1]]);
        return;
      default:
        break;
    }
    const std::uint32_t b = p.vert_offsets[v], e = p.vert_offsets[v + 1];
    Vec3d sum = Vec3d::Zero();
    for (std::uint32_t k = b; k < e; ++k) {
      const std::uint32_t c = p.vert_corners[k];
      sum += fp[C::face(p, c)] + in[fv[C::next(p, c)]];
    }
    const double n = e - b;
    vp[v] = ((n - 2.0) / n) * in[v] + (1.0 / (n * n)) * sum;
  });
}

/// Vertices whose corners are not one fan (two cones touching): they are
/// kept as corners (OpenSubdiv makes non-manifold vertices sharp too).
void mark_nonmanifold(const CornerMesh& m, std::vector<std::uint8_t>& corner) {
  std::vector<std::uint32_t> ring;
  for (std::uint32_t v = 0; v < m.vertex_count; ++v) {
    const std::size_t nc = m.vert_offsets[v + 1] - m.vert_offsets[v];
    if (nc == 0) continue;
    const bool closed = m.ring(v, ring);
    if (ring.size() != (closed ? nc : nc + 1)) corner[v] = 1;
  }
}

}  // namespace

Expected<CatmullClarkRefiner> CatmullClarkRefiner::create(const PolygonSoupView& control, std::size_t vertex_count,
                                                          std::span<const std::array<std::uint32_t, 2>> creases,
                                                          std::span<const std::uint32_t> corners,
                                                          const CatmullClarkOptions& opt, const ExecContext& ctx) {
  if (opt.levels < 0 || opt.levels > 8)
    return Status(ErrorCode::kInvalidArgument,
                  "Catmull-Clark: levels must be in [0, 8], got " + std::to_string(opt.levels));
  auto base = build_corner_mesh(control, vertex_count, ctx);
  if (!base) return base.status();
  CatmullClarkRefiner r;
  r.levels_.push_back(std::move(base).value());
  const CornerMesh& m0 = r.levels_[0];
  std::vector<std::uint8_t> sharp(m0.edge_count(), 0);
  for (std::size_t e = 0; e < m0.edge_count(); ++e) sharp[e] = m0.is_boundary_edge(static_cast<std::uint32_t>(e));
  std::vector<std::uint32_t> crease_ids;
  for (const auto& ab : creases) {
    if (ab[0] >= vertex_count || ab[1] >= vertex_count)
      return Status(ErrorCode::kInvalidArgument, "Catmull-Clark: crease (" + std::to_string(ab[0]) + ", " +
                                                     std::to_string(ab[1]) + ") names a vertex out of range");
    const std::uint32_t e = m0.find_edge(ab[0], ab[1]);
    if (e == kNoCorner)
      return Status(ErrorCode::kInvalidArgument, "Catmull-Clark: crease (" + std::to_string(ab[0]) + ", " +
                                                     std::to_string(ab[1]) + ") is not an edge of the mesh");
    sharp[e] = 1;
    crease_ids.push_back(e);
  }
  std::sort(crease_ids.begin(), crease_ids.end());
  crease_ids.erase(std::unique(crease_ids.begin(), crease_ids.end()), crease_ids.end());
  std::vector<std::uint8_t> corner(vertex_count, 0);
  for (std::uint32_t v : corners) {
    if (v >= vertex_count)
      return Status(ErrorCode::kInvalidArgument, "Catmull-Clark: corner vertex " + std::to_string(v) + " out of range");
    corner[v] = 1;
  }
  mark_nonmanifold(m0, corner);
  std::vector<std::array<std::uint32_t, 2>> crease_pairs;
  for (std::uint32_t e : crease_ids) crease_pairs.push_back(m0.edge_verts[e]);
  r.sharp_.push_back(std::move(sharp));
  r.corner_.push_back(std::move(corner));
  r.creases_.push_back(std::move(crease_pairs));
  r.rules_.emplace_back();
  r.crease_nb_.emplace_back();
  std::vector<std::uint32_t> level_creases = crease_ids;
  for (int l = 0; l < opt.levels; ++l) {
    if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "Catmull-Clark: cancelled");
    const CornerMesh& p = r.levels_.back();
    if (l > 0 || all_quads(p))
      vertex_rules<QuadCorners>(p, r.sharp_.back(), r.corner_.back(), r.rules_.back(), r.crease_nb_.back(), ctx);
    else
      vertex_rules<AnyCorners>(p, r.sharp_.back(), r.corner_.back(), r.rules_.back(), r.crease_nb_.back(), ctx);
    const std::size_t child_vertices = std::size_t{p.vertex_count} + p.edge_count() + p.face_count();
    if (child_vertices >= kNoCorner || 4 * p.corner_count() >= kNoCorner)
      return Status(ErrorCode::kInvalidArgument,
                    "Catmull-Clark: level " + std::to_string(l + 1) + " would exceed 2^32 - 2 vertices or corners");
    const bool full = l + 1 < opt.levels || opt.full_topology_in_last_level;
    CornerMesh c = all_quads(p) ? child_topology<QuadCorners>(p, full, ctx) : child_topology<AnyCorners>(p, full, ctx);
    const auto E = static_cast<std::uint32_t>(p.edge_count());
    std::vector<std::uint8_t> cs;
    if (full) {
      cs.assign(c.edge_count(), 0);
      const auto& ps = r.sharp_.back();
      par::for_each_n(ctx, E, [&](std::size_t e) { cs[2 * e] = cs[2 * e + 1] = ps[e]; });
    }
    std::vector<std::uint8_t> cc(c.vertex_count, 0);
    std::copy(r.corner_.back().begin(), r.corner_.back().end(), cc.begin());
    std::vector<std::uint32_t> next_creases;
    std::vector<std::array<std::uint32_t, 2>> pairs;
    next_creases.reserve(2 * level_creases.size());
    pairs.reserve(2 * level_creases.size());
    for (std::uint32_t e : level_creases) {
      next_creases.push_back(2 * e);
      next_creases.push_back(2 * e + 1);
      pairs.push_back({p.edge_verts[e][0], p.vertex_count + e});
      pairs.push_back({p.vertex_count + e, p.edge_verts[e][1]});
    }
    level_creases = std::move(next_creases);
    r.levels_.push_back(std::move(c));
    r.sharp_.push_back(std::move(cs));
    r.corner_.push_back(std::move(cc));
    r.creases_.push_back(std::move(pairs));
    r.rules_.emplace_back();
    r.crease_nb_.emplace_back();
  }
  return r;
}

std::vector<std::array<std::uint32_t, 2>> CatmullClarkRefiner::last_level_creases() const {
  return creases_.back();
}

Status CatmullClarkRefiner::refine_level(int l, std::span<const Vec3d> in, std::span<Vec3d> out,
                                         const ExecContext& ctx) const {
  if (l < 0 || l >= levels())
    return Status(ErrorCode::kInvalidArgument, "Catmull-Clark: no level " + std::to_string(l + 1));
  const auto li = static_cast<std::size_t>(l);
  const CornerMesh& p = levels_[li];
  if (in.size() != p.vertex_count || out.size() != levels_[li + 1].vertex_count)
    return Status(ErrorCode::kMismatch, "Catmull-Clark: level " + std::to_string(l) + " has " +
                                            std::to_string(p.vertex_count) + " vertices, got " +
                                            std::to_string(in.size()) + " positions");
  if (l > 0 || all_quads(p))
    refine_positions<QuadCorners>(p, sharp_[li], rules_[li], crease_nb_[li], in.data(), out.data(), ctx);
  else
    refine_positions<AnyCorners>(p, sharp_[li], rules_[li], crease_nb_[li], in.data(), out.data(), ctx);
  return {};
}

std::size_t CatmullClarkRefiner::total_vertex_count() const noexcept {
  std::size_t n = 0;
  for (const CornerMesh& m : levels_) n += m.vertex_count;
  return n;
}

Status CatmullClarkRefiner::refine_all(std::span<Vec3d> all, const ExecContext& ctx) const {
  if (all.size() != total_vertex_count())
    return Status(ErrorCode::kMismatch, "Catmull-Clark: a buffer of " + std::to_string(all.size()) + " positions for " +
                                            std::to_string(total_vertex_count()) + " vertices");
  for (std::size_t v = 0; v < levels_[0].vertex_count; ++v)
    if (!all[v].allFinite())
      return Status(ErrorCode::kInvalidArgument,
                    "Catmull-Clark: control vertex " + std::to_string(v) + " is not finite");
  std::size_t at = 0;
  for (int l = 0; l < levels(); ++l) {
    if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "Catmull-Clark: cancelled");
    const std::size_t n = levels_[static_cast<std::size_t>(l)].vertex_count;
    const std::size_t m = levels_[static_cast<std::size_t>(l) + 1].vertex_count;
    if (Status s = refine_level(l, all.subspan(at, n), all.subspan(at + n, m), ctx); !s) return s;
    at += n;
  }
  return {};
}

Status CatmullClarkRefiner::refine(std::span<const Vec3d> control, std::vector<Vec3d>& out,
                                   const ExecContext& ctx) const {
  if (control.size() != levels_[0].vertex_count)
    return Status(ErrorCode::kMismatch, "Catmull-Clark: " + std::to_string(control.size()) + " control positions for " +
                                            std::to_string(levels_[0].vertex_count) + " vertices");
  for (std::size_t v = 0; v < control.size(); ++v)
    if (!control[v].allFinite())
      return Status(ErrorCode::kInvalidArgument,
                    "Catmull-Clark: control vertex " + std::to_string(v) + " is not finite");
  if (levels() == 0) {
    out.assign(control.begin(), control.end());
    return {};
  }
  // Intermediate levels in one scratch buffer, the last straight into `out`.
  std::size_t inner = 0;
  for (int l = 1; l < levels(); ++l) inner += levels_[static_cast<std::size_t>(l)].vertex_count;
  std::vector<Vec3d> scratch(inner);
  out.resize(levels_.back().vertex_count);
  std::span<const Vec3d> cur = control;
  std::size_t at = 0;
  for (int l = 0; l < levels(); ++l) {
    if (ctx.cancelled()) return Status(ErrorCode::kCancelled, "Catmull-Clark: cancelled");
    const std::size_t m = levels_[static_cast<std::size_t>(l) + 1].vertex_count;
    const std::span<Vec3d> dst = l + 1 == levels() ? std::span<Vec3d>(out) : std::span<Vec3d>(scratch).subspan(at, m);
    if (Status s = refine_level(l, cur, dst, ctx); !s) return s;
    cur = dst;
    at += l + 1 == levels() ? 0 : m;
  }
  return {};
}

Expected<SubdividedMesh> subdivide_catmull_clark(const PolygonSoupView& control,
                                                 std::span<const std::array<std::uint32_t, 2>> creases,
                                                 std::span<const std::uint32_t> corners, const CatmullClarkOptions& opt,
                                                 const ExecContext& ctx) {
  auto r = CatmullClarkRefiner::create(control, control.positions.size(), creases, corners, opt, ctx);
  if (!r) return r.status();
  SubdividedMesh out;
  if (Status s = r->refine(control.positions, out.mesh.positions, ctx); !s) return s;
  const CornerMesh& last = r->level(r->levels());
  out.mesh.face_offsets = last.face_offsets;
  out.mesh.face_nodes = last.face_verts;
  out.creases = r->last_level_creases();
  const auto c = r->corner_vertices(r->levels());
  out.corners.assign(c.begin(), c.end());
  return out;
}

std::vector<Vec3d> crease_limit_positions(std::span<const Vec3d> positions,
                                          std::span<const std::array<std::uint32_t, 2>> creases,
                                          std::span<const std::uint8_t> corners) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<Vec3d> out(positions.size(), Vec3d(nan, nan, nan));
  std::vector<std::uint32_t> count(positions.size(), 0);
  std::vector<Vec3d> sum(positions.size(), Vec3d::Zero());
  for (const auto& ab : creases) {
    ++count[ab[0]];
    ++count[ab[1]];
    sum[ab[0]] += positions[ab[1]];
    sum[ab[1]] += positions[ab[0]];
  }
  for (std::size_t v = 0; v < positions.size(); ++v) {
    if (count[v] == 0) continue;
    if ((v < corners.size() && corners[v]) || count[v] > 2)
      out[v] = positions[v];
    else if (count[v] == 2)
      out[v] = (sum[v] + 4.0 * positions[v]) / 6.0;
  }
  return out;
}

}  // namespace atelier
